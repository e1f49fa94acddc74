# phi against interpenetration: the exact packings inflated by S (lines), the contact models
# (points) and the published point, for the 188-grain piles (inflation.csv, variants.csv) and the
# 6 x 6 x 10 ones (about 530 grains) (inflation600.csv, variants600.csv: tables600.py --csv)
# (docs/pinacoids-and-the-paper.md).
set terminal svg size 720,480 font "sans,12"
set output "phi_interpenetration.svg"
set datafile separator ","
set key bottom right
set xlabel "interpenetration, % of the solid volume"
set ylabel "solid fraction phi (bulk)"
set xrange [-0.2:4.6]
set yrange [0.64:0.84]
set grid
plot "inflation.csv" every ::1 using 4:2 with linespoints lw 2 pt 7 title "exact packings inflated by S = 1.00 ... 1.07 (exact overlap)", \
     "inflation.csv" every ::1 using 4:2:(sprintf("%s", stringcolumn(1))) with labels offset 1.8,-0.6 notitle, \
     "variants.csv" every ::1::5 using 3:2 with points pt 5 ps 1.2 title "contact models (exact, loose, velocity law, common plane, both)", \
     "inflation600.csv" every ::1 using 4:2 with linespoints lw 2 dt 2 pt 6 title "the same, 6 x 6 x 10 piles (about 530 grains)", \
     "variants600.csv" every ::1 using 3:2 with points pt 4 ps 1.2 title "contact models, 6 x 6 x 10 piles (about 530 grains)", \
     "-" using 1:2:3 with xerrorbars pt 9 ps 1.8 lc rgb "black" title "published (biperiodic, lattice bounds)"
3.6,0.772,0.1
e
