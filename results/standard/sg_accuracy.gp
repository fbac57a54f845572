set terminal svg size 900,560 dynamic noenhanced
set output 'sg_accuracy.svg'
set title 'Seed 004 under an SG light of sharpness 200: energy error (SG warp solid, ASG warp dashed)'
set xlabel 'view angle from the normal (degrees)'
set ylabel 'sum(approx) / sum(exact) - 1 (%)'
set xzeroaxis lt 1 lc rgb '#999999'
set key outside right top font ',9'
set grid
plot 'sg_accuracy.dat' index 0 using 1:2 with linespoints pt 7 lw 1.5 lc rgb '#1f77b4' dt 1 title 'SG warp, alpha 0.05', \
     'sg_accuracy.dat' index 0 using 1:3 with linespoints pt 6 lw 1.5 lc rgb '#1f77b4' dt 2 title 'ASG warp, alpha 0.05', \
     'sg_accuracy.dat' index 1 using 1:2 with linespoints pt 7 lw 1.5 lc rgb '#ff7f0e' dt 1 title 'SG warp, alpha 0.1', \
     'sg_accuracy.dat' index 1 using 1:3 with linespoints pt 6 lw 1.5 lc rgb '#ff7f0e' dt 2 title 'ASG warp, alpha 0.1', \
     'sg_accuracy.dat' index 2 using 1:2 with linespoints pt 7 lw 1.5 lc rgb '#2ca02c' dt 1 title 'SG warp, alpha 0.2', \
     'sg_accuracy.dat' index 2 using 1:3 with linespoints pt 6 lw 1.5 lc rgb '#2ca02c' dt 2 title 'ASG warp, alpha 0.2', \
     'sg_accuracy.dat' index 3 using 1:2 with linespoints pt 7 lw 1.5 lc rgb '#d62728' dt 1 title 'SG warp, alpha 0.4', \
     'sg_accuracy.dat' index 3 using 1:3 with linespoints pt 6 lw 1.5 lc rgb '#d62728' dt 2 title 'ASG warp, alpha 0.4', \
     'sg_accuracy.dat' index 4 using 1:2 with linespoints pt 7 lw 1.5 lc rgb '#9467bd' dt 1 title 'SG warp, alpha 0.8', \
     'sg_accuracy.dat' index 4 using 1:3 with linespoints pt 6 lw 1.5 lc rgb '#9467bd' dt 2 title 'ASG warp, alpha 0.8'
