set terminal pngcairo size 960,640 noenhanced font ",11"
set output "docs/results/receiver-e6-horse-mid.png"
set title "E6 horse, mid view: PSNR against bytes received (τ = 0 px, cut at 40 dB)"
set xlabel "bytes received (log)"
set ylabel "PSNR dB"
set grid
set key top left
set logscale x
set format x "%.0s%c"
$s0 << EOD
5416 22.5350615
26019 34.203613
45296 38.3306486
63607 39.1747007
80169 39.8860786
94394 39.9747107
107130 40
EOD
$s1 << EOD
1445 22.5350615
16982 34.203613
33183 38.3306486
49725 39.1747007
66566 39.8860786
83688 39.9747107
101034 40
EOD
$s2 << EOD
6030 22.5350615
8310 27.8586924
10418 30.6151904
12206 31.9620448
14253 34.2321748
17152 36.135137
19926 37.2428253
22603 37.7884407
26080 38.898633
29719 39.9271623
34337 40
EOD
$s3 << EOD
1445 22.5350615
18573 34.2930299
35917 37.6040854
53390 39.5183233
70910 40
EOD
plot $s0 using 1:2 with linespoints pointtype 7 title "sender-driven" axes x1y1, \
     $s1 using 1:2 with linespoints pointtype 7 title "sender-plain" axes x1y1, \
     $s2 using 1:2 with linespoints pointtype 7 title "receiver-driven" axes x1y1, \
     $s3 using 1:2 with linespoints pointtype 7 title "view-independent" axes x1y1
