set terminal svg size 438,450 dynamic noenhanced
set output 'heatmap.svg'
set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'
set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')
set cbrange [-2.18283:2.18283]
set cblabel 'log10 ratio to none'
set xrange [-0.5:5.5]
set yrange [7.5:-0.5]
set tics scale 0
set xtics rotate by 60 right font ',8' ('glint-plane / glints:0.3,local=0.03,density=1e4 / dolly / quad' 0, 'glint-plane / glints:0.3,local=0.03,density=1e4 / orbit / quad' 1, 'glint-plane / glints:0.3,local=0.03,density=1e4 / vr-jitter / quad' 2, 'glint-sphere / glints:0.2,local=0.02,density=1e5 / dolly / quad' 3, 'glint-sphere / glints:0.2,local=0.02,density=1e5 / orbit / quad' 4, 'glint-sphere / glints:0.2,local=0.02,density=1e5 / vr-jitter / quad' 5)
set ytics font ',9' ('glints-smooth' 0, 'glints-zk16' 1, 'glints-zk16-counting' 2, 'glints-db23' 3, 'glints-points' 4, 'supersample-2' 5, 'none' 6, 'glints-naive' 7)
set bmargin 16
set lmargin 28
unset key
plot 'heatmap.dat' using 1:2:3 with image pixels, \
     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'
