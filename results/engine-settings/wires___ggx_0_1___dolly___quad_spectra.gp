set terminal svg size 900,560 dynamic noenhanced
set output 'wires___ggx_0_1___dolly___quad_spectra.svg'
set title 'wires / ggx:0.1 / dolly / quad: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'wires___ggx_0_1___dolly___quad_spectra.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 1 title 'filament', \
     'wires___ggx_0_1___dolly___quad_spectra.dat' index 1 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 1 title 'godot', \
     'wires___ggx_0_1___dolly___quad_spectra.dat' index 2 using 1:2 with lines lw 1.5 lc rgb '#2ca02c' dt 1 title 'none', \
     'wires___ggx_0_1___dolly___quad_spectra.dat' index 3 using 1:2 with lines lw 1.5 lc rgb '#d62728' dt 1 title 'unity-hdrp', \
     'wires___ggx_0_1___dolly___quad_spectra.dat' index 4 using 1:2 with lines lw 1.5 lc rgb '#9467bd' dt 1 title 'vlachos15'
