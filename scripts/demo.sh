#!/usr/bin/env bash
# The human middle-ear model (models/middle_ear, docs/middle-ear.md): installs what is missing,
# builds the model's solver, prints its natural frequencies and damping ratios, computes the
# transfer function H = V_stapes/P_ec from 100 Hz to 10 kHz for the default parameters and two
# clinical variations (stapes fixation, disarticulated incudostapedial joint), and draws a Bode plot
# against the reference band and the measured points of models/middle_ear/reference.csv.
# Writes only into build/: the solver into build/demo-solver, the data and the plot into build/demo.
#
# The solver is built from the middle ear's committed kernels (generated/middle_ear, which the
# test generated_code_is_current keeps equal to what mbsgen generates) by the preset "demo": the
# runtime and the solver's command line only, without the generator, the tests or debug
# information, so that a bare machine answers in minutes (issue 40 §4). `mbsgen run
# models/middle_ear/middle_ear.yaml -- modes` (README) generates the same kernels itself.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh --demo

# Build only what the demo needs. Parallel only while no other build is running.
jobs=2
if pgrep -f "cmake --build" > /dev/null; then jobs=1; fi
cmake --preset demo > /dev/null
build_log=build/demo-solver/demo-build.log
if ! cmake --build --preset demo -j "$jobs" --target middle_ear-solve > "$build_log" 2>&1; then
  cat "$build_log" >&2
  exit 1
fi

solve=build/demo-solver/generated/middle_ear-solve
out=build/demo
mkdir -p "$out"
ref=models/middle_ear/reference.csv

echo "== Middle ear: natural frequencies and damping ratios (default parameters) =="
echo "   (real modes have zeta = 1: overdamped relaxations of the joint spring-dashpots)"
"$solve" modes
"$solve" modes --shapes > "$out/modes_shapes.txt"
"$solve" modes --format csv --shapes > "$out/modes.csv"

# Parameter overrides. Scenes select effects but cannot change parameter values, so the stapes
# fixation is a run-time override: the annular ligament's stiffnesses k_al_* and kr_al_* times 10
# and 100 (their dampings beta*k follow, being expressions of them). The disarticulated
# incudostapedial joint sets k_isj_*, kr_isj_*, d_isj_* to 0; the model file's scene
# isj_disarticulated is the same model with the joint's bushing removed.
default_of() { "$solve" info | awk -v p="$1" '$1 == p && $2 == "=" { print $3 }'; }
fixation=()
for factor in 10 100; do
  sets=()
  for p in k_al_x k_al_y k_al_z kr_al_x kr_al_y kr_al_z; do
    v=$(default_of "$p")
    sets+=(--set "$p=$(awk -v v="$v" -v f="$factor" 'BEGIN { printf "%.17g", v * f }')")
  done
  fixation+=("${sets[*]}")
done
isj=()
for p in k_isj_x k_isj_y k_isj_z kr_isj_x kr_isj_y kr_isj_z d_isj_x d_isj_y d_isj_z; do
  isj+=(--set "$p=0")
done

frf() { "$solve" frf --input P --output v_stapes --from 100 --to 10000 --points 300 --format csv "$@"; }
frf > "$out/default.csv"
# shellcheck disable=SC2086  # the --set options of one variation, split on purpose
frf ${fixation[0]} > "$out/fixation10.csv"
# shellcheck disable=SC2086
frf ${fixation[1]} > "$out/fixation100.csv"
frf "${isj[@]}" > "$out/isj.csv"

