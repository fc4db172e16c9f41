set terminal pngcairo size 960,640 noenhanced font ",11"
set output "docs/results/receiver-e6-horse-close.png"
set title "E6 horse, close view: PSNR against bytes received (τ = 0 px, cut at 40 dB)"
set xlabel "bytes received (log)"
set ylabel "PSNR dB"
set grid
set key top left
set logscale x
set format x "%.0s%c"
$s0 << EOD
5416 16.2234173
25023 35.5295704
41914 40
EOD
$s1 << EOD
1445 16.2234173
17609 35.5295704
34647 40
EOD
$s2 << EOD
6030 16.2234173
7537 21.2944889
9642 24.0076456
11520 27.7316442
13270 28.2947442
15232 36.6309951
17179 39.7625166
19709 40
EOD
$s3 << EOD
1445 16.2234173
18573 21.9007002
35917 19.6573491
53390 26.3539688
70910 27.9146294
88508 28.0385161
106143 27.7232629
123824 28.9095957
141523 29.0591031
159251 30.2021922
194782 33.8650242
230410 33.9397342
266106 34.3517938
301860 34.7302969
355630 39.9006347
409481 40
EOD
plot $s0 using 1:2 with linespoints pointtype 7 title "sender-driven" axes x1y1, \
     $s1 using 1:2 with linespoints pointtype 7 title "sender-plain" axes x1y1, \
     $s2 using 1:2 with linespoints pointtype 7 title "receiver-driven" axes x1y1, \
     $s3 using 1:2 with linespoints pointtype 7 title "view-independent" axes x1y1
