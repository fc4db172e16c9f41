set terminal pngcairo size 960,640 noenhanced font ",11"
set output "docs/results/scaling.png"
set title "pmstream build on the procedural terrain"
set xlabel "faces"
set ylabel "seconds"
set grid
set key top left
set logscale x
set format x "%.0s%c"
set logscale y
set y2label "peak RSS (MB)"
set ytics nomirror
set y2tics
set logscale y2
$s0 << EOD
99904 0.353182369
500000 1.49725927
2000000 6.50162445
8000000 25.5983142
EOD
$s1 << EOD
99904 32.6132812
500000 114.890625
2000000 413.691406
8000000 1540.49219
EOD
plot $s0 using 1:2 with linespoints pointtype 7 title "seconds (wall)" axes x1y1, \
     $s1 using 1:2 with linespoints pointtype 7 title "peak RSS MB" axes x1y2
