#!/usr/bin/python3
"""The Python package's cost against the C++ it calls (issue 41 §4; figures in docs/python.md).

  1. Overhead per call: Model.linear() from Python against the same facade call timed in C++
     (mbsgen._mbsgen._timing), in one process, on the double pendulum and the middle ear;
  2. a 1,000-point frequency response of the middle ear: Model.frf() against the same call in C++;
  3. batch: N parameter sets of the middle ear's stapes velocity per ear-canal pressure at 300
     frequencies (10 parameters varied uniformly ±20 %) with Model.frf(params=…) against the
     compiled solver's `study` of the same design size (`mbsgen run … -- study`), both on every
     core; the study's time is its process's wall time, warm (its solver built before).

Each figure is the median of R repeats, the pairs interleaved; ratios are of medians taken in the
same run.

usage: PYTHONPATH=build/ci/python /usr/bin/python3 bench/python_bench.py [--sets N] [--repeats R]
       (MBSGEN: the mbsgen command, default build/ci/generator/mbsgen)
"""
import argparse
import os
import statistics
import subprocess
import time

import numpy as np

import mbsgen
from mbsgen import _mbsgen

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EAR = os.path.join(ROOT, "models/middle_ear/middle_ear.yaml")
PENDULUM = os.path.join(ROOT, "models/textbook/double_pendulum.yaml")
VARIED = ["k_aml_x", "k_pil_x", "k_imj_x", "k_isj_x", "k_isj_z", "k_al_y", "k_al_z", "d_isj_z", "d_al_z", "k_eardrum_z"]


def median_of(f, repeats):
    return statistics.median(f() for _ in range(repeats))


def per_call(model, calls, repeats):
    p = model.parameter_values()
    py_s, cpp_s = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            model.linear()
        py_s.append((time.perf_counter() - t0) / calls)
        cpp_s.append(_mbsgen._timing.linear(model._kernels, p, calls) / calls)
    return statistics.median(py_s), statistics.median(cpp_s)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sets", type=int, default=10_000)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    tool = os.environ.get("MBSGEN", os.path.join(ROOT, "build/ci/generator/mbsgen"))
    os.environ["MBSGEN"] = tool
    cores = os.cpu_count()
    print(f"mbsgen python bench: {cores} cores, {a.repeats} repeats, numpy {np.__version__}")

    for path in (PENDULUM, EAR):
        m = mbsgen.Model(path)
        py, cpp = per_call(m, 2000 if m.name != "middle_ear" else 300, a.repeats)
        print(f"linear() {m.name}: python {py * 1e6:.2f} us, C++ {cpp * 1e6:.2f} us, "
              f"overhead {(py - cpp) * 1e6:.2f} us per call")

    ear = mbsgen.Model(EAR)
    p = ear.parameter_values()
    hz = np.logspace(2, 4, 1000)
    py_s, cpp_s = [], []
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        ear.frf("P", "v_stapes", hz)
        py_s.append(time.perf_counter() - t0)
        cpp_s.append(_mbsgen._timing.frf(ear._kernels, p, "P", "v_stapes", hz, 1))
    py, cpp = statistics.median(py_s), statistics.median(cpp_s)
    print(f"frf 1000 points middle_ear: python {py * 1e3:.2f} ms, C++ {cpp * 1e3:.2f} ms, ratio {py / cpp:.3f}")

    names = [n for n in VARIED if n in {q.name for q in ear.parameters}]
    defaults = dict(zip([q.name for q in ear.parameters], p))
    rng = np.random.default_rng(1)
    sets = {n: defaults[n] * rng.uniform(0.8, 1.2, a.sets) for n in names}
    hz300 = np.logspace(2, 4, 300)
    def study_args(samples):
        args = [tool, "run", EAR, "--", "study", "--design", "lhs", "--samples", str(samples), "--input", "P",
                "--output", "v_stapes", "--from", "100", "--to", "10000", "--points", "300"]
        for n in names:
            args += ["--parameter", f"{n}=uniform:{defaults[n] * 0.8!r}:{defaults[n] * 1.2!r}"]
        return args

    subprocess.run(study_args(10), check=True, stdout=subprocess.DEVNULL)  # builds the compiled solver
    batch_s, study_s = [], []
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        b = ear.frf("P", "v_stapes", hz300, params=sets)
        batch_s.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        subprocess.run(study_args(a.sets), check=True, stdout=subprocess.DEVNULL)
        study_s.append(time.perf_counter() - t0)
    bt, st = statistics.median(batch_s), statistics.median(study_s)
    print(f"batch {a.sets} sets x 300 frequencies middle_ear ({len(names)} parameters, {len(b.failures)} failed): "
          f"python {bt:.2f} s, study {st:.2f} s, ratio {bt / st:.3f}")


if __name__ == "__main__":
    main()
