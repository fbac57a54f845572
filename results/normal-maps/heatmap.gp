set terminal svg size 412,540 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-1.54342:1.54342]
set cblabel 'log10 ratio to none'
set xrange [-0.5:3.5]
set yrange [13.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('nm-plane / ggx:0.05 / orbit / quad' 0, 'nm-plane@patches / ggx:0.05 / orbit / quad' 1, 'nm-plane@ridges / ggx:0.05 / orbit / quad' 2, 'nm-sphere / ggx:0.05 / orbit / quad' 3)
set ytics font ',9' ('lean' 0, 'k16-ggx-rect-stable+lean' 1, 'clean' 2, 'toksvig' 3, 'vmf' 4, 'toksvig-bp' 5, 'toksvig-map' 6, 'tk19+toksvig' 7, 'unity-hdrp-nm' 8, 'tk19' 9, 'supersample-2' 10, 'nm-mip' 11, 'none' 12, 'nm-point' 13)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
