#!/usr/bin/env bash
# The middle ear over a population of ligament and joint parameters (issue 20 §3; docs/studies.md,
# docs/middle-ear.md): each of the 37 stiffnesses and dampings of the anterior mallear ligament
# (AML), the posterior incudal ligament (PIL), the incudomallear and incudostapedial joints (IMJ,
# ISJ) and the annular ligament (AL) log-normal about the model's value with a factor of 2 at one
# standard deviation.
#   1. Latin hypercube, N samples (default 10,000): the 5-95 % band of |V_stapes / P_ec| at 300
#      frequencies, plotted beside the reference band (scripts/middle_ear_study.gp);
#   2. Saltelli's design, base M (default 10,000; M·39 evaluations): first-order and total Sobol'
#      indices of the level of |V_stapes / P_ec| at 0.5, 1 and 4 kHz.
#   scripts/middle_ear_study.sh SOLVER OUTDIR [N] [M]
set -euo pipefail
solve=$1
out=$2
n=${3:-10000}
m=${4:-10000}
ref=$(cd "$(dirname "$0")/.." && pwd)/models/middle_ear/reference.csv
mkdir -p "$out"

names=()
for part in aml pil; do for kind in k kr; do for ax in x y z; do names+=("${kind}_${part}_$ax"); done; done; done
for part in imj isj; do for kind in k kr d; do for ax in x y z; do names+=("${kind}_${part}_$ax"); done; done; done
for kind in k kr; do for ax in x y z; do names+=("${kind}_al_$ax"); done; done
names+=(d_al_z)
# Each about its default value (the solver's info), a factor of 2 at one standard deviation.
args=()
for p in "${names[@]}"; do
  v=$("$solve" info | awk -v p="$p" '$1 == p && $2 == "=" { print $3 }')
  [ -n "$v" ] || { echo "middle_ear_study.sh: no parameter $p in the solver's info" >&2; exit 1; }
  args+=(--parameter "$p=lognormal:$v:2")
done

"$solve" frf --input P --output v_stapes --from 100 --to 10000 --points 300 --format csv > "$out/default.csv"
rm -f "$out/bands.csv" "$out/samples.csv" "$out/sobol.csv" "$out/sobol.json"
echo "== Monte Carlo (Latin hypercube), $n samples of ${#names[@]} parameters =="
"$solve" study "${args[@]}" --design latin-hypercube --samples "$n" --seed 2026 --input P --output v_stapes \
  --from 100 --to 10000 --points 300 --at 500,1000,4000 --bands "$out/bands.csv" --write-samples "$out/samples.csv"
echo
echo "== Sobol' indices (Saltelli), base $m ($(( m * (${#names[@]} + 2) )) evaluations) =="
"$solve" study "${args[@]}" --design saltelli --samples "$m" --seed 2026 --input P --output v_stapes --points 0 \
  --at 500,1000,4000 --sobol "$out/sobol.csv" > "$out/sobol_summary.txt"
sed -n 1,4p "$out/sobol_summary.txt"
# The largest first-order indices per frequency, and the sums per ligament or joint.
for q in L_500Hz_dB L_1000Hz_dB L_4000Hz_dB; do
  echo "-- $q: the five largest first-order indices; per ligament/joint the sum of its parameters' --"
  grep "^$q," "$out/sobol.csv" | sort -t, -k3 -g -r | awk "NR <= 5" |
    awk -F, '{ gsub(/"/, "", $2); printf "  %-10s S1 %.3f [%.3f, %.3f]   ST %.3f\n", $2, $3, $4, $5, $6 }'
  grep "^$q," "$out/sobol.csv" | awk -F, '{ gsub(/"/, "", $2); split($2, w, "_"); s[w[2]] += $3; t[w[2]] += $6 }
    END { for (g in s) printf "  %-4s sum S1 %.3f   sum ST %.3f\n", g, s[g], t[g] }' | sort -k4 -g -r
done
for ext in png svg; do
  gnuplot -e "dir='$out'; ref='$ref'; out='$out/middle_ear_study.$ext.tmp'; fmt='$ext'; n='$n'" \
    "$(dirname "$0")/middle_ear_study.gp"
  mv "$out/middle_ear_study.$ext.tmp" "$out/middle_ear_study.$ext"
done
echo "wrote $out/middle_ear_study.png, .svg (bands beside the reference), bands.csv, samples.csv, sobol.csv"