# Peak of |H| and |H| at 500 Hz, 1 kHz, 2 kHz per variation, in (mm/s)/Pa.
summary() {
  awk -F, -v name="$1" 'NR > 1 {
      f = $1; a = 1e3 * sqrt($2 * $2 + $3 * $3)
      if (a > peak) { peak = a; fpeak = f }
      for (i = 1; i <= 3; ++i) if (!(i in v) && f >= t[i]) v[i] = a
      next }
    BEGIN { t[1] = 500; t[2] = 1000; t[3] = 2000; peak = -1 }
    END { if (peak <= 0) { printf "  %-34s H = 0 at every frequency\n", name; exit }
          printf "  %-34s peak %9.4g at %6.0f Hz   |H| 500 Hz %9.4g   1 kHz %9.4g   2 kHz %9.4g\n",
                 name, peak, fpeak, v[1], v[2], v[3] }' "$2"
}
echo
echo "== |V_stapes / P_ec| in (mm/s)/Pa, 100 Hz - 10 kHz, 300 log-spaced points =="
summary "default parameters" "$out/default.csv"
summary "stapes fixation x10" "$out/fixation10.csv"
summary "stapes fixation x100" "$out/fixation100.csv"
summary "ISJ disarticulated" "$out/isj.csv"
isj_max=$(awk -F, 'NR > 1 { a = 1e3 * sqrt($2 * $2 + $3 * $3); if (a > m) m = a } END { printf "%g", m + 0 }' "$out/isj.csv")
if [[ "$isj_max" == 0 ]]; then
  isj_note="ISJ disarticulated: H = 0 (stapes not driven), no curve"
else
  isj_note="ISJ disarticulated: max |H| = $isj_max (mm/s)/Pa"
fi

for ext in png svg; do
  gnuplot -e "dir='$out'; ref='$ref'; out='$out/middle_ear_bode.$ext.tmp'; fmt='$ext'; isj_note='$isj_note'" \
    scripts/middle_ear_bode.gp
  mv "$out/middle_ear_bode.$ext.tmp" "$out/middle_ear_bode.$ext"
done

# Bone conduction: the temporal bone vibrates (a motion input); the stapes velocity relative to
# the cochlea (the oval window) per bone displacement, in (m/s)/m.
for axis in x y z; do
  "$solve" frf --input "bone_$axis" --output v_stapes_rel --from 100 --to 10000 --points 300 --format csv \
    > "$out/bc_$axis.csv"
done
echo
echo "== Bone conduction: |V_stapes,rel / V_bone| in dB (the ossicular, inertial pathway) =="
for axis in x y z; do
  awk -F, -v name="bone vibrating along $axis" 'NR > 1 {
      f = $1; d = 20 * log(sqrt($2 * $2 + $3 * $3) / (2 * 3.141592653589793 * f)) / log(10)
      for (i = 1; i <= 4; ++i) if (!(i in v) && f >= t[i]) v[i] = d
      next }
    BEGIN { t[1] = 100; t[2] = 500; t[3] = 1000; t[4] = 4000 }
    END { printf "  %-26s 100 Hz %6.1f   500 Hz %6.1f   1 kHz %6.1f   4 kHz %6.1f\n", name, v[1], v[2], v[3], v[4] }' \
    "$out/bc_$axis.csv"
done
for ext in png svg; do
  gnuplot -e "dir='$out'; ref='$ref'; out='$out/middle_ear_bone_conduction.$ext.tmp'; fmt='$ext'" \
    scripts/middle_ear_bone_conduction.gp
  mv "$out/middle_ear_bone_conduction.$ext.tmp" "$out/middle_ear_bone_conduction.$ext"
done

# A parameter study of the ligaments and joints (docs/studies.md): 10,000 Latin-hypercube
# samples, the 5-95 % band of |H| beside the reference, and Sobol' indices at 0.5, 1 and 4 kHz.
echo
scripts/middle_ear_study.sh "$solve" "$out/study"

echo
echo "Wrote, in $(pwd)/$out:"
echo "  middle_ear_bode.png, middle_ear_bode.svg   Bode plot: model, stapes fixation x10/x100,"
echo "                                             reference band and measured points"
echo "  default.csv, fixation10.csv, fixation100.csv, isj.csv   H (re, im in (m/s)/Pa), solver CSV"
echo "  middle_ear_bone_conduction.png, .svg        bone conduction beside air conduction"
echo "  study/middle_ear_study.png, .svg            the band of a population of ligament parameters"
echo "  bc_x.csv, bc_y.csv, bc_z.csv               V_stapes,rel per bone displacement ((m/s)/m)"
echo "  modes.csv, modes_shapes.txt                 eigenvalues and mode shapes"
