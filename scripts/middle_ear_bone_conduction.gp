# Bone conduction beside air conduction for the middle-ear model (scripts/demo.sh).
# Usage: gnuplot -e "dir='DIR'; ref='models/middle_ear/reference.csv'; out='FILE.png|FILE.svg'" \
#                scripts/middle_ear_bone_conduction.gp
#   (add fmt='png' or fmt='svg' to choose the terminal when out ends otherwise)
# Reads, in DIR, the solver's CSV (`middle_ear-solve frf ... --format csv`: frequency_hz, re, im,
# amplitude, phase_lag_deg, rcond, flag):
#   default.csv              V_stapes / P (air conduction), (m/s)/Pa
#   bc_x.csv, bc_y.csv, bc_z.csv   V_stapes,rel / X_bone for the temporal bone's displacement along
#                            x, y, z ((m/s)/m; divided here by the bone's velocity i*2*pi*f*X_bone)
# and from ref the reference band of the air-conduction plot (columns 1, 8, 9; (mm/s)/Pa).

if (!exists("fmt")) fmt = out[strlen(out)-2:]
if (fmt eq "svg") {
  set terminal svg size 1000,900 dynamic enhanced font "Helvetica,13" background rgb "white"
} else {
  set terminal pngcairo size 1000,900 enhanced font "Helvetica,11"
}
set output out

set datafile separator ","
set datafile commentschars "#"
refdata = "< grep -v '^#' ".ref." | tail -n +2"
mag(re, im) = 1e3 * sqrt(re**2 + im**2)
# |V_rel / V_bone| in dB, V_bone = i 2 pi f X_bone
db(f, re, im) = 20 * log10(sqrt(re**2 + im**2) / (2 * pi * f))

set multiplot layout 2,1 title "Human middle ear (mbsgen, models/middle\\_ear): air and bone conduction" font ",13"

set logscale x
set xrange [100:10000]
set grid xtics mxtics ytics lc rgb "#dddddd"
set format x "%g"
set xtics (100, 200, 500, 1000, 2000, 5000, 10000)
set lmargin 12
set rmargin 3

# --- air conduction ---
set logscale y
set format y "10^{%T}"
set yrange [1e-3:30]
set ylabel "|V_{stapes} / P_{ec}|  ((mm/s)/Pa)"
set xlabel ""
set key at graph 0.995, graph 0.99 right top box opaque font ",9" spacing 1.1 samplen 2.5 width -3
plot \
  refdata using 1:8:9 with filledcurves lc rgb "#bcd4ee" fs solid 0.7 noborder title "air conduction: reference band (3 lumped models + Aibara/Goode points)", \
  dir."/default.csv" skip 1 using 1:(mag($2,$3)) with lines lw 2.5 lc rgb "#000000" title "air conduction: model, stapes velocity per ear-canal pressure"

# --- bone conduction ---
unset logscale y
set format y "%g"
set yrange [-100:10]
set ytics 10
set ylabel "|V_{stapes,rel} / V_{bone}|  (dB)"
set xlabel "frequency (Hz)"
set key at graph 0.995, graph 0.04 right bottom box opaque font ",9" spacing 1.1 samplen 2.5 width -3
plot \
  dir."/bc_z.csv" skip 1 using 1:(db($1,$2,$3)) with lines lw 2.5 lc rgb "#000000" title "bone vibrating along z (lateral-medial, the piston direction)", \
  dir."/bc_y.csv" skip 1 using 1:(db($1,$2,$3)) with lines lw 1.8 dt 2 lc rgb "#d95f02" title "along y (superior)", \
  dir."/bc_x.csv" skip 1 using 1:(db($1,$2,$3)) with lines lw 1.8 dt 4 lc rgb "#7570b3" title "along x (anterior, the ossicles' rotation axis)", \
  0 with lines lw 1 lc rgb "#888888" title "0 dB: the stapes stands still while the cochlea moves"

unset multiplot
set output
