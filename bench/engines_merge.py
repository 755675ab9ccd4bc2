"""Merges the engines.csv of several engines_bench processes (bench/engines.sh --processes K) into
one engines.csv of the same columns: per row, the median over the processes of their medians, the
smallest min and the largest max, and `processes` added.

Why several processes: on these machines one process of the same binary runs the 12-link chain's
kernels either about 10 % faster or slower than the next, for the whole process (its memory
placement: the same bimodal split with address-space randomisation off). The ratios of one
process then depend on which mode it drew; the median over processes does not (Mytkowicz et al.,
"Producing wrong data without doing anything obviously wrong!", ASPLOS 2009, on such layout
effects). Only the standard library is used.

    python3 bench/engines_merge.py OUT_CSV RUN_CSV [RUN_CSV ...]
"""
import csv
import statistics
import sys


def merge(out_path, run_paths):
    runs = []
    for path in run_paths:
        with open(path) as f:
            runs.append(list(csv.DictReader(f)))
    fields = list(csv.DictReader(open(run_paths[0])).fieldnames) + ["processes"]
    key = lambda r: (r["model"], r["N"], r["engine"], r["quantity"])
    order = [key(r) for r in runs[0]]
    by_key = {}
    for rows in runs:
        for r in rows:
            by_key.setdefault(key(r), []).append(r)
    with open(out_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for k in order:
            rs = by_key[k]
            out = dict(rs[0])
            out["median_ns"] = "%.4g" % statistics.median(float(r["median_ns"]) for r in rs)
            out["min_ns"] = "%.4g" % min(float(r["min_ns"]) for r in rs)
            out["max_ns"] = "%.4g" % max(float(r["max_ns"]) for r in rs)
            out["processes"] = str(len(rs))
            w.writerow(out)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: engines_merge.py OUT_CSV RUN_CSV [RUN_CSV ...]")
    merge(sys.argv[1], sys.argv[2:])
