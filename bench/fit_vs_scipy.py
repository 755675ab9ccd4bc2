#!/usr/bin/python3
"""mbsgen's fit against SciPy's least_squares on the same residuals and starting points (issue 42).

    PYTHONPATH=build/ci/python /usr/bin/python3 bench/fit_vs_scipy.py [--repeats 5] [--only chain|ear]

Two problems, each from the model's values with bounds a factor 10 around them, on synthetic data
(the response of known parameters with 1 % noise, σ = 0.01 on ln|H| and on the phase):
  chain:      chain3_sympy (models/textbook), k1..k3, c1..c3, end_x/F at 60 frequencies;
  middle ear: models/middle_ear, ten suspension parameters, v_stapes/P and v_umbo/P at 60
              frequencies each.
Three rows (the chain has all three, the middle ear the first two):
mbsgen: Model.fit (Ceres Levenberg–Marquardt, exact Jacobian from the sensitivity kernels, in C++).
SciPy:  scipy.optimize.least_squares(method="trf", jac="2-point", x_scale="jac") on the residuals of
        fit.hpp (ln|H/H_d|/σ, wrap(arg H − arg H_d)/σ) in θ = ln p, each evaluation one call of
        Model.frf (the same tape, in C++): what a SciPy user writes around mbsgen's responses.
        Its finite differences cost n + 1 responses per Jacobian where ours costs about two, and a
        response costs it what it costs us, so this ratio is bounded near (n + 1)/2 by construction.
SciPy + SymPy: what a user without mbsgen writes, the workflow of SymPy/PyDy, which leave fitting
        to the user: chain3_sympy derived with sympy.physics.mechanics.KanesMethod (the chain of
        bench/peers/sympy_chain.py with the end load F), linearised at rest about q = 0 (F = 0) to
        M(p), Q(p) (damping), K(p), B, C (end_x/F) in all 13 parameters, lambdified once with
        modules="numpy" (a one-off cost, reported apart and not in the medians); the residuals are
        those of the SciPy row, with H(ω) = C (K + iωQ − ω²M)⁻¹ B by numpy.linalg.solve over all
        frequencies at once, and the same least_squares call. Before timing, this H is checked
        against Model.frf at the start and at the truth (all 60 frequencies, 1e-10 relative), so
        the two rows solve the same problem.
        The middle ear has no SymPy row: its SymPy derivation (87 parameters, 3-D bodies with full
        inertia tensors) is not available here, and none is made up for this benchmark.
Reported: the final cost ½Σr² of each, the wall-time medians (the runs interleaved) and their
ratios to mbsgen's, evaluations.
SciPy and SymPy come from Debian (python3-scipy, python3-sympy; scripts/bench.sh installs them),
never from the test suite.
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


def least_squares_fit(residuals, lo, hi, theta0):
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    s = least_squares(residuals, theta0, bounds=(np.log(lo), np.log(hi)), method="trf", jac="2-point", x_scale="jac")
    return time.perf_counter() - t0, s.cost, s.nfev, np.exp(s.x), s.status


def scipy_fit(model, data, names, lo, hi, theta0):
    def residuals(theta):
        values = dict(zip(names, np.exp(theta)))
        r = []
        for d in data:
            h = model.frf(d["input"], d["output"], d["frequency_hz"], **values).values
            lr = np.log(h / d["response"])  # imag: the phase difference wrapped to (-pi, pi]
            r.append(lr.real / 0.01)
            r.append(lr.imag / 0.01)
        return np.concatenate(r)

    return least_squares_fit(residuals, lo, hi, theta0)


def sympy_chain3():
    """chain3_sympy (models/textbook/chain3_sympy.yaml) derived with sympy.physics.mechanics, as
    bench/peers/sympy_chain.py builds the chain (point masses m_i at the ends of massless rods l_i,
    relative angles q_i about z, q1 from the downward vertical, gravity g along -y, generalized
    forces -k_i q_i - c_i q_i' on each relative angle) with the horizontal end load F, linearised
    at rest about q = 0, F = 0: M, Q = -df/du, K = -df/dq, B = df/dF of M u' = f(q, u, F), and
    C = d(end_x)/dq. Returns the parameter symbols' names and the lambdified (numpy) function of
    them that gives [M, Q, K, B, C], and the seconds of the import and of derivation + lambdify."""
    t0 = time.perf_counter()
    import sympy as sp
    sys.path.insert(0, os.path.join(ROOT, "bench", "peers"))
    import sympy_chain  # noqa: E402  (imports sympy.physics.mechanics)
    t1 = time.perf_counter()
    force = sp.Symbol("F")
    parts = sympy_chain.chain(3, end_load=force)
    km, particles, loads, q, u = parts["km"], parts["particles"], parts["loads"], parts["q"], parts["u"]
    m, l, k, c, g = parts["m"], parts["l"], parts["k"], parts["c"], parts["g"]
    world, origin, joint = parts["world"], parts["origin"], parts["end"]
    km.kanes_equations(particles, loads)
    op = {**{x: 0 for x in q}, **{x: 0 for x in u}, force: 0}
    f = km.forcing
    M = km.mass_matrix.xreplace(op)
    Q = -f.jacobian(u).xreplace(op)
    K = -f.jacobian(q).xreplace(op)
    B = f.jacobian([force]).xreplace(op)
    C = sp.Matrix([[joint.pos_from(origin).dot(world.x)]]).jacobian(q).xreplace(op)  # end_x
    symbols = m + l + k + c + (g,)
    fn = sp.lambdify(symbols, [M, Q, K, B, C], modules="numpy")
    return [str(x) for x in symbols], fn, t1 - t0, time.perf_counter() - t1


def sympy_frf(fn, p, hz):
    """H(ω) = C (K + iωQ − ω²M)⁻¹ B at every frequency (Hz), the parameters p in fn's order."""
    M, Q, K, B, C = fn(*p)
    w = (2 * np.pi * hz)[:, None, None]
    x = np.linalg.solve(K - w * w * M + 1j * w * Q, np.broadcast_to(B, (hz.size,) + B.shape))
    return (C @ x)[:, 0, 0]


def sympy_scipy_fit(fn, symbols, base, data, names, lo, hi, theta0):
    p = np.array([base[s] for s in symbols], dtype=float)
    at = [symbols.index(n) for n in names]
    (d,) = data  # the chain: end_x/F only

    def residuals(theta):
        p[at] = np.exp(theta)
        lr = np.log(sympy_frf(fn, p, d["frequency_hz"]) / d["response"])  # imag: wrapped to (-pi, pi]
        return np.concatenate([lr.real / 0.01, lr.imag / 0.01])

    return least_squares_fit(residuals, lo, hi, theta0)


def check_sympy(model, fn, symbols, base, pairs, hz, points):
    """The worst relative difference |H_sympy/H_mbsgen - 1| over the frequencies and points."""
    assert pairs == [("F", "end_x")]
    worst = 0.0
    for values in points:
        p = np.array([{**base, **values}[s] for s in symbols], dtype=float)
        ours = model.frf("F", "end_x", hz, **values).values
        worst = max(worst, float(np.max(np.abs(sympy_frf(fn, p, hz) / ours - 1))))
    return worst


def run(label, path, truth, pairs, hz, repeats, with_sympy=False):
    model = mbsgen.Model(os.path.join(ROOT, path))
    names = list(truth)
    defaults = {p.name: p.default for p in model.parameters}
    start = np.array([defaults[n] for n in names])
    lo, hi = start / 10, start * 10
    data = synthetic(model, truth, pairs, hz, 1)
    params = {n: (a, b) for n, a, b in zip(names, lo, hi)}
    if with_sympy:
        symbols, fn, import_s, derive_s = sympy_chain3()
        assert sorted(symbols) == sorted(defaults), (symbols, list(defaults))
        worst = check_sympy(model, fn, symbols, defaults, pairs, hz, [{}, truth])
        print(f"{label}: SymPy (numpy) H against Model.frf at the start and the truth, {hz.size} frequencies: "
              f"worst relative difference {worst:.2e}")
        assert worst < 1e-10, worst
        print(f"  SymPy one-off cost (not in the medians): import {import_s * 1e3:.0f} ms, "
              f"derivation + linearisation + lambdify {derive_s * 1e3:.0f} ms")
    ours, theirs, sympys = [], [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = model.fit(data, params)
        ours.append(time.perf_counter() - t0)
        t, cost, nfev, x, status = scipy_fit(model, data, names, lo, hi, np.log(start))
        theirs.append(t)
        if with_sympy:
            ts, cost_s, nfev_s, x_s, status_s = sympy_scipy_fit(fn, symbols, defaults, data, names, lo, hi,
                                                                np.log(start))
            sympys.append(ts)
    a, b = statistics.median(ours), statistics.median(theirs)
    print(f"{label}: {len(names)} parameters, {r.residuals} residuals")
    print(f"  mbsgen fit:          cost {r.cost:.10g}, {r.iterations} iterations, median {a * 1e3:.2f} ms "
          f"(converged {r.converged})")
    print(f"  SciPy least_squares: cost {cost:.10g}, {nfev} evaluations (+ the Jacobian's differences), "
          f"median {b * 1e3:.2f} ms (status {status})")
    if with_sympy:
        bs = statistics.median(sympys)
        print(f"  SciPy + SymPy:       cost {cost_s:.10g}, {nfev_s} evaluations (+ the Jacobian's differences), "
              f"median {bs * 1e3:.2f} ms (status {status_s})")
    print(f"  SciPy / mbsgen wall time: {b / a:.1f}x; cost mbsgen - SciPy: {r.cost - cost:.3g} "
          f"({'equal or lower' if r.cost <= cost * (1 + 1e-9) else 'HIGHER'})")
    print(f"  largest relative difference of the estimates: {np.max(np.abs(r.values / x - 1)):.2e}")
    rows = [("SciPy", label, b / a, r.cost <= cost * (1 + 1e-9))]
    if with_sympy:
        print(f"  SciPy + SymPy / mbsgen wall time: {bs / a:.1f}x; cost mbsgen - SciPy + SymPy: {r.cost - cost_s:.3g} "
              f"(relative {(r.cost - cost_s) / cost_s:.2g}, "
              f"{'equal or lower' if r.cost <= cost_s * (1 + 1e-9) else 'HIGHER'})")
        print(f"  largest relative difference of the estimates (SciPy + SymPy): {np.max(np.abs(r.values / x_s - 1)):.2e}")
        rows.append(("SciPy + SymPy", label, bs / a, r.cost <= cost_s * (1 + 1e-9)))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--only", choices=["chain", "ear"], help="run one problem only")
    a = ap.parse_args()
    results = []
    if a.only != "ear":
        results += run("chain3_sympy", "models/textbook/chain3_sympy.yaml",
                       {"k1": 12, "k2": 18, "k3": 33, "c1": 0.12, "c2": 0.17, "c3": 0.35}, [("F", "end_x")],
                       np.logspace(np.log10(0.2), 1, 60), a.repeats, with_sympy=True)
    if a.only != "chain":
        ear = mbsgen.Model(os.path.join(ROOT, "models/middle_ear/middle_ear.yaml"))
        d = {p.name: p.default for p in ear.parameters}
        names = ["k_eardrum_z", "d_eardrum_z", "kr_aml_x", "k_aml_z", "k_pil_z", "kr_imj_x", "k_isj_z", "d_isj_z",
                 "k_al_z", "d_cochlea_z"]
        truth = {n: d[n] * (0.8 if k % 2 else 1.25) for k, n in enumerate(names)}
        results += run("middle ear", "models/middle_ear/middle_ear.yaml", truth, [("P", "v_stapes"), ("P", "v_umbo")],
                       np.logspace(2, 4, 60), a.repeats)
    print("goal (cost equal or lower, >= 20x faster), per peer and problem:")
    for peer in ("SciPy", "SciPy + SymPy"):
        rows = [r for r in results if r[0] == peer]
        if rows:
            note = " (chain only: no SymPy derivation of the middle ear here)" if peer != "SciPy" else ""
            print(f"  {peer}{note}: " + "; ".join(f"{p} {x:.1f}x, cost {'equal or lower' if c else 'HIGHER'}"
                                                   for _, p, x, c in rows)
                  + ": " + ("met" if all(x >= 20 and c for _, _, x, c in rows) else "NOT met"))
    ok = all(x >= 20 and c for _, _, x, c in results)
    print("goal (cost equal or lower, >= 20x faster):", "met" if ok else "NOT met")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
