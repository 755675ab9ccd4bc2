#!/usr/bin/env bash
# Per-call speed on the URDF robots (issue 43): runs a built urdf_engines (bench/urdf_engines.cpp,
# with our kernels compiled in: bench/CMakeLists.txt does that when the generator is built) in
# --time mode over the five robots of models/robots/urdf, K times each (each a new process), and
# prints a markdown table: per robot and quantity (M, bias = c + g, M+bias), the median over the
# processes of each engine's median ns per call, with the spread over the processes (min-max),
# and the ratio of the fastest other engine to ours. KDL is its faster variant per quantity (the
# tree's RNE solver, or ChainDynParam when the robot is a chain; named in the table). It builds
# nothing. urdf_engines checks ours against MuJoCo (1e-10) before timing; a failure stops here.
#
#   bench/urdf_speed.sh URDF_ENGINES [--processes K (3)] [--reps R (21)] [--out DIR]
#
#   --out DIR  keeps each run's CSV and log (DIR/runs/ROBOT.K.csv, .log) and the recorded states
#              (DIR/ROBOT.engines.csv, as urdf_engines writes them); default a temporary directory,
#              removed at the end
# Exit status 1 when a run fails or disagrees.
set -euo pipefail
usage="usage: bench/urdf_speed.sh URDF_ENGINES [--processes K] [--reps R] [--out DIR]"
bin=""
processes=3
reps=21
out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --processes) processes="$2"; shift ;;
    --reps) reps="$2"; shift ;;
    --out) out="$2"; shift ;;
    -*) echo "$usage" >&2; exit 2 ;;
    *) [ -z "$bin" ] || { echo "$usage" >&2; exit 2; }; bin="$1" ;;
  esac
  shift
done
[ -n "$bin" ] || { echo "$usage" >&2; exit 2; }
for v in "$processes" "$reps"; do
  case "$v" in ''|*[!0-9]*|0) echo "urdf_speed: --processes and --reps want positive integers" >&2; exit 2 ;; esac
done
[ -x "$bin" ] || { echo "urdf_speed: $bin is not an executable" >&2; exit 2; }
bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
if [ -n "$out" ]; then
  mkdir -p "$out"
  out=$(cd "$out" && pwd)
  keep=1
else
  out=$(mktemp -d)
  keep=0
fi
cd "$(dirname "$0")/.."
robots=(puma560 ur5 panda biped gripper)
ver() { dpkg-query -W -f='${Version}' "$1" 2>/dev/null || echo "?"; }
rm -rf "$out/runs"
mkdir -p "$out/runs"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
for k in $(seq 1 "$processes"); do
  for r in "${robots[@]}"; do
    echo "[urdf_speed] $r, process $k of $processes" >&2
    if ! "$bin" "$out/$r.engines.csv" "models/robots/urdf/$r.urdf" --time --reps "$reps" \
        >"$out/runs/$r.$k.csv" 2>"$out/runs/$r.$k.log"; then
      tail -5 "$out/runs/$r.$k.log" >&2
      exit 1
    fi
  done
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

python3 - "$out/runs" "$processes" "${robots[@]}" <<'EOF'
import csv, re, statistics, sys
runs, K, robots = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
quantities = ["M", "bias", "M+bias"]
def fmt(x):
    return "-" if x is None else (f"{x:.0f}" if x >= 100 else f"{x:.1f}")
rows, notes, worst = [], [], []
for robot in robots:
    per = {}  # (engine, quantity) -> [median ns of each process]
    agree = {}
    for k in range(1, K + 1):
        with open(f"{runs}/{robot}.{k}.csv") as f:
            for row in csv.DictReader(f):
                per.setdefault((row["engine"], row["quantity"]), []).append(float(row["ns_per_call"]))
                if row["agreement"]:
                    agree[(row["engine"], row["quantity"])] = max(agree.get((row["engine"], row["quantity"]), 0.0),
                                                                   float(row["agreement"]))
        with open(f"{runs}/{robot}.{k}.log") as f:
            log = f.read()
    n = re.search(r", (\d+) joints,", log)
    m = re.search(r"ours take the (\d+) independent coordinates of (\d+)", log)
    size = f"{m.group(1)} of {m.group(2)}" if m else (n.group(1) if n else "?")
    if m:
        notes.append(f"{robot}: ours in the {m.group(1)} independent coordinates (<mimic> a constraint, the loop "
                     f"closed in each call); MuJoCo and KDL on their unconstrained {m.group(2)}-joint tree, "
                     "without projecting onto them; all at states where the mimic holds")
    if ("ours", "M") not in per:
        notes.append(f"{robot}: no kernels of ours in this binary")
    for q in quantities:
        med = {e: statistics.median(v) for (e, qq), v in per.items() if qq == q}
        spread = {e: (min(v), max(v)) for (e, qq), v in per.items() if qq == q}
        kdl = min((e for e in ("kdl", "kdl_chain") if e in med), key=lambda e: med[e], default=None)
        def cell(e):
            if e is None or e not in med:
                return "-"
            lo, hi = spread[e]
            return f"{fmt(med[e])} ({fmt(lo)}-{fmt(hi)})" if K > 1 else fmt(med[e])
        others = [med[e] for e in ("mujoco", kdl) if e in med]
        ratio = min(others) / med["ours"] if "ours" in med and others else None
        if ratio is not None:
            worst.append((ratio, robot, q))
        label = {"kdl": "tree RNE", "kdl_chain": "ChainDynParam"}.get(kdl, "")
        a = agree.get(("ours", q))
        rows.append(f"| {robot} | {size} | {q} | {cell('ours')} | {cell('mujoco')} | {cell(kdl)} {label} | "
                    f"{'-' if ratio is None else f'{ratio:.2f}'} | {'-' if a is None else f'{a:.1e}'} |")
spread_note = f", spread over the {K} processes (min-max)" if K > 1 else ""
print(f"ns per call: median over {K} processes of each process's median{spread_note}\n")
print("| robot | coords | quantity | ours | MuJoCo | KDL (faster variant) | fastest other / ours | ours vs MuJoCo |")
print("|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
if worst:
    r = min(worst)
    print(f"\nsmallest ratio: {r[0]:.2f} ({r[1]}, {r[2]})")
for s in notes:
    print(f"- {s}")
EOF
echo
echo "MuJoCo $(ver libmujoco-dev), Orocos KDL $(ver liborocos-kdl-dev), kdl_parser $(ver libkdl-parser-dev); $processes processes x $reps repetitions; thread CPU time; load average before $load_before, after $load_after"
if [ "$keep" = 0 ]; then rm -rf "$out"; fi
