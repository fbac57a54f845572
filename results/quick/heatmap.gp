set terminal svg size 412,570 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-2.10533:2.10533]
set cblabel 'log10 ratio to none'
set xrange [-0.5:3.5]
set yrange [15.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('sphere-field / ggx:0.02 / orbit / quad' 0, 'sphere-field / ggx:0.1 / orbit / quad' 1, 'wires / ggx:0.02 / orbit / quad' 2, 'wires / ggx:0.1 / orbit / quad' 3)
set ytics font ',9' ('tk21' 0, 'k16-beckmann-rect fp_max=1' 1, 'godot' 2, 'k16-ggx-proxy' 3, 'k16-ggx-rect-jacobian' 4, 'vlachos15' 5, 'unity-hdrp' 6, 'toksvig-quad' 7, 'filament' 8, 'tk19' 9, 'k16-beckmann-rect fp_max=0.25' 10, 'k16-ggx-rect' 11, 'k16-ggx-rect-stable' 12, 'k16-beckmann-parallelogram' 13, 'supersample-2' 14, 'none' 15)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
