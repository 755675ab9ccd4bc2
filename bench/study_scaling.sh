#!/usr/bin/env bash
# Parameter studies of the middle ear (issue 20 §4): the whole study (10^5 samples x 300
# frequencies) on the machine's cores, the scaling from 1 to 2 MPI ranks and from 1 to 2 threads
# (medians of 3 runs, the same run), and the cost of an evaluation by part and method
# (bench/study_breakdown.cpp). Not part of the test suite.
#   bench/study_scaling.sh [BUILD_DIR]     (default build/release, with -DMBSGEN_BUILD_BENCH=ON)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
solve=$build/generated/middle_ear-solve
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
params=()
for p in k_aml_x kr_aml_x k_pil_z k_imj_x kr_imj_x d_imj_x k_isj_z d_isj_z k_al_z kr_al_x d_al_z; do
  v=$("$solve" info | awk -v p="$p" '$1 == p && $2 == "=" { print $3 }')
  params+=(--parameter "$p=lognormal:$v:2")
done
study=(study "${params[@]}" --design latin-hypercube --seed 1 --input P --output v_stapes --from 100 --to 10000
       --points 300)
wall() { /usr/bin/time -f %e "$@" 2>&1 >/dev/null | tail -1; }
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

echo "== The whole study: 100000 samples x 300 frequencies, $(nproc) cores, one process =="
"$solve" "${study[@]}" --samples 100000 | sed -n 1,3p

n=20000
echo
echo "== Scaling, $n samples x 300 frequencies (medians of 3 runs, seconds wall) =="
for mode in "threads 1" "threads 2" "ranks 1" "ranks 2"; do
  set -- $mode
  times=()
  for r in 1 2 3; do
    if [ "$1" = threads ]; then
      times+=("$(wall "$solve" "${study[@]}" --samples "$n" --threads "$2")")
    else
      times+=("$(wall mpirun -n "$2" --oversubscribe "$solve" "${study[@]}" --samples "$n" --threads 1)")
    fi
  done
  m=$(median "${times[@]}")
  echo "$1 $2: ${times[*]} -> median $m"
  eval "t_${1}_$2=$m"
done
awk -v a="$t_ranks_1" -v b="$t_ranks_2" 'BEGIN { printf "MPI 1 -> 2 ranks: speed-up %.2f, efficiency %.0f %%\n", a / b, 50 * a / b }'
awk -v a="$t_threads_1" -v b="$t_threads_2" 'BEGIN { printf "threads 1 -> 2: speed-up %.2f, efficiency %.0f %%\n", a / b, 50 * a / b }'

echo
echo "== One evaluation by part and method (medians over 1000 evaluations, one thread) =="
"$build/bench/study_breakdown" 1000
