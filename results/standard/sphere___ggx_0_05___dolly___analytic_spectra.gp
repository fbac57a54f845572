set terminal svg size 900,560 dynamic noenhanced
set output 'sphere___ggx_0_05___dolly___analytic_spectra.svg'
set title 'sphere / ggx:0.05 / dolly / analytic: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 1 title 'filament', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 1 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 1 title 'godot', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 2 using 1:2 with lines lw 1.5 lc rgb '#2ca02c' dt 1 title 'k16-beckmann-parallelogram sigma2=0.25', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 3 using 1:2 with lines lw 1.5 lc rgb '#d62728' dt 1 title 'k16-beckmann-parallelogram sigma2=1', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 4 using 1:2 with lines lw 1.5 lc rgb '#9467bd' dt 1 title 'k16-beckmann-rect fp_max=0.25', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 5 using 1:2 with lines lw 1.5 lc rgb '#8c564b' dt 1 title 'k16-beckmann-rect fp_max=1', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 6 using 1:2 with lines lw 1.5 lc rgb '#e377c2' dt 1 title 'k16-ggx-proxy', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 7 using 1:2 with lines lw 1.5 lc rgb '#7f7f7f' dt 1 title 'k16-ggx-rect', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 8 using 1:2 with lines lw 1.5 lc rgb '#bcbd22' dt 1 title 'k16-ggx-rect-jacobian', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 9 using 1:2 with lines lw 1.5 lc rgb '#17becf' dt 1 title 'k16-ggx-rect-stable', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 10 using 1:2 with lines lw 1.5 lc rgb '#aec7e8' dt 1 title 'none', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 11 using 1:2 with lines lw 1.5 lc rgb '#ffbb78' dt 1 title 'supersample-1', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 12 using 1:2 with lines lw 1.5 lc rgb '#98df8a' dt 1 title 'supersample-2', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 13 using 1:2 with lines lw 1.5 lc rgb '#ff9896' dt 1 title 'supersample-3', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 14 using 1:2 with lines lw 1.5 lc rgb '#c5b0d5' dt 1 title 'supersample-4', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 15 using 1:2 with lines lw 1.5 lc rgb '#c49c94' dt 1 title 'tk19', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 16 using 1:2 with lines lw 1.5 lc rgb '#f7b6d2' dt 1 title 'tk19-forward', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 17 using 1:2 with lines lw 1.5 lc rgb '#c7c7c7' dt 1 title 'tk19-forward-rect', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 18 using 1:2 with lines lw 1.5 lc rgb '#dbdb8d' dt 1 title 'tk21', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 19 using 1:2 with lines lw 1.5 lc rgb '#9edae5' dt 1 title 'toksvig-quad', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 20 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 2 title 'unity-hdrp', \
     'sphere___ggx_0_05___dolly___analytic_spectra.dat' index 21 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 2 title 'vlachos15'
