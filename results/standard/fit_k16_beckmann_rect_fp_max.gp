set terminal svg size 900,560 dynamic noenhanced
set output 'fit_k16_beckmann_rect_fp_max.svg'
set title 'k16-beckmann-rect: training objective J(fp_max)'
set xlabel 'fp_max'
set ylabel 'J'
set logscale x
set key outside right font ',9'
plot 'fit_k16_beckmann_rect_fp_max.dat' index 0 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.01', \
     '' index 1 using 1:2 with points pt 6 ps 2 lc 'black' title 'optimum', \
     'fit_k16_beckmann_rect_fp_max.dat' index 2 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.05', \
     '' index 3 using 1:2 with points pt 6 ps 2 lc 'black' notitle, \
     'fit_k16_beckmann_rect_fp_max.dat' index 4 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.2', \
     '' index 5 using 1:2 with points pt 6 ps 2 lc 'black' notitle, \
     'fit_k16_beckmann_rect_fp_max.dat' index 6 using 1:2 with linespoints pt 7 ps 0.5 title 'ggx:0.5', \
     '' index 7 using 1:2 with points pt 6 ps 2 lc 'black' notitle
