set terminal svg size 900,560 dynamic noenhanced
set output 'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.svg'
set title 'experiments/scenes/cable.json / ggx:0.05 / orbit / quad: flicker spectra of the error'
set xlabel 'Hz'
set ylabel 'PSD'
set logscale y
set key outside right font ',8'
plot 'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 0 using 1:2 with lines lw 1.5 lc rgb '#1f77b4' dt 1 title 'filament', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 1 using 1:2 with lines lw 1.5 lc rgb '#ff7f0e' dt 1 title 'k16-beckmann-parallelogram sigma2=0.25', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 2 using 1:2 with lines lw 1.5 lc rgb '#2ca02c' dt 1 title 'k16-beckmann-parallelogram sigma2=1', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 3 using 1:2 with lines lw 1.5 lc rgb '#d62728' dt 1 title 'k16-beckmann-rect fp_max=1', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 4 using 1:2 with lines lw 1.5 lc rgb '#9467bd' dt 1 title 'k16-ggx-rect-jacobian', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 5 using 1:2 with lines lw 1.5 lc rgb '#8c564b' dt 1 title 'k16-ggx-rect-stable', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 6 using 1:2 with lines lw 1.5 lc rgb '#e377c2' dt 1 title 'none', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 7 using 1:2 with lines lw 1.5 lc rgb '#7f7f7f' dt 1 title 'supersample-2', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 8 using 1:2 with lines lw 1.5 lc rgb '#bcbd22' dt 1 title 'tk19', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 9 using 1:2 with lines lw 1.5 lc rgb '#17becf' dt 1 title 'tk19-forward', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 10 using 1:2 with lines lw 1.5 lc rgb '#aec7e8' dt 1 title 'tk19-forward-rect', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 11 using 1:2 with lines lw 1.5 lc rgb '#ffbb78' dt 1 title 'tk21', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 12 using 1:2 with lines lw 1.5 lc rgb '#98df8a' dt 1 title 'toksvig-quad', \
     'experiments_scenes_cable_json___ggx_0_05___orbit___quad_spectra.dat' index 13 using 1:2 with lines lw 1.5 lc rgb '#ff9896' dt 1 title 'vlachos15'
