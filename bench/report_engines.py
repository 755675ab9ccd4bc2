"""The section of docs/accuracy-vs-time.md on the per-call speed of our kernels against MuJoCo and
Orocos KDL (issue 17 §2), from the results of bench/engines.sh: engines.csv, engines_agreement.csv
and system.txt in RESULTS_DIR. Only the standard library is used.

    from report_engines import engines_section
    markdown = engines_section(RESULTS_DIR)

Run alone (`python3 bench/report_engines.py RESULTS_DIR`), it prints the section.
"""
import csv
import math
import os
import sys

GOAL_RATIO = 3.0   # issue 17 §2: ours at least 3× faster than the fastest engine for N ≤ 12 ...
GOAL_N = 12        # ... and never slower up to N = 30
QUANTITIES = ("M", "bias", "M+bias")


def _read(results, name):
    path = os.path.join(results, name)
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def _num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def _system(results):
    info = {}
    path = os.path.join(results, "system.txt")
    if os.path.exists(path):
        for line in open(path):
            if ":" in line:
                k, v = line.split(":", 1)
                info[k.strip()] = v.strip()
    return info


def _ns(t):
    if not math.isfinite(t):
        return "–"
    if t < 1e3:
        return "%.3g ns" % t
    if t < 1e6:
        return "%.3g µs" % (t / 1e3)
    return "%.3g ms" % (t / 1e6)


def _ratio(r):
    if not math.isfinite(r):
        return "–"
    return "%.2g×" % r if r < 10 else "%.0f×" % r


def _label(model, n):
    return "spatial chain N = %s" % n if model == "spatial_chain" else {"puma560": "PUMA 560"}.get(model, model)


