set terminal svg size 438,630 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-2.10533:2.10533]
set cblabel 'log10 ratio to none'
set xrange [-0.5:5.5]
set yrange [19.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('sg-plane / ggx:0.1 / orbit / quad' 0, 'sg-sphere-field / ggx:0.1 / orbit / quad' 1, 'sphere-field / ggx:0.02 / orbit / quad' 2, 'sphere-field / ggx:0.1 / orbit / quad' 3, 'wires / ggx:0.02 / orbit / quad' 4, 'wires / ggx:0.1 / orbit / quad' 5)
set ytics font ',9' ('k16-beckmann-rect fp_max=1' 0, 'godot' 1, 'k16-ggx-proxy' 2, 'k16-ggx-rect-jacobian' 3, 'vlachos15' 4, 'unity-hdrp' 5, 'toksvig-quad' 6, 'filament' 7, 'tk19' 8, 'tk21' 9, 'k16-beckmann-rect fp_max=0.25' 10, 'k16-ggx-rect' 11, 'k16-ggx-rect-stable' 12, 'k16-beckmann-parallelogram' 13, 'supersample-2' 14, 'none' 15, 'asg-warp-k16' 16, 'asg-warp' 17, 'sg-warp-k16' 18, 'sg-warp' 19)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
