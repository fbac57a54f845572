set terminal svg size 900,560 dynamic noenhanced
set output 'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.svg'
set title 'glint-plane / glints:0.3,local=0.03,density=1e4 / dolly / quad: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 1 title 'glints-db23', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 1 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 1 title 'glints-naive', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 2 using 1:2 with lines lw 1.5 lc rgb '#2ca02c' dt 1 title 'glints-points', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 3 using 1:2 with lines lw 1.5 lc rgb '#d62728' dt 1 title 'glints-smooth', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 4 using 1:2 with lines lw 1.5 lc rgb '#9467bd' dt 1 title 'glints-zk16', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 5 using 1:2 with lines lw 1.5 lc rgb '#8c564b' dt 1 title 'glints-zk16-counting', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 6 using 1:2 with lines lw 1.5 lc rgb '#e377c2' dt 1 title 'none', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_spectra.dat' index 7 using 1:2 with lines lw 1.5 lc rgb '#7f7f7f' dt 1 title 'supersample-2'
