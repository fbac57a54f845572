set terminal svg size 900,560 dynamic noenhanced
set output 'sphere_field___ggx_0_02___orbit___quad_spectra.svg'
set title 'sphere-field / ggx:0.02 / orbit / quad: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'sphere_field___ggx_0_02___orbit___quad_spectra.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 1 title 'engine-tk19 (external)', \
     'sphere_field___ggx_0_02___orbit___quad_spectra.dat' index 1 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 1 title 'k16-beckmann-rect fp_max=0.25', \
     'sphere_field___ggx_0_02___orbit___quad_spectra.dat' index 2 using 1:2 with lines lw 1.5 lc rgb '#2ca02c' dt 1 title 'none', \
     'sphere_field___ggx_0_02___orbit___quad_spectra.dat' index 3 using 1:2 with lines lw 1.5 lc rgb '#d62728' dt 1 title 'tk19'
