set terminal pngcairo size 960,640 noenhanced font ",11"
set output "docs/results/receiver-e6-horse-far.png"
set title "E6 horse, far view: PSNR against bytes received (τ = 0 px, cut at 40 dB)"
set xlabel "bytes received (log)"
set ylabel "PSNR dB"
set grid
set key top left
set logscale x
set format x "%.0s%c"
$s0 << EOD
5416 40
EOD
$s1 << EOD
1445 40
EOD
$s2 << EOD
6030 40
EOD
$s3 << EOD
1445 40
EOD
plot $s0 using 1:2 with linespoints pointtype 7 title "sender-driven" axes x1y1, \
     $s1 using 1:2 with linespoints pointtype 7 title "sender-plain" axes x1y1, \
     $s2 using 1:2 with linespoints pointtype 7 title "receiver-driven" axes x1y1, \
     $s3 using 1:2 with linespoints pointtype 7 title "view-independent" axes x1y1
