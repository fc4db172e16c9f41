set terminal pngcairo size 960,640 noenhanced font ",11"
set output "docs/results/soak-rss.png"
set title "soak: 10 clients on dragon"
set xlabel "minutes"
set ylabel "server RSS MB"
set grid
set key top left
set y2label "sessions active"
set ytics nomirror
set y2tics
$s0 << EOD
0 175.023438
0.166691583 176.53125
0.333347015 176.53125
0.500047035 176.53125
0.666714288 176.53125
0.833353885 176.53125
1.00001451 176.53125
EOD
$s1 << EOD
0 0
0.166691583 10
0.333347015 10
0.500047035 10
0.666714288 10
0.833353885 10
1.00001451 10
EOD
plot $s0 using 1:2 with linespoints pointtype 7 title "server RSS (MB)" axes x1y1, \
     $s1 using 1:2 with linespoints pointtype 7 title "sessions active" axes x1y2
