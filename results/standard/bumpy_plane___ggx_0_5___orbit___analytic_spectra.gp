set terminal svg size 900,560 dynamic
set output 'bumpy_plane___ggx_0_5___orbit___analytic_spectra.svg'
set title 'bumpy-plane / ggx:0.5 / orbit / analytic: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 0 using 1:2 with lines title 'filament', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 1 using 1:2 with lines title 'godot', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 2 using 1:2 with lines title 'k16-beckmann-parallelogram', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 3 using 1:2 with lines title 'k16-beckmann-rect fp_max=0.25', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 4 using 1:2 with lines title 'k16-beckmann-rect fp_max=1', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 5 using 1:2 with lines title 'k16-ggx-proxy', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 6 using 1:2 with lines title 'k16-ggx-rect', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 7 using 1:2 with lines title 'k16-ggx-rect-stable', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 8 using 1:2 with lines title 'none', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 9 using 1:2 with lines title 'supersample-1', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 10 using 1:2 with lines title 'supersample-2', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 11 using 1:2 with lines title 'supersample-3', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 12 using 1:2 with lines title 'supersample-4', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 13 using 1:2 with lines title 'tk19', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 14 using 1:2 with lines title 'tk21', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 15 using 1:2 with lines title 'toksvig-quad', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 16 using 1:2 with lines title 'unity-hdrp', \
     'bumpy_plane___ggx_0_5___orbit___analytic_spectra.dat' index 17 using 1:2 with lines title 'vlachos15'
