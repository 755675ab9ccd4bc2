# The middle ear's response over a population of ligament and joint parameters (issue 20 §3,
# scripts/middle_ear_study.sh): the 5-95 % and 25-75 % bands and the median of |V_stapes / P_ec|
# from `middle_ear-solve study --bands`, the default parameters' curve, beside the reference band
# and the measured points of scripts/middle_ear_bode.gp.
# Usage: gnuplot -e "dir='DIR'; ref='models/middle_ear/reference.csv'; out='FILE.svg|FILE.png'; n='10000'" \
#                scripts/middle_ear_study.gp
# Reads, in DIR: bands.csv (frequency_hz, p5, p25, p50, p75, p95 in (m/s)/Pa; '#' comments) and
# default.csv (the solver's frf CSV: frequency_hz, re, im, ...).

if (!exists("fmt")) fmt = out[strlen(out)-2:]
if (!exists("n")) n = "?"
if (fmt eq "svg") {
  set terminal svg size 1000,620 dynamic enhanced font "Helvetica,13" background rgb "white"
} else {
  set terminal pngcairo size 1000,620 enhanced font "Helvetica,11"
}
set output out
set datafile separator ","
set datafile commentschars "#"
refdata = "< grep -v '^#' ".ref." | tail -n +2"
mag(re, im) = 1e3 * sqrt(re**2 + im**2)

set title "Human middle ear (mbsgen): |V_{stapes} / P_{ec}| over ".n." Latin-hypercube samples\nof the 37 ligament and joint stiffnesses and dampings (log-normal, a factor of 2 at one standard deviation)" font ",12"
set logscale xy
set xrange [100:10000]
set yrange [3e-3:10]
set grid xtics mxtics ytics lc rgb "#dddddd"
set format x "%g"
set format y "10^{%T}"
set xtics (100, 200, 500, 1000, 2000, 5000, 10000)
set xlabel "frequency (Hz)"
set ylabel "|V_{stapes} / P_{ec}|  ((mm/s)/Pa)"
set key at graph 0.995, graph 0.99 right top box opaque font ",9" spacing 1.1 samplen 2.5 width -3
plot \
  refdata using 1:8:9 with filledcurves lc rgb "#bcd4ee" fs solid 0.7 noborder title "reference band (3 lumped models + Aibara/Goode points)", \
  dir."/bands.csv" skip 3 using 1:($2*1e3):($6*1e3) with filledcurves lc rgb "#f4a582" fs transparent solid 0.45 noborder title "model: 5-95 % of the samples", \
  dir."/bands.csv" skip 3 using 1:($3*1e3):($5*1e3) with filledcurves lc rgb "#d6604d" fs transparent solid 0.45 noborder title "model: 25-75 %", \
  dir."/bands.csv" skip 3 using 1:($4*1e3) with lines lw 2 lc rgb "#b2182b" title "model: median", \
  dir."/default.csv" skip 1 using 1:(mag($2,$3)) with lines lw 2 dt 2 lc rgb "#000000" title "model, default parameters", \
  refdata using 1:6 with points pt 7 ps 1.6 lc rgb "#e7298a" title "Aibara et al. 2001: mean peak, 12 temporal bones", \
  refdata using 1:7 with points pt 5 ps 1.3 lc rgb "#66a61e" title "Goode et al. 1994: 104 dB SPL, as velocity (amplitudes)"
set output
