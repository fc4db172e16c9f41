set terminal pngcairo size 960,640 noenhanced font ",11"
set output "docs/results/receiver-e6-dragon-far.png"
set title "E6 dragon, far view: PSNR against bytes received (τ = 0 px, cut at 40 dB)"
set xlabel "bytes received (log)"
set ylabel "PSNR dB"
set grid
set key top left
set logscale x
set format x "%.0s%c"
$s0 << EOD
11895 33.7550376
31889 40
EOD
$s1 << EOD
8185 33.7550376
21336 40
EOD
$s2 << EOD
12513 33.7550376
14739 37.1949957
17174 37.7241707
19426 37.9135929
22313 40
EOD
$s3 << EOD
8185 33.7550376
23691 40
EOD
plot $s0 using 1:2 with linespoints pointtype 7 title "sender-driven" axes x1y1, \
     $s1 using 1:2 with linespoints pointtype 7 title "sender-plain" axes x1y1, \
     $s2 using 1:2 with linespoints pointtype 7 title "receiver-driven" axes x1y1, \
     $s3 using 1:2 with linespoints pointtype 7 title "view-independent" axes x1y1
