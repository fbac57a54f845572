set terminal svg size 373,390 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-1.96133:1.96133]
set cblabel 'log10 ratio to none'
set xrange [-0.5:0.5]
set yrange [3.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('sphere-field / ggx:0.02 / orbit / quad' 0)
set ytics font ',9' ('k16-beckmann-rect fp_max=0.25' 0, 'engine-tk19 (external)' 1, 'tk19' 2, 'none' 3)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
