set terminal svg size 900,560 dynamic
set output 'wires___ggx_0_2___dolly___analytic_spectra.svg'
set title 'wires / ggx:0.2 / dolly / analytic: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'wires___ggx_0_2___dolly___analytic_spectra.dat' index 0 using 1:2 with lines title 'filament', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 1 using 1:2 with lines title 'godot', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 2 using 1:2 with lines title 'k16-beckmann-parallelogram', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 3 using 1:2 with lines title 'k16-beckmann-rect fp_max=0.25', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 4 using 1:2 with lines title 'k16-beckmann-rect fp_max=1', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 5 using 1:2 with lines title 'k16-ggx-proxy', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 6 using 1:2 with lines title 'k16-ggx-rect', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 7 using 1:2 with lines title 'k16-ggx-rect-stable', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 8 using 1:2 with lines title 'none', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 9 using 1:2 with lines title 'supersample-1', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 10 using 1:2 with lines title 'supersample-2', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 11 using 1:2 with lines title 'supersample-3', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 12 using 1:2 with lines title 'supersample-4', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 13 using 1:2 with lines title 'tk19', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 14 using 1:2 with lines title 'tk21', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 15 using 1:2 with lines title 'toksvig-quad', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 16 using 1:2 with lines title 'unity-hdrp', \
     'wires___ggx_0_2___dolly___analytic_spectra.dat' index 17 using 1:2 with lines title 'vlachos15'