def engines_section(results):
    """The markdown of the section (a `###` heading and what follows), or a note when the
    benchmark did not run."""
    rows = _read(results, "engines.csv")
    lines = ["### Kernels against numeric engines (MuJoCo, Orocos KDL)", ""]
    if not rows:
        lines += ["Not run: `bench/engines.sh` found no results (MuJoCo or KDL missing, or the engines disagreed: "
                  "see engines.log).", ""]
        return "\n".join(lines)
    system = _system(results)
    agree = {}
    for r in _read(results, "engines_agreement.csv"):
        key = (r["model"], r["N"], r["quantity"])
        agree[key] = max(agree.get(key, 0.0), _num(r["max_rel_diff"]))
    t = {(r["model"], r["N"], r["engine"], r["quantity"]): r for r in rows}
    models = []
    for r in rows:
        key = (r["model"], r["N"], r["coords"])
        if key not in models:
            models.append(key)

    lines += [
        "Our generated `mass_matrix` and `residual` kernels against MuJoCo %s and Orocos KDL %s (Debian "
        "packages, as installed), same process, same states, on the spatial chains of §4 (universal joints: two "
        "coordinates per link, full inertia tensors; springs and dampers set to zero) and on the PUMA 560 "
        "(`models/robots/puma560.yaml`: Armstrong, Khatib & Burdick 1986). Per call, from the state (q, q̇) to "
        "the result: **M**, ours `mass_matrix`, MuJoCo `mj_kinematics` + `mj_comPos` + `mj_crb` + `mj_fullM`, "
        "KDL `ChainDynParam::JntToMass`; **bias** k − q = c(q, q̇) + g(q), ours `residual`, MuJoCo "
        "`mj_kinematics` + `mj_comPos` + `mj_comVel` + `mj_rne` (`qfrc_bias`), KDL `JntToCoriolis` + "
        "`JntToGravity` or one `ChainIdSolver_RNE` pass with q̈ = 0 (the faster is shown, *RNE* when it is "
        "that one); **M+bias** both, ours one call of `dynamics` (M and k − q in one kernel sharing their "
        "sines, cosines and transforms: `mbsgen generate --dynamics`), MuJoCo sharing its position stages, KDL "
        "both calls. Medians of %s interleaved repetitions "
        "(batches of about 2 ms cycling through 16 random states, in thread CPU time so that other jobs on the "
        "shared machine count little; `bench/engines_bench.cpp`), then the median over %s processes: one "
        "process of the same binary runs the 12-link kernels about 10 %% faster or slower than the next, "
        "whatever it does, as memory placement falls (`bench/engines_merge.py`). Before timing, the three must agree to 1e-12 "
        "(largest difference over largest entry, over the states; *agreement* is the worst pair). "
        "*ratio* = fastest engine / ours: above 1 we are faster; *of minima* = the same from each one's "
        "fastest batch (over all processes), which other tenants of the host slow least (in this session's "
        "runs they slowed MuJoCo's 12-link M by up to 50 %%, ours by up to 15 %%). The goal is called met only "
        "where both ratios meet it."
        % (system.get("mujoco", "?"), system.get("orocos_kdl", "?"), rows[0].get("repetitions", "?"),
           rows[0].get("processes", "1")),
        "",
        "| model | coords | quantity | ours | ops (ours) | MuJoCo | KDL | ratio | of minima | agreement |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    verdict = []
    for model, n, coords in models:
        for q in QUANTITIES:
            ours = t.get((model, n, "ours", q))
            if not ours:
                continue
            mj = _num(t[(model, n, "mujoco", q)]["median_ns"]) if (model, n, "mujoco", q) in t else math.nan
            kdl = _num(t[(model, n, "kdl", q)]["median_ns"]) if (model, n, "kdl", q) in t else math.nan
            rne = _num(t[(model, n, "kdl_rne", q)]["median_ns"]) if (model, n, "kdl_rne", q) in t else math.nan
            kdl_best, kdl_text = kdl, _ns(kdl)
            if math.isfinite(rne) and not rne >= kdl:
                kdl_best, kdl_text = rne, _ns(rne) + " *RNE*"
            fastest = min(x for x in (mj, kdl_best) if math.isfinite(x)) if math.isfinite(mj) or math.isfinite(kdl_best) else math.nan
            o = _num(ours["median_ns"])
            ratio = fastest / o if o > 0 else math.nan
            minima = [_num(t[(model, n, e, q)]["min_ns"]) for e in ("mujoco", "kdl", "kdl_rne") if (model, n, e, q) in t]
            minima = [x for x in minima if math.isfinite(x)]
            o_min = _num(ours.get("min_ns"))
            ratio_min = min(minima) / o_min if minima and o_min > 0 else math.nan
            if q == "M+bias":  # the pairs of M and of bias, and our dynamics kernel's against the engines
                a = max(agree.get((model, n, "M"), math.nan), agree.get((model, n, "bias"), math.nan),
                        agree.get((model, n, "M+bias"), 0.0))
            else:
                a = agree.get((model, n, q), math.nan)
            lines.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |"
                         % (_label(model, n), coords, q, _ns(o), ours.get("ops") or "–", _ns(mj), kdl_text,
                            _ratio(ratio), _ratio(ratio_min), "%.1e" % a if math.isfinite(a) else "–"))
            if model == "spatial_chain" and math.isfinite(ratio):
                need = GOAL_RATIO if int(n) <= GOAL_N else 1.0
                worse = min(ratio, ratio_min) if math.isfinite(ratio_min) else ratio
                if worse < need:
                    verdict.append("N = %s %s: %s (goal ≥ %s)" % (n, q, _ratio(worse), _ratio(need)))
    lines.append("")
    if verdict:
        lines.append("**Goal** (ours ≥ 3× faster than the fastest engine for N ≤ 12, never slower up to N = 30) "
                     "**not met** on the chains at: " + "; ".join(verdict) + ".")
    else:
        lines.append("**Goal** (ours ≥ 3× faster than the fastest engine for N ≤ 12, never slower up to N = 30) "
                     "met on every chain and quantity in this run.")
    lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print("usage: report_engines.py RESULTS_DIR", file=sys.stderr)
        sys.exit(2)
    print(engines_section(sys.argv[1]))
