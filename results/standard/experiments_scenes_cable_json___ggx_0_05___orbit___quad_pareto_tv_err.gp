set terminal svg size 900,560 dynamic noenhanced
set output 'experiments_scenes_cable_json___ggx_0_05___orbit___quad_pareto_tv_err.svg'
set title 'experiments/scenes/cable.json / ggx:0.05 / orbit / quad: speed against tv_err'
set xlabel 'benchmark GPU ms per frame'
set ylabel 'tv_err'
set logscale y
set key outside right top font ',9'
plot 'experiments_scenes_cable_json___ggx_0_05___orbit___quad_pareto.dat' index 0 using 1:2 with points pt 7 lc rgb '#1f77b4' title 'variants', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_front_tv_err.dat' using 1:2 with points pt 6 ps 2 lc rgb '#d62728' title 'Pareto front', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_front_tv_err.dat' using 1:2:3 with labels offset 1.2,0.8 font ',9' notitle, \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_pareto.dat' index 1 using 1:2 with linespoints dt 2 lc rgb '#555555' title 'supersample-N (brute force)', \
     keyentry with points pt 6 lc rgb '#d62728' title '1: none', \
     keyentry with points pt 6 lc rgb '#d62728' title '2: k16-beckmann-rect fp_max=1', \
     keyentry with points pt 6 lc rgb '#d62728' title '3: tk19-forward-rect', \
     keyentry with points pt 6 lc rgb '#d62728' title '4: supersample-2'
