"""Section of docs/accuracy-vs-time.md on large models (issue 17 §1), from compile_scale.csv of
bench/compile_scale.py: what a user pays before the first answer, against model size."""
import csv
import math
import os


def _num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def _rows(results):
    path = os.path.join(results, "compile_scale.csv")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def section(results, table, ftime):
    """Markdown lines; table(header, rows) and ftime(seconds) are report.py's."""
    rows = _rows(results)
    if not rows:
        return []
    by = {}
    for r in rows:
        by.setdefault(int(r["links"]), {})[r["variant"]] = r
    runs = next((r.get("runs") or "1" for r in rows if r["variant"] == "generate"), "1")
    out = ["### Large models: the cost before the first answer", "",
           "The N-link spatial chain (`bench/spatial_chain_model.py`, 2N coordinates, universal joints), "
           "by `bench/compile_scale.py`: **run** = `mbsgen run MODEL -- modes` with an empty solver cache "
           "(generation, the kernels longer than 20,000 operations cut into parts of 5,000, compiled by %s compilers at once — "
           "parts at -O2 up to 100,000 operations in all kernels, else at -O1, the rest at -O2 —, linking, the first eigenvalues), its wall and CPU time and the peak "
           "memory of all its processes together; **generate** = `mbsgen generate` alone (median of %s runs, their largest peak); ops = operations of "
           "mass_matrix + residual + linear + outputs + bodies (linear_structured calls linear); **kernels "
           "compiled** = the generated files compiled as a shared library the same way." % ("2", runs), ""]
    t = []
    for n in sorted(by):
        v = by[n]
        run, gen, parts = v.get("run", {}), v.get("generate", {}), v.get("parts", {})
        t.append([str(n), str(2 * n), "%.0f" % _num(gen.get("ops_total")),
                  ftime(_num(gen.get("wall_s"))), "%.0f MB" % _num(gen.get("peak_mb")),
                  ftime(_num(parts.get("wall_s"))), ftime(_num(parts.get("cpu_s"))), "%.0f MB" % _num(parts.get("peak_mb")),
                  ftime(_num(run.get("wall_s"))) + ("" if run.get("status") == "ok" else " (failed)"),
                  "%.0f MB" % _num(run.get("peak_mb"))])
    out += [table(["N", "coords", "ops", "generate", "its memory", "kernels compiled (wall)", "(CPU)",
                   "compile memory", "run: first answer", "run: peak memory"], t), ""]
    t = []
    for n in sorted(by):
        v = by[n]
        parts, whole = v.get("parts", {}), v.get("whole")
        for k in ("mass_matrix", "residual", "linear"):
            a = _num(parts.get(k + "_s"))
            if whole:
                b = _num(whole.get(k + "_s"))
                same = parts.get(k + "_checksum") == whole.get(k + "_checksum")
                t.append([str(n), k, ftime(a), ftime(b), "%.2f" % (a / b), "same" if same else "differ",
                          ftime(_num(whole.get("wall_s")))])
            else:
                t.append([str(n), k, ftime(a), "–", "–", "–", "–"])
    out += ["Time per call (thread CPU time, medians of 51 batches with the variants in turn, `bench/kernel_call_timing.cpp`): the kernels cut into parts "
            "(-O2 up to 100,000 operations, else -O1, as `mbsgen run` compiles them) against the whole kernels in one function each (`--part-operations 0`, -O2, one compiler: "
            "the form before issue 17), where that still compiles within the run's budget; \"same\" = the "
            "checksums of the outputs agree bit for bit.", "",
            table(["N", "kernel", "parts", "whole, -O2", "ratio", "outputs", "whole: compile wall"], t), ""]
    return out
