set terminal svg size 900,560 dynamic noenhanced
set output 'bumpy_plane___ggx_0_5___orbit___quad_pareto_tv_err.svg'
set title 'bumpy-plane / ggx:0.5 / orbit / quad: speed against tv_err'
set xlabel 'benchmark GPU ms per frame'
set ylabel 'tv_err'
set logscale y
set key outside right top font ',9'
plot 'bumpy_plane___ggx_0_5___orbit___quad_pareto.dat' index 0 using 1:2 with points pt 7 lc rgb '#1f77b4' title 'variants', \
     'bumpy_plane___ggx_0_5___orbit___quad_front_tv_err.dat' using 1:2 with points pt 6 ps 2 lc rgb '#d62728' title 'Pareto front', \
     'bumpy_plane___ggx_0_5___orbit___quad_front_tv_err.dat' using 1:2:3 with labels offset 1.2,0.8 font ',9' notitle, \
     'bumpy_plane___ggx_0_5___orbit___quad_pareto.dat' index 1 using 1:2 with linespoints dt 2 lc rgb '#555555' title 'supersample-N (brute force)', \
     keyentry with points pt 6 lc rgb '#d62728' title '1: supersample-1', \
     keyentry with points pt 6 lc rgb '#d62728' title '2: k16-beckmann-rect fp_max=1', \
     keyentry with points pt 6 lc rgb '#d62728' title '3: k16-beckmann-rect fp_max=0.25', \
     keyentry with points pt 6 lc rgb '#d62728' title '4: tk19-forward-rect', \
     keyentry with points pt 6 lc rgb '#d62728' title '5: godot', \
     keyentry with points pt 6 lc rgb '#d62728' title '6: supersample-2', \
     keyentry with points pt 6 lc rgb '#d62728' title '7: supersample-3', \
     keyentry with points pt 6 lc rgb '#d62728' title '8: supersample-4'
