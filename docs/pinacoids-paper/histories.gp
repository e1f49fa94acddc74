# phi(t) and interpenetration(t) of one pile (seed 1) under each contact model at dt = 1e-3 and a
# loose Gauss-Seidel tolerance. Data: histories.csv (each run's result.json, timing.history).
set terminal svg size 720,720 font "sans,12"
set output "histories.svg"
set datafile separator ","
set multiplot layout 2,1
set grid
set key bottom right
set xlabel "t [t0]"
set ylabel "solid fraction phi (bulk)"
set yrange [0.55:0.70]
models = "exact velocity_law common_plane both"
name(i) = system(sprintf("echo '%s' | cut -d' ' -f%d | tr _ ' '", models, i))
plot for [i=1:4] "histories.csv" every ::1 using 2:(stringcolumn(1) eq name(i) ? $3 : NaN) with lines lw 2 title name(i)
set ylabel "interpenetration, exact [% of the solid volume]"
set logscale y
set yrange [1e-12:1e-2]
set key top left
plot for [i=1:4] "histories.csv" every ::1 using 2:(stringcolumn(1) eq name(i) && $4 > 0 ? $4 : NaN) with lines lw 2 title name(i)
unset multiplot
