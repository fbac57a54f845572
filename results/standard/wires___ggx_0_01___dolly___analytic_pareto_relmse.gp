set terminal svg size 900,560 dynamic noenhanced
set output 'wires___ggx_0_01___dolly___analytic_pareto_relmse.svg'
set title 'wires / ggx:0.01 / dolly / analytic: speed against relmse'
set xlabel 'GPU ms per frame'
set ylabel 'relmse'
set logscale y
set key top right
plot 'wires___ggx_0_01___dolly___analytic_pareto.dat' index 0 using 1:3 with points pt 7 title 'variants', \
     '' index 0 using ($5 > 0 ? $1 : 1/0):3 with points pt 6 ps 2 title 'Pareto front', \
     '' index 0 using ($5 > 0 ? $1 : 1/0):3:6 with labels offset 0.8,0.6 left font ',8' notitle, \
     '' index 1 using 1:3 with linespoints dt 2 title 'supersample-N (equal-time baseline)'
