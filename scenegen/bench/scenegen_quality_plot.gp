# Plot of scenegen_quality_study's CSV: photo render time against PSNR to the converged
# reference; the final preset of 180441f circled red, that of 9b9e633 orange, that of 4731a3c
# purple, the new final preset circled green, the final preset before its area lights were
# jittered (4939aeb) grey, the best preset (3 x 3 jittered area lights) black.
#   gnuplot -e "csv='docs/data/scenegen_quality.csv'; out='docs/images/scenegen_quality.png'" scenegen/bench/scenegen_quality_plot.gp
set datafile separator ","
set terminal pngcairo size 900,600
set output out
set xlabel "photo render time [s] (single-threaded POV-Ray, wall, summed over row bands)"
set ylabel "PSNR to the converged reference [dB]"
set grid
set key off
set xrange [0:60]
plot csv every ::1 using 2:($3 < 1000 ? $3 : 1/0) with points pt 7 ps 1.5 lc rgb "#1f77b4", \
     csv every ::1 using 2:($3 < 1000 ? $3 : 1/0):1 with labels offset 0,1 font ",9", \
     csv every ::1 using 2:(strcol(1) eq "final (180441f)" ? $3 : 1/0) with points pt 6 ps 3 lw 2 lc rgb "red", \
     csv every ::1 using 2:(strcol(1) eq "final (9b9e633)" ? $3 : 1/0) with points pt 6 ps 3 lw 2 lc rgb "orange", \
     csv every ::1 using 2:(strcol(1) eq "final (4731a3c)" ? $3 : 1/0) with points pt 6 ps 3 lw 2 lc rgb "#9467bd", \
     csv every ::1 using 2:(strcol(1) eq "final (new)" ? $3 : 1/0) with points pt 6 ps 3 lw 2 lc rgb "#2ca02c", \
     csv every ::1 using 2:(strcol(1) eq "final (4939aeb)" ? $3 : 1/0) with points pt 6 ps 3 lw 2 lc rgb "gray50", \
     csv every ::1 using 2:(strcol(1) eq "best" ? $3 : 1/0) with points pt 6 ps 3 lw 2 lc rgb "black"
