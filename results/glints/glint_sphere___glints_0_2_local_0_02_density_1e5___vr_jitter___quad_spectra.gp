set terminal svg size 900,560 dynamic noenhanced
set output 'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.svg'
set title 'glint-sphere / glints:0.2,local=0.02,density=1e5 / vr-jitter / quad: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 1 title 'glints-db23', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 1 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 1 title 'glints-naive', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 2 using 1:2 with lines lw 1.5 lc rgb '#2ca02c' dt 1 title 'glints-points', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 3 using 1:2 with lines lw 1.5 lc rgb '#d62728' dt 1 title 'glints-smooth', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 4 using 1:2 with lines lw 1.5 lc rgb '#9467bd' dt 1 title 'glints-zk16', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 5 using 1:2 with lines lw 1.5 lc rgb '#8c564b' dt 1 title 'glints-zk16-counting', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 6 using 1:2 with lines lw 1.5 lc rgb '#e377c2' dt 1 title 'none', \
     'glint_sphere___glints_0_2_local_0_02_density_1e5___vr_jitter___quad_spectra.dat' index 7 using 1:2 with lines lw 1.5 lc rgb '#7f7f7f' dt 1 title 'supersample-2'
