#!/usr/bin/python3
"""mbsgen's fit against SciPy's least_squares on the same residuals and starting points (issue 42).

    PYTHONPATH=build/ci/python /usr/bin/python3 bench/fit_vs_scipy.py [--repeats 5]

Two problems, each from the model's values with bounds a factor 10 around them, on synthetic data
(the response of known parameters with 1 % noise, σ = 0.01 on ln|H| and on the phase):
  chain:      chain3_sympy (models/textbook), k1..k3, c1..c3, end_x/F at 60 frequencies;
  middle ear: models/middle_ear, ten suspension parameters, v_stapes/P and v_umbo/P at 60
              frequencies each.
mbsgen: Model.fit (Ceres Levenberg–Marquardt, exact Jacobian from the sensitivity kernels, in C++).
SciPy:  scipy.optimize.least_squares(method="trf", jac="2-point", x_scale="jac") on the residuals of
        fit.hpp (ln|H/H_d|/σ, wrap(arg H − arg H_d)/σ) in θ = ln p, each evaluation one call of
        Model.frf (the same tape, in C++): what a SciPy user writes around mbsgen's responses.
Reported: the final cost ½Σr² of each, the wall-time medians and their ratio, evaluations.
SciPy comes from Debian (python3-scipy; scripts/bench.sh installs it), never from the test suite.
"""
import argparse
import os
import statistics
import sys
import time

import numpy as np

import mbsgen

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def synthetic(model, truth, pairs, hz, seed):
    rng = np.random.default_rng(seed)
    data = []
    for inp, out in pairs:
        h = model.frf(inp, out, hz, **truth).values
        h = h * np.exp(0.01 * rng.standard_normal(hz.size) + 1j * 0.01 * rng.standard_normal(hz.size))
        data.append({"frequency_hz": hz, "response": h, "sigma_magnitude": 0.01, "sigma_phase_deg": np.degrees(0.01),
                     "input": inp, "output": out})
    return data


def scipy_fit(model, data, names, lo, hi, theta0):
    from scipy.optimize import least_squares

    def residuals(theta):
        values = dict(zip(names, np.exp(theta)))
        r = []
        for d in data:
            h = model.frf(d["input"], d["output"], d["frequency_hz"], **values).values
            lr = np.log(h / d["response"])  # imag: the phase difference wrapped to (-pi, pi]
            r.append(lr.real / 0.01)
            r.append(lr.imag / 0.01)
        return np.concatenate(r)

    t0 = time.perf_counter()
    s = least_squares(residuals, theta0, bounds=(np.log(lo), np.log(hi)), method="trf", jac="2-point", x_scale="jac")
    return time.perf_counter() - t0, s.cost, s.nfev, np.exp(s.x), s.status


def run(label, path, truth, pairs, hz, repeats):
    model = mbsgen.Model(os.path.join(ROOT, path))
    names = list(truth)
    defaults = {p.name: p.default for p in model.parameters}
    start = np.array([defaults[n] for n in names])
    lo, hi = start / 10, start * 10
    data = synthetic(model, truth, pairs, hz, 1)
    params = {n: (a, b) for n, a, b in zip(names, lo, hi)}
    ours, theirs = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = model.fit(data, params)
        ours.append(time.perf_counter() - t0)
        t, cost, nfev, x, status = scipy_fit(model, data, names, lo, hi, np.log(start))
        theirs.append(t)
    a, b = statistics.median(ours), statistics.median(theirs)
    print(f"{label}: {len(names)} parameters, {r.residuals} residuals")
    print(f"  mbsgen fit:          cost {r.cost:.10g}, {r.iterations} iterations, median {a * 1e3:.2f} ms "
          f"(converged {r.converged})")
    print(f"  SciPy least_squares: cost {cost:.10g}, {nfev} evaluations (+ the Jacobian's differences), "
          f"median {b * 1e3:.2f} ms (status {status})")
    print(f"  SciPy / mbsgen wall time: {b / a:.1f}x; cost mbsgen - SciPy: {r.cost - cost:.3g} "
          f"({'equal or lower' if r.cost <= cost * (1 + 1e-9) else 'HIGHER'})")
    print(f"  largest relative difference of the estimates: {np.max(np.abs(r.values / x - 1)):.2e}")
    return b / a, r.cost <= cost * (1 + 1e-9)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    results = [
        run("chain3_sympy", "models/textbook/chain3_sympy.yaml",
            {"k1": 12, "k2": 18, "k3": 33, "c1": 0.12, "c2": 0.17, "c3": 0.35}, [("F", "end_x")],
            np.logspace(np.log10(0.2), 1, 60), a.repeats),
    ]
    ear = mbsgen.Model(os.path.join(ROOT, "models/middle_ear/middle_ear.yaml"))
    d = {p.name: p.default for p in ear.parameters}
    names = ["k_eardrum_z", "d_eardrum_z", "kr_aml_x", "k_aml_z", "k_pil_z", "kr_imj_x", "k_isj_z", "d_isj_z", "k_al_z",
             "d_cochlea_z"]
    truth = {n: d[n] * (0.8 if k % 2 else 1.25) for k, n in enumerate(names)}
    results.append(run("middle ear", "models/middle_ear/middle_ear.yaml", truth, [("P", "v_stapes"), ("P", "v_umbo")],
                       np.logspace(2, 4, 60), a.repeats))
    ok = all(r[0] >= 20 and r[1] for r in results)
    print("goal (cost equal or lower, >= 20x faster):", "met" if ok else "NOT met")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
