#!/usr/bin/python3
"""mbsgen's Python package against SymPy mechanics with lambdify (issue 41 §4), side by side in
one run, on planar chains of N point masses on massless rods (N = 2: the double pendulum; N = 6),
the model of bench/peers/sympy_chain.py (KanesMethod; per-link m_i, l_i, k_i, c_i, gravity):

  model to first eigenvalues: from the model (a YAML file for mbsgen, with an empty cache, so that
      the generation is counted; SymPy's KanesMethod from scratch) to the eigenvalues of the
      linearization at rest about q = 0: mbsgen.Model(...).modes(); SymPy: kanes_equations, the
      Jacobians of the forcing by q and u, lambdify, the quadratic eigenproblem by SciPy (the
      companion pencil, scipy.linalg.eig); lambdify with cse=True (its common subexpressions);
  per-call right-hand side: the accelerations ÿ(q, q̇) at a state, Model.accelerations against
      a lambdified mass matrix and forcing and numpy.linalg.solve; medians of R batches.

Both eigenvalue sets and both right-hand sides are compared (they must agree to rounding).

usage: PYTHONPATH=build/ci/python /usr/bin/python3 bench/python_vs_sympy.py [--links 2 6] [--repeats R]
(Debian python3-sympy and python3-scipy, which scripts/bench.sh installs)
"""
import argparse
import importlib.util
import os
import statistics
import tempfile
import time

import numpy as np
import scipy.linalg
import sympy as sp

import mbsgen

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
spec = importlib.util.spec_from_file_location("sympy_chain", os.path.join(ROOT, "bench/peers/sympy_chain.py"))
sympy_chain = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sympy_chain)

M_DEFAULT, L_DEFAULT, K_DEFAULT, C_DEFAULT = 1.0, 0.5, 10.0, 0.1  # sympy_chain's defaults


def chain_yaml(n):
    """The model of sympy_chain.build(n) as an mbsgen model file."""
    lines = [f"model: planar_chain_{n}", "parameters:"]
    for i in range(1, n + 1):
        lines += [f"  m{i}: {{value: {M_DEFAULT}, unit: kg}}", f"  l{i}: {{value: {L_DEFAULT}, unit: m}}",
                  f"  k{i}: {{value: {K_DEFAULT}, unit: N m/rad}}", f"  c{i}: {{value: {C_DEFAULT}, unit: N m s/rad}}"]
    lines += ["  g: {value: 9.81, unit: m/s^2}", "coordinates:"]
    lines += [f"  - {{name: q{i}, unit: rad}}" for i in range(1, n + 1)]
    lines += ["bodies:"]
    for i in range(1, n + 1):
        lines += [f"  - name: link{i}"]
        if i > 1:
            lines += [f"    parent: link{i - 1}", f"    translation: [0, -l{i - 1}, 0]"]
        lines += [f"    rotation: [{{z: q{i}}}]", f"    mass: m{i}", f"    com: [0, -l{i}, 0]"]
    lines += ["forces:", "  - {type: gravity, g: [0, -g, 0]}"]
    for i in range(1, n + 1):
        lines += [f"  - {{name: spring{i}, type: generalized, coordinate: q{i}, value: -k{i}*q{i}, category: springs}}",
                  f"  - {{name: damper{i}, type: generalized, coordinate: q{i}, value: -c{i}*q{i}_dot, category: dampers}}"]
    return "\n".join(lines) + "\n"


def quadratic_eigenvalues(M, C, K):
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
    return scipy.linalg.eig(A, B, right=False)


def sympy_first_eigenvalues(n):
    t0 = time.perf_counter()
    km, particles, loads, q, u, params = sympy_chain.build(n)
    km.kanes_equations(particles, loads)
    at_rest = {ui: 0 for ui in u}
    at_zero = {qi: 0 for qi in q}
    M = km.mass_matrix.xreplace(at_zero)
    C = -km.forcing.jacobian(u).xreplace(at_rest).xreplace(at_zero)
    K = -km.forcing.jacobian(q).xreplace(at_rest).xreplace(at_zero)
    symbols = sorted(params, key=str)
    f = sp.lambdify([symbols], [M, C, K], modules="numpy", cse=True)
    Mn, Cn, Kn = (np.array(x, dtype=float) for x in f([params[s] for s in symbols]))
    lam = quadratic_eigenvalues(Mn, Cn, Kn)
    return time.perf_counter() - t0, lam, (km, q, u, params)


def sympy_rhs(km, q, u, params):
    symbols = sorted(params, key=str)
    f = sp.lambdify([q, u, symbols], [km.mass_matrix, km.forcing], modules="numpy", cse=True)
    values = [params[s] for s in symbols]

    def rhs(y, yd):
        M, F = f(y, yd, values)
        return np.linalg.solve(np.array(M, dtype=float), np.array(F, dtype=float).ravel())
    return rhs


def median_per_call(f, calls, repeats):
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            f()
        out.append((time.perf_counter() - t0) / calls)
    return statistics.median(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--links", type=int, nargs="+", default=[2, 6])
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    print(f"sympy {sp.__version__}, numpy {np.__version__}, mbsgen {mbsgen.__version__}")
    for n in a.links:
        with tempfile.TemporaryDirectory() as work:
            os.environ["MBSGEN_CACHE_DIR"] = os.path.join(work, "cache")
            path = os.path.join(work, f"chain{n}.yaml")
            with open(path, "w", encoding="utf-8") as f:
                f.write(chain_yaml(n))
            t0 = time.perf_counter()
            model = mbsgen.Model(path)
            ours = model.modes(all=True).eigenvalues
            t_ours = time.perf_counter() - t0
            t_sympy, theirs, (km, q, u, params) = sympy_first_eigenvalues(n)
            eig_diff = max(np.min(np.abs(theirs - lam)) / abs(lam) for lam in ours)
            rng = np.random.default_rng(n)
            y, yd = rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, n)
            rhs = sympy_rhs(km, q, u, params)
            rhs_diff = np.max(np.abs(model.accelerations(y, yd) - rhs(y, yd)))
            per_ours = median_per_call(lambda: model.accelerations(y, yd), 2000, a.repeats)
            per_sympy = median_per_call(lambda: rhs(y, yd), 2000, a.repeats)
            print(f"chain of {n}: model to first eigenvalues mbsgen {t_ours:.3f} s, SymPy {t_sympy:.3f} s "
                  f"({t_sympy / t_ours:.1f}x); eigenvalues agree to {eig_diff:.1e} (relative)")
            print(f"chain of {n}: right-hand side per call mbsgen {per_ours * 1e6:.2f} us, SymPy lambdify "
                  f"{per_sympy * 1e6:.2f} us ({per_sympy / per_ours:.1f}x); agree to {rhs_diff:.1e} rad/s^2")


if __name__ == "__main__":
    main()
