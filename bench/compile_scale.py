#!/usr/bin/env python3
"""What a large model costs before its first answer (issue 17 §1, docs/accuracy-vs-time.md).

For N-link spatial chains (bench/spatial_chain_model.py, 2N coordinates) this measures, in one run:

  run      `mbsgen run MODEL -- modes` with an empty solver cache: generation, compilation of the
           kernels cut into parts (several compilers at once) and the first answer; wall time,
           CPU time and the peak memory of all its processes together (sampled every 0.1 s)
  generate `mbsgen generate` alone, --generate-runs times (default 3): the median of its wall and
           CPU times, its largest peak memory, and the operation counts (one process of the
           generator runs 10-20 % slower or faster than the next on these shared machines)
  parts    the kernels cut into parts (at mbsgen run's level: -O2 up to 100,000 operations, else -O1)
           and the rest (-O2) compiled as a shared library, 2
           compilers at once, and the time per call of mass_matrix, residual and linear
           (bench/kernel_call_timing.cpp: thread CPU time, medians of 51 batches, the variants
           timed in turn in one process)
  whole    (N <= --whole-max) the same kernels not cut (`--part-operations 0`), the whole file
           at -O2 in one compiler: the form before issue 17, as the baseline of the time per call

Writes compile_scale.csv into OUT_DIR (one row per N and variant) and prints progress to stderr.

usage: compile_scale.py MBSGEN KERNEL_CALL_TIMING OUT_DIR [--links 10,20,30] [--whole-max 20]
                        [--jobs 2] [--compiler c++] [--generate-runs 3]
"""
import argparse
import csv
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import spatial_chain_model  # noqa: E402


