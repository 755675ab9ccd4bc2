# Bode plot of the middle-ear transfer function H = V_stapes / P_ec (scripts/demo.sh).
# Usage: gnuplot -e "dir='DIR'; ref='models/middle_ear/reference.csv'; out='FILE.png|FILE.svg'" \
#                scripts/middle_ear_bode.gp
#   (add fmt='png' or fmt='svg' to choose the terminal when out ends otherwise)
# Reads, in DIR, the solver's CSV (`middle_ear-solve frf ... --format csv`: frequency_hz, re, im,
# amplitude, phase_lag_deg, rcond, flag; H in (m/s)/Pa):
#   default.csv, fixation10.csv, fixation100.csv, isj.csv
# and from ref the reference band and the measured points (f_hz, lumped_min, lumped_max,
# phase_min_deg, phase_max_deg, aibara, goode, band_lo, band_hi; (mm/s)/Pa and degrees).
# isj_note: the legend text for the disarticulated joint (its |H| is zero: no curve on a log axis).

if (!exists("isj_note")) isj_note = "ISJ disarticulated: H = 0 (stapes not driven), not drawn"
if (!exists("fmt")) fmt = out[strlen(out)-2:]
if (fmt eq "svg") {
  set terminal svg size 1000,900 dynamic enhanced font "Helvetica,13" background rgb "white"
} else {
  set terminal pngcairo size 1000,900 enhanced font "Helvetica,11"
}
set output out

set datafile separator ","
set datafile commentschars "#"
# the reference table without its comment and header lines
refdata = "< grep -v '^#' ".ref." | tail -n +2"
# re, im in (m/s)/Pa -> (mm/s)/Pa
mag(re, im) = 1e3 * sqrt(re**2 + im**2)
# the phase of V/P (not a lag), in degrees, unwrapped once below -180 (curves start near +90)
ph(re, im) = (ph_ = atan2(im, re) * 180 / pi, ph_ > 135 ? ph_ - 360 : ph_)
band_title = "reference band: range of 3 lumped models + Aibara/Goode points"
band_title2 = "(lumped: Rosowski 1993, Hudde \\& Engel 1998, 4-DOF fit; not ASTM F2504)"

set multiplot layout 2,1 title "Human middle ear (mbsgen, models/middle\\_ear): stapes velocity per ear-canal pressure" font ",13"

set logscale x
set xrange [100:10000]
set grid xtics mxtics ytics lc rgb "#dddddd"
set format x "%g"
set xtics (100, 200, 500, 1000, 2000, 5000, 10000)

# --- amplitude ---
set lmargin 12
set rmargin 3
set logscale y
set format y "10^{%T}"
set yrange [1e-3:30]   # room above the curves for the legend
set ylabel "|V_{stapes} / P_{ec}|  ((mm/s)/Pa)"
set xlabel ""
set key at graph 0.995, graph 0.99 right top box opaque font ",9" spacing 1.1 samplen 2.5 width -3
plot \
  refdata using 1:8:9 with filledcurves lc rgb "#bcd4ee" fs solid 0.7 noborder title band_title, \
  keyentry with lines lc rgb "white" title band_title2, \
  dir."/default.csv" skip 1 using 1:(mag($2,$3)) with lines lw 2.5 lc rgb "#000000" title "model, default parameters (docs/middle-ear.md)", \
  dir."/fixation10.csv" skip 1 using 1:(mag($2,$3)) with lines lw 1.8 dt 2 lc rgb "#d95f02" title "stapes fixation: annular ligament k, k_{rot} x10", \
  dir."/fixation100.csv" skip 1 using 1:(mag($2,$3)) with lines lw 1.8 dt 4 lc rgb "#7570b3" title "stapes fixation: annular ligament k, k_{rot} x100", \
  keyentry with lines lw 1.8 dt 3 lc rgb "#1b9e77" title isj_note, \
  refdata using 1:6 with points pt 7 ps 1.6 lc rgb "#e7298a" title "Aibara et al. 2001: mean peak, 12 temporal bones", \
  refdata using 1:7 with points pt 5 ps 1.3 lc rgb "#66a61e" title "Goode et al. 1994: 104 dB SPL, as velocity (amplitudes)"

# --- phase ---
unset logscale y
set format y "%g"
set yrange [-200:120]
set ytics 45
set ylabel "phase of V_{stapes} / P_{ec}  (degrees)"
set xlabel "frequency (Hz)"
set key at graph 0.995, graph 0.99 right top box opaque font ",9"
plot \
  refdata using 1:4:5 with filledcurves lc rgb "#bcd4ee" fs solid 0.7 noborder title "phase range of the 3 lumped models", \
  dir."/default.csv" skip 1 using 1:(ph($2,$3)) with lines lw 2.5 lc rgb "#000000" notitle, \
  dir."/fixation10.csv" skip 1 using 1:(ph($2,$3)) with lines lw 1.8 dt 2 lc rgb "#d95f02" notitle, \
  dir."/fixation100.csv" skip 1 using 1:(ph($2,$3)) with lines lw 1.8 dt 4 lc rgb "#7570b3" notitle

unset multiplot
set output
