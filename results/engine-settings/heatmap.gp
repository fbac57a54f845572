set terminal svg size 555,405 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-2.03207:2.03207]
set cblabel 'log10 ratio to none'
set xrange [-0.5:14.5]
set yrange [4.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('bumpy-plane / ggx:0.02 / dolly / quad' 0, 'bumpy-plane / ggx:0.02 / orbit / quad' 1, 'bumpy-plane / ggx:0.1 / dolly / quad' 2, 'bumpy-plane / ggx:0.1 / orbit / quad' 3, 'sphere / ggx:0.02 / dolly / quad' 4, 'sphere / ggx:0.02 / orbit / quad' 5, 'sphere / ggx:0.1 / dolly / quad' 6, 'sphere / ggx:0.1 / orbit / quad' 7, 'sphere-field / ggx:0.02 / dolly / quad' 8, 'sphere-field / ggx:0.02 / orbit / quad' 9, 'sphere-field / ggx:0.1 / dolly / quad' 10, 'sphere-field / ggx:0.1 / orbit / quad' 11, 'wires / ggx:0.02 / dolly / quad' 12, 'wires / ggx:0.1 / dolly / quad' 13, 'wires / ggx:0.1 / orbit / quad' 14)
set ytics font ',9' ('unity-hdrp' 0, 'godot' 1, 'filament' 2, 'none' 3, 'vlachos15' 4)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
