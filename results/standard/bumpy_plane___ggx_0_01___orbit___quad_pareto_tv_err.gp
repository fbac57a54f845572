set terminal svg size 900,560 dynamic noenhanced
set output 'bumpy_plane___ggx_0_01___orbit___quad_pareto_tv_err.svg'
set title 'bumpy-plane / ggx:0.01 / orbit / quad: speed against tv_err'
set xlabel 'GPU ms per frame'
set ylabel 'tv_err'
set logscale y
set key top right
plot 'bumpy_plane___ggx_0_01___orbit___quad_pareto.dat' index 0 using 1:2 with points pt 7 title 'variants', \
     '' index 0 using ($4 > 0 ? $1 : 1/0):2 with points pt 6 ps 2 title 'Pareto front', \
     '' index 0 using ($4 > 0 ? $1 : 1/0):2:6 with labels offset 0.8,0.6 left font ',8' notitle, \
     '' index 1 using 1:2 with linespoints dt 2 title 'supersample-N (equal-time baseline)'