def tree_rss_kb(root):
    """Resident memory of root and all its descendants, in KiB."""
    children, rss = {}, {}
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % pid) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open("/proc/%s/statm" % pid) as f:
                pages = int(f.read().split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(int(fields[1]), []).append(int(pid))
        rss[int(pid)] = pages * os.sysconf("SC_PAGE_SIZE") // 1024
    total, stack = 0, [root]
    while stack:
        p = stack.pop()
        total += rss.get(p, 0)
        stack.extend(children.get(p, []))
    return total


def measured(cmd, env=None, stdout=subprocess.DEVNULL):
    """Runs cmd; returns (exit code, wall s, CPU s of it and its children, peak tree RSS KiB)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=stdout, stderr=subprocess.PIPE)
    peak = [0]
    done = threading.Event()

    def sample():
        while not done.wait(0.1):
            peak[0] = max(peak[0], tree_rss_kb(proc.pid))

    sampler = threading.Thread(target=sample)
    sampler.start()
    _, err = proc.communicate()
    done.set()
    sampler.join()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode != 0:
        sys.stderr.write(err.decode(errors="replace")[-2000:])
    return proc.returncode, wall, cpu, peak[0]


def operation_counts(source):
    with open(source) as f:
        for line in f:
            if line.startswith("// Operation counts"):
                return {k.split()[0]: int(k.split()[1]) for k in line.split(":", 1)[1].strip().rstrip(";").split(";")}
    return {}


PARTS_O2_MAX_OPERATIONS = 100000  # generator/tool/run.cpp, kPartsO2MaxOperations


def compile_library(compiler, directory, units, jobs, output):
    """Compiles units [(source, level)] to objects, `jobs` at once, and links output.so."""
    t0 = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    pending, running, objects, peak = list(units), [], [], 0
    while pending or running:
        while pending and len(running) < jobs:
            source, level = pending.pop(0)
            obj = source[:-4] + ".o"
            objects.append(obj)
            running.append(subprocess.Popen([compiler, level, "-std=c++17", "-fPIC", "-c", source, "-o", obj,
                                             "-I", directory]))
        time.sleep(0.1)
        peak = max(peak, sum(tree_rss_kb(p.pid) for p in running))
        for p in list(running):
            if p.poll() is not None:
                if p.returncode != 0:
                    raise RuntimeError("compiling failed: %s" % p.args)
                running.remove(p)
    subprocess.run([compiler, "-shared", "-o", output] + objects, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.perf_counter() - t0, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), peak


def kernel_times(timing, model_id, libraries):
    """{library index: {kernel: (median s, checksum)}}, the libraries timed in turn in one process."""
    out = subprocess.run([timing, model_id] + libraries, check=True, capture_output=True, text=True).stdout
    times = {}
    for line in out.splitlines():
        index, name, median, checksum = line.split()
        times.setdefault(int(index), {})[name] = (float(median), float(checksum))
    return times


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("mbsgen")
    ap.add_argument("timing")
    ap.add_argument("out")
    ap.add_argument("--links", default="10,20,30")
    ap.add_argument("--whole-max", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--compiler", default="c++")
    ap.add_argument("--generate-runs", type=int, default=3)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = []
    work = tempfile.mkdtemp(prefix="mbsgen-compile-scale-")
    try:
        for n in [int(x) for x in args.links.split(",") if x]:
            model_id = "spatial_chain_%d" % n
            model = os.path.join(work, "%s.yaml" % model_id)
            with open(model, "w") as f:
                f.write(spatial_chain_model.chain_yaml(n))
            env = dict(os.environ, MBSGEN_CACHE_DIR=os.path.join(work, "cache-%d" % n), MBSGEN_JOBS=str(args.jobs))
            sys.stderr.write("[compile_scale] N = %d: mbsgen run -- modes\n" % n)
            rc, wall, cpu, peak = measured([args.mbsgen, "run", model, "--", "modes"], env=env)
            row = {"links": n, "coordinates": 2 * n}
            rows.append(dict(row, variant="run", status="ok" if rc == 0 else "failed", wall_s=wall, cpu_s=cpu,
                             peak_mb=peak / 1024))
            sys.stderr.write("[compile_scale] N = %d: mbsgen generate\n" % n)
            parts = os.path.join(work, "parts-%d" % n)
            runs = []
            for _ in range(max(1, args.generate_runs)):
                shutil.rmtree(parts, ignore_errors=True)
                runs.append(measured([args.mbsgen, "generate", model, "--out", parts, "--parts", str(2 * args.jobs)]))
                if runs[-1][0] != 0:
                    break  # a failure (a signal gives a negative code) is the row's status
            rc = runs[-1][0]
            wall = statistics.median(r[1] for r in runs)
            cpu = statistics.median(r[2] for r in runs)
            peak = max(r[3] for r in runs)
            ops = operation_counts(os.path.join(parts, model_id + ".cpp"))
            rows.append(dict(row, variant="generate", status="ok" if rc == 0 else "failed", wall_s=wall, cpu_s=cpu,
                             peak_mb=peak / 1024, runs=len(runs), ops_mass_matrix=ops.get("mass_matrix"),
                             ops_residual=ops.get("residual"), ops_linear=ops.get("linear"),
                             ops_total=sum(v for k, v in ops.items() if k != "linear_structured")))
            # The level mbsgen run takes (generator/tool/run.cpp, parts_level).
            level = "-O2" if sum(v for k, v in ops.items() if k != "linear_structured") <= PARTS_O2_MAX_OPERATIONS else "-O1"
            units = [(os.path.join(parts, f), level) for f in sorted(os.listdir(parts))
                     if "_part" in f and f.endswith(".cpp")]
            units.append((os.path.join(parts, model_id + ".cpp"), "-O2"))
            sys.stderr.write("[compile_scale] N = %d: compiling the parts\n" % n)
            wall, cpu, peak = compile_library(args.compiler, parts, units, args.jobs, os.path.join(parts, "lib.so"))
            variants = [dict(row, variant="parts", status="ok", wall_s=wall, cpu_s=cpu, peak_mb=peak / 1024)]
            libraries = [os.path.join(parts, "lib.so")]
            if n <= args.whole_max:
                sys.stderr.write("[compile_scale] N = %d: the whole kernels (-O2, one file)\n" % n)
                whole = os.path.join(work, "whole-%d" % n)
                subprocess.run([args.mbsgen, "generate", model, "--out", whole, "--part-operations", "0"], check=True,
                               stderr=subprocess.DEVNULL)
                wall, cpu, peak = compile_library(args.compiler, whole, [(os.path.join(whole, model_id + ".cpp"), "-O2")],
                                                  1, os.path.join(whole, "lib.so"))
                variants.append(dict(row, variant="whole", status="ok", wall_s=wall, cpu_s=cpu, peak_mb=peak / 1024))
                libraries.append(os.path.join(whole, "lib.so"))
            times = kernel_times(args.timing, model_id, libraries)
            for k, variant in enumerate(variants):
                for kernel, (median, checksum) in times[k].items():
                    variant["%s_s" % kernel] = median
                    variant["%s_checksum" % kernel] = checksum
                rows.append(variant)
            shutil.rmtree(parts, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    fields = ["links", "coordinates", "variant", "status", "wall_s", "cpu_s", "peak_mb", "runs", "ops_mass_matrix",
              "ops_residual", "ops_linear", "ops_total", "mass_matrix_s", "residual_s", "linear_s",
              "mass_matrix_checksum", "residual_checksum", "linear_checksum"]
    with open(os.path.join(args.out, "compile_scale.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    return 0


if __name__ == "__main__":
    sys.exit(main())
