#!/usr/bin/python3
"""Issue 18 §4: simulate() against SciPy's solve_ivp (Radau and LSODA) on the same problems, with
the right-hand side and its Jacobian through the same generated kernels (a shared library of the
kernels, called with ctypes; M ÿ = −(k − q) solved with numpy.linalg.solve).

    /usr/bin/python3 bench/simulation_compare.py GENERATED_DIR RESULTS_DIR [REPEATS]   (Debian's python, with python3-scipy)

GENERATED_DIR holds <id>/<id>.cpp of simple_pendulum, double_pendulum and middle_ear, generated
with --dynamics (the build tree's generated/mbsgen, or the repository's generated/). RESULTS_DIR
holds bench/simulation_timing's output (ours_*.csv, reference_*.csv, ours_timing.csv); this
writes RESULTS_DIR/simulation_compare.csv (problem, solver, rtol, seconds, error), the error being
the largest difference of a coordinate from the reference run over all samples, relative to the
largest coordinate of the reference. Needs Debian python3-scipy (scripts/bench.sh installs it).
"""
import csv
import ctypes
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

PROBLEMS = {  # id, duration, step, initial coordinates, input (amplitude, Hz), atol scale, tolerances
    "pendulum": ("simple_pendulum", 10.0, 0.01, {0: 2.5}, None, 1.0, (1e-4, 1e-6, 1e-8, 1e-10)),
    "double_pendulum": ("double_pendulum", 100.0, 0.1, {0: 0.5}, None, 1.0, (1e-4, 1e-6, 1e-8, 1e-10)),
    # rtol 1e-10 is at the kernels' rounding floor (ours takes 190,000 steps; Radau tens of minutes)
    "middle_ear": ("middle_ear", 0.02, 1e-5, {}, (1.0, 1000.0), 1e-9, (1e-4, 1e-6, 1e-8)),
}


def load(generated, model_id, work):
    lib = os.path.join(work, "lib%s.so" % model_id)
    src = os.path.join(generated, model_id, model_id + ".cpp")
    subprocess.run(["g++", "-O2", "-shared", "-fPIC", "-std=c++17", "-I", os.path.dirname(src), src, "-o", lib], check=True)
    return ctypes.CDLL(lib)


class Model:
    def __init__(self, lib, model_id, n, m, p):
        self.n, self.m = n, m
        dp = ctypes.POINTER(ctypes.c_double)
        self.dynamics = getattr(lib, model_id + "_dynamics")
        self.dynamics.argtypes = [dp] * 6
        self.jacobian = getattr(lib, model_id + "_dynamics_jacobian")
        self.jacobian.argtypes = [dp] * 7
        self.p = np.ascontiguousarray(p, dtype=float)
        self.M = np.zeros((n, n), order="F")
        self.r = np.zeros(n)
        self.Ky = np.zeros((n, n), order="F")
        self.Kv = np.zeros((n, n), order="F")
        self.ptr = lambda a: a.ctypes.data_as(dp)

    def accelerations(self, y, v, u):
        y, v, u = (np.ascontiguousarray(a, dtype=float) for a in (y, v, u))
        if self.dynamics(self.ptr(y), self.ptr(v), self.ptr(u), self.ptr(self.p), self.ptr(self.M), self.ptr(self.r)):
            raise FloatingPointError("non-finite kernel values")
        return np.linalg.solve(self.M, -self.r)

    def jac(self, y, v, u):
        a = self.accelerations(y, v, u)
        a = np.ascontiguousarray(a)
        self.jacobian(self.ptr(np.ascontiguousarray(y, dtype=float)), self.ptr(np.ascontiguousarray(v, dtype=float)),
                      self.ptr(a), self.ptr(np.ascontiguousarray(u, dtype=float)), self.ptr(self.p), self.ptr(self.Ky),
                      self.ptr(self.Kv))
        n = self.n
        J = np.zeros((2 * n, 2 * n))
        J[:n, n:] = np.eye(n)
        J[n:, :n] = -np.linalg.solve(self.M, self.Ky)
        J[n:, n:] = -np.linalg.solve(self.M, self.Kv)
        return J


def parameters(generated, model_id):
    """The parameter defaults from the manifest."""
    import json
    with open(os.path.join(generated, model_id, model_id + ".json")) as f:
        j = json.load(f)
    return [p["value"] for p in j["parameters"]], len(j["coordinates"]), len(j["inputs"])


def read_samples(path):
    with open(path) as f:
        rows = [list(map(float, r)) for r in csv.reader(f)]
    a = np.array(rows)
    return a[:, 0], a[:, 1:]


def error(y, ref):
    return float(np.max(np.abs(y - ref)) / np.max(np.abs(ref)))


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: simulation_compare.py GENERATED_DIR RESULTS_DIR [REPEATS]")
    generated, results = sys.argv[1], sys.argv[2]
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    out = []
    with open(os.path.join(results, "ours_timing.csv")) as f:
        for r in csv.DictReader(f):
            t, y = read_samples(os.path.join(results, "ours_%s_%s_%g.csv" % (r["problem"], r["method"], float(r["rtol"]))))
            _, ref = read_samples(os.path.join(results, "reference_%s.csv" % r["problem"]))
            out.append((r["problem"], "mbsgen " + r["method"].upper().replace("ADAMS", "Adams").replace("RADAU", "Radau"), float(r["rtol"]),
                        float(r["seconds"]), error(y, ref)))
    work = tempfile.mkdtemp(prefix="mbsgen-scipy-")
    for name, (model_id, duration, step, initial, tone, atol_scale, rtols) in PROBLEMS.items():
        p, n, m = parameters(generated, model_id)
        model = Model(load(generated, model_id, work), model_id, n, m, p)
        t_ref, ref = read_samples(os.path.join(results, "reference_%s.csv" % name))
        x0 = np.zeros(2 * n)
        for i, v in initial.items():
            x0[i] = v

        def u_of(t):
            # The tone drives the first input (the middle ear's P; its others move the temporal
            # bone, held still here); one entry per input, as the kernels read.
            u = np.zeros(max(m, 1))
            if tone:
                u[0] = tone[0] * np.sin(2 * np.pi * tone[1] * t)
            return u

        def f(t, x):
            return np.concatenate((x[n:], model.accelerations(x[:n], x[n:], u_of(t))))

        def jac(t, x):
            return model.jac(x[:n], x[n:], u_of(t))

        for method in ("Radau", "LSODA"):
            for rtol in rtols:
                seconds, sol = [], None
                for _ in range(repeats):
                    t0 = time.perf_counter()
                    sol = solve_ivp(f, (0.0, duration), x0, method=method, t_eval=t_ref, rtol=rtol,
                                    atol=rtol * atol_scale, jac=jac)
                    seconds.append(time.perf_counter() - t0)
                seconds.sort()
                e = error(sol.y[:n].T, ref) if sol.success and sol.y.shape[1] == len(t_ref) else float("nan")
                out.append((name, "SciPy " + method, rtol, seconds[len(seconds) // 2], e))
                print("%-16s %-14s rtol %-6g %9.4f s  error %.3e  (%s)" % (name, "SciPy " + method, rtol,
                                                                         seconds[len(seconds) // 2], e, sol.message),
                      flush=True)
    with open(os.path.join(results, "simulation_compare.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["problem", "solver", "rtol", "seconds", "error"])
        for row in out:
            w.writerow(row)
    for row in out:
        if row[1].startswith("mbsgen"):
            print("%-16s %-14s rtol %-6g %9.5f s  error %.3e" % row)


if __name__ == "__main__":
    main()
