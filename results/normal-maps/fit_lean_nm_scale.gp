set terminal svg size 900,560 dynamic noenhanced
set output 'fit_lean_nm_scale.svg'
set title 'lean: training objective J(nm_scale)'
set xlabel 'nm_scale'
set ylabel 'J'
set logscale x
set key outside right font ',9'
plot 'fit_lean_nm_scale.dat' index 0 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.05 with bumps', \
     '' index 1 using 1:2 with points pt 6 ps 2 lc 'black' title 'optimum', \
     'fit_lean_nm_scale.dat' index 2 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.05 with bumps-fine', \
     '' index 3 using 1:2 with points pt 6 ps 2 lc 'black' notitle, \
     'fit_lean_nm_scale.dat' index 4 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.05 with ridges', \
     '' index 5 using 1:2 with points pt 6 ps 2 lc 'black' notitle, \
     'fit_lean_nm_scale.dat' index 6 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.05 with patches', \
     '' index 7 using 1:2 with points pt 6 ps 2 lc 'black' notitle
