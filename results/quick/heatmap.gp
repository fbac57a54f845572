set terminal svg size 477,720 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-3:3]
set cblabel 'log10 ratio to none'
set xrange [-0.5:8.5]
set yrange [25.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('nm-magnify / ggx:0.05 / orbit / quad' 0, 'nm-plane / ggx:0.05 / orbit / quad' 1, 'nm-sphere / ggx:0.05 / orbit / quad' 2, 'sg-plane / ggx:0.1 / orbit / quad' 3, 'sg-sphere-field / ggx:0.1 / orbit / quad' 4, 'sphere-field / ggx:0.02 / orbit / quad' 5, 'sphere-field / ggx:0.1 / orbit / quad' 6, 'wires / ggx:0.02 / orbit / quad' 7, 'wires / ggx:0.1 / orbit / quad' 8)
set ytics font ',9' ('k16-beckmann-rect fp_max=1' 0, 'godot' 1, 'k16-ggx-proxy' 2, 'k16-ggx-rect-jacobian' 3, 'vlachos15' 4, 'unity-hdrp' 5, 'toksvig-quad' 6, 'filament' 7, 'tk21' 8, 'lean' 9, 'k16-beckmann-rect fp_max=0.25' 10, 'toksvig' 11, 'vmf' 12, 'toksvig-map' 13, 'tk19+toksvig' 14, 'k16-ggx-rect' 15, 'k16-ggx-rect-stable' 16, 'tk19' 17, 'k16-beckmann-parallelogram' 18, 'supersample-2' 19, 'nm-mip' 20, 'none' 21, 'asg-warp-k16' 22, 'asg-warp' 23, 'sg-warp-k16' 24, 'sg-warp' 25)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
