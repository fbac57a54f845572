set terminal svg size 900,560 dynamic noenhanced
set output 'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_pareto_relmse.svg'
set title 'glint-plane / glints:0.3,local=0.03,density=1e4 / dolly / quad: speed against relmse'
set xlabel 'benchmark GPU ms per frame'
set ylabel 'relmse'
set logscale y
set key outside right top font ',9'
plot 'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_pareto.dat' index 0 using 1:3 with points pt 7 lc rgb '#1f77b4' title 'variants', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_front_relmse.dat' using 1:2 with points pt 6 ps 2 lc rgb '#d62728' title 'Pareto front', \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_front_relmse.dat' using 1:2:3 with labels offset 1.2,0.8 font ',9' notitle, \
     'glint_plane___glints_0_3_local_0_03_density_1e4___dolly___quad_pareto.dat' index 1 using 1:3 with linespoints dt 2 lc rgb '#555555' title 'supersample-N (brute force)', \
     keyentry with points pt 6 lc rgb '#d62728' title '1: glints-smooth', \
     keyentry with points pt 6 lc rgb '#d62728' title '2: supersample-2'
