"""Section "Time simulation" of docs/accuracy-vs-time.md (issue 18 §4), from
RESULTS/simulation_compare.csv (bench/simulation_timing and bench/simulation_compare.py); the
work-precision plots are bench/plot_simulation.py's, in docs/simulation/.

    simulation_section(results, table) -> list of markdown lines (empty without the CSV)

Run alone, `python3 bench/report_simulation.py RESULTS` prints the section.
"""
import csv
import math
import os
import sys

LABELS = {"pendulum": "simple pendulum from 2.5 rad, 10 s",
          "double_pendulum": "double pendulum from 0.5 rad, 100 s",
          "middle_ear": "middle ear, 1 Pa at 1 kHz, 20 ms"}


def _rows(results):
    path = os.path.join(results, "simulation_compare.csv")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [dict(r, rtol=float(r["rtol"]), seconds=float(r["seconds"]), error=float(r["error"] or "nan"))
                for r in csv.DictReader(f)]


def _equal_accuracy(rows, problem):
    """For each SciPy run: our fastest run at least as accurate, and the ratio of the times."""
    ours = [r for r in rows if r["problem"] == problem and r["solver"].startswith("mbsgen")]
    out = []
    for s in rows:
        if s["problem"] != problem or not s["solver"].startswith("SciPy") or not math.isfinite(s["error"]):
            continue
        better = [o for o in ours if math.isfinite(o["error"]) and o["error"] <= s["error"]]
        if better:
            best = min(better, key=lambda o: o["seconds"])
            out.append((s, best, s["seconds"] / best["seconds"]))
        else:
            out.append((s, None, None))
    return out


def _interpolated(rows, problem, scipy_run):
    """Our time at exactly the SciPy run's error: along each of our methods' work-precision curve
    (runs in order of rtol), log-log between two neighbouring runs whose errors bracket it; the
    fastest over the methods and brackets (None where no curve brackets it; the caller takes our
    fastest run at least as accurate where that is faster still). The pairing with that run alone
    overstates our time by up to the grid's half decade of rtol."""
    target = math.log(scipy_run["error"])
    best = None
    for solver in {r["solver"] for r in rows if r["problem"] == problem and r["solver"].startswith("mbsgen")}:
        curve = sorted((r for r in rows if r["problem"] == problem and r["solver"] == solver and
                        math.isfinite(r["error"]) and r["error"] > 0), key=lambda r: -r["rtol"])
        for a, b in zip(curve, curve[1:]):
            ea, eb = math.log(a["error"]), math.log(b["error"])
            if min(ea, eb) <= target <= max(ea, eb):
                w = 0.0 if ea == eb else (target - ea) / (eb - ea)
                t = math.exp((1 - w) * math.log(a["seconds"]) + w * math.log(b["seconds"]))
                best = t if best is None else min(best, t)
    return best


def simulation_section(results, table):
    rows = _rows(results)
    if not rows:
        return []
    out = ["## 6. Time simulation", "",
           "`simulate` (SUNDIALS CVODE's BDF and Adams, and our Radau IIA of orders 5 and 9, `radau` and `radau9`; "
           "docs/simulation.md) against SciPy's "
           "`solve_ivp` (Radau and LSODA, "
           "Debian python3-scipy) on the same problems, in the same run. SciPy's right-hand side and Jacobian "
           "call the same generated kernels (a shared library through ctypes; M ÿ = −(k − q) by "
           "`numpy.linalg.solve`), so the difference is the integrators and the language around them. Error: "
           "the largest difference of a coordinate from a reference run (our Radau at rtol 1e-13; the middle "
           "ear's 1e-11: at ten times the tolerance it is 1e-11, 2.7e-10 and 3e-12 off itself), relative "
           "to the largest coordinate, over all samples; atol = rtol (the middle ear: "
           "rtol × 1e-9 m). Times are medians (ours of 5 runs, SciPy's of 3). `bench/simulation_timing`, "
           "`bench/simulation_compare.py`. Each SciPy run is paired with our fastest run at least as accurate "
           "(ours every half decade of rtol, so that run may be up to a half decade more accurate than "
           "needed); the last column is our time at exactly the SciPy run's error instead, interpolated "
           "log–log between two neighbouring runs of one of our methods whose errors bracket it (or that "
           "fastest run, where it is faster still).", ""]
    for problem in [p for p in LABELS if any(r["problem"] == p for r in rows)]:
        out.append("**%s**" % LABELS[problem])
        out.append("")
        body = []
        for r in sorted((r for r in rows if r["problem"] == problem), key=lambda r: (r["solver"], -r["rtol"])):
            body.append([r["solver"], "%g" % r["rtol"], "%.3g s" % r["seconds"],
                         "%.2e" % r["error"] if math.isfinite(r["error"]) else "failed"])
        out.append(table(["solver", "rtol", "time", "error"], body))
        out.append("")
        pairs = _equal_accuracy(rows, problem)
        eq = [x for x in pairs if x[1] is not None]
        if pairs:
            body = []
            for sc, best, ratio in pairs:
                t = _interpolated(rows, problem, sc)
                if best and (t is None or best["seconds"] < t):  # a faster run, more accurate
                    t = best["seconds"]
                body.append(["%s %g" % (sc["solver"].replace("SciPy ", ""), sc["rtol"]), "%.2e" % sc["error"],
                             "%.3g s" % sc["seconds"],
                             "%s %g" % (best["solver"].replace("mbsgen ", ""), best["rtol"]) if best else "none as accurate",
                             "%.2e" % best["error"] if best else "", "%.3g s" % best["seconds"] if best else "",
                             "%.1f×" % ratio if best else "", "%.1f×" % (sc["seconds"] / t) if t else ""])
            out.append(table(["SciPy run", "its error", "its time", "our fastest run as accurate", "error", "time",
                              "ratio", "ratio at its error (interpolated)"], body))
            out.append("")
        if eq:
            ratios = [x[2] for x in eq]
            per = []
            for solver in sorted({x[0]["solver"] for x in eq}):
                rs = sorted(x[2] for x in eq if x[0]["solver"] == solver)
                per.append("%s %.0f–%.0f× (median %.0f×)" % (solver.replace("SciPy ", ""), rs[0], rs[-1], rs[len(rs) // 2]))
            out.append("At equal or better accuracy, ours is %.0f–%.0f× faster than SciPy (each SciPy run against our "
                       "fastest run at least as accurate; median %.0f×): %s." %
                       (min(ratios), max(ratios), sorted(ratios)[len(ratios) // 2], ", ".join(per)))
            out.append("")
        out.append("![work_precision_%s](simulation/work_precision_%s.svg)" % (problem, problem))
        out.append("")
    return out


if __name__ == "__main__":
    def _table(header, body):
        lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in body])
    print("\n".join(simulation_section(sys.argv[1], _table)))
