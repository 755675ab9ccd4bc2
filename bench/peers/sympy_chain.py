#!/usr/bin/python3
"""SymPy peer of bench/generation_cost.cpp (issue 7 §4, docs/accuracy-vs-time.md).

Builds the N-link planar chain of mbsgen::planar_chain (generator/src/model/parametric_chains.cpp) with
sympy.physics.mechanics.KanesMethod — point masses m_i at the ends of massless rods l_i,
revolute joints about z with relative angles q_i (q_1 from the downward vertical), a torsional
spring k_i and damper c_i on each relative angle, gravity g along -y — derives the equations of
motion (kanes_equations) and prints, as it goes, one "key value" line per result so that a run
stopped by a time limit still reports what it finished:

  sympy_version, derive_s, ops_mass_forcing
  mck_s, ops_mck_cse, ops_mck_q0_cse: M, C, K at rest (u = 0) straight from the equations of
      motion M(q) u' = f(q, u): M, C = -df/du, K = -df/dq, each entry as mbsgen's `linear`
      kernel has it (same signs, no kinematic rows); sympy.cse of all three about any q (like
      the kernel, whose operating point y0 is an argument) and with q = 0 substituted (the
      figures of issue 17 §3: 265 at N = 6, 989 at N = 10)
  linearize_s, ops_linear, cse_s, ops_linear_cse: KanesMethod.linearize at rest about any q
      (A_and_B=False, i.e. without inverting M symbolically) and sympy.cse of its M_l and A_l
  max_rel_diff (M, C, K at q = 0 with mbsgen's default parameters against the matrices of
      generation_cost in GEN_MATRICES, when given), done

Operations are sympy.count_ops of the expressions with the coordinates and speeds as plain
symbols: count_ops counts each q_i(t) of a dynamicsymbol as one operation (FUNC), which a
generated kernel reads from a variable (this added 2 to 4 at N = 2 before; ops_linear_cse 51
became 47). Ours are the operations of the emitted kernel (+, -, *, /, calls), where x**k is
k - 1 products and count_ops says 1: a difference that favours SymPy.

usage: /usr/bin/python3 bench/peers/sympy_chain.py N [GEN_MATRICES_FILE]
Run by scripts/bench.sh under `timeout`; needs Debian's python3-sympy.
"""
import sys
import time

import sympy as sp
import sympy.physics.mechanics as me


def say(key, value):
    print(key, value, flush=True)


def chain(n, end_load=None):
    """The chain's symbols, frames and Kane's equations: a dict with km, particles, loads, q, u,
    m, l, k, c, g, world, origin and end (the last point); with `end_load` (a symbol), that force
    along the world x axis acts at the end (bench/fit_vs_scipy.py's chain3_sympy with its F)."""
    q = me.dynamicsymbols("q1:%d" % (n + 1))
    u = me.dynamicsymbols("u1:%d" % (n + 1))
    m = sp.symbols("m1:%d" % (n + 1))
    l = sp.symbols("l1:%d" % (n + 1))
    k = sp.symbols("k1:%d" % (n + 1))
    c = sp.symbols("c1:%d" % (n + 1))
    g = sp.Symbol("g")
    world = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(world, 0)
    particles, loads = [], []
    parent, joint = world, origin
    for i in range(n):
        frame = parent.orientnew("A%d" % (i + 1), "Axis", [q[i], parent.z])
        frame.set_ang_vel(parent, u[i] * parent.z)
        point = joint.locatenew("P%d" % (i + 1), -l[i] * frame.y)
        point.v2pt_theory(joint, world, frame)
        particles.append(me.Particle("pa%d" % (i + 1), point, m[i]))
        loads.append((point, -m[i] * g * world.y))
        torque = (-k[i] * q[i] - c[i] * u[i]) * world.z  # on the relative angle q_i
        loads.append((frame, torque))
        if i > 0:
            loads.append((parent, -torque))
        parent, joint = frame, point
    if end_load is not None:
        loads.append((joint, end_load * world.x))
    kd = [q[i].diff(me.dynamicsymbols._t) - u[i] for i in range(n)]
    km = me.KanesMethod(world, q_ind=q, u_ind=u, kd_eqs=kd)
    return dict(km=km, particles=particles, loads=loads, q=q, u=u, m=m, l=l, k=k, c=c, g=g, world=world,
                origin=origin, end=joint)


def build(n):
    parts = chain(n)
    m, l, k, c = parts["m"], parts["l"], parts["k"], parts["c"]
    params = {parts["g"]: 9.81}
    for i in range(n):  # mbsgen::planar_chain's defaults
        params.update({m[i]: 1.0, l[i]: 0.5, k[i]: 10.0, c[i]: 0.1})
    return parts["km"], parts["particles"], parts["loads"], parts["q"], parts["u"], params


def plain(q, u):
    """Coordinates and speeds q_i(t), u_i(t) -> plain symbols, for count_ops (see the docstring)."""
    names = ["q%d" % (i + 1) for i in range(len(q))] + ["u%d" % (i + 1) for i in range(len(u))]
    return dict(zip(list(q) + list(u), sp.symbols(names)))


def ops(exprs, symbols):
    return sum(sp.count_ops(sp.sympify(e).xreplace(symbols)) for e in exprs)


def ops_after_cse(exprs, symbols):
    replacements, reduced = sp.cse([sp.sympify(e).xreplace(symbols) for e in exprs])
    return sum(sp.count_ops(e) for _, e in replacements) + sum(sp.count_ops(e) for e in reduced)


def read_matrices(path):
    mats, name, rows = {}, None, []
    with open(path) as f:
        for line in f:
            line = line.split()
            if len(line) == 1 and line[0] in ("M", "Q", "K"):
                if name:
                    mats[name] = sp.Matrix(rows)
                name, rows = line[0], []
            elif line:
                rows.append([float(x) for x in line])
    if name:
        mats[name] = sp.Matrix(rows)
    return mats


def main():
    n = int(sys.argv[1])
    say("sympy_version", sp.__version__)
    t0 = time.perf_counter()
    km, particles, loads, q, u, params = build(n)
    km.kanes_equations(particles, loads)
    say("derive_s", "%.4g" % (time.perf_counter() - t0))
    symbols = plain(q, u)
    say("ops_mass_forcing", ops(km.mass_matrix, symbols) + ops(km.forcing, symbols))
    # At rest (u = 0) but about any q, as mbsgen's `linear` kernel, which takes the operating
    # point y0 as an argument (q = 0 substituted folds sin and cos into constants).
    op = {ui: 0 for ui in u}
    t0 = time.perf_counter()
    M = km.mass_matrix
    C = -km.forcing.jacobian(u).xreplace(op)
    K = -km.forcing.xreplace(op).jacobian(q)
    mck = list(M) + list(C) + list(K)
    say("mck_s", "%.4g" % (time.perf_counter() - t0))
    say("ops_mck_cse", ops_after_cse(mck, symbols))
    say("ops_mck_q0_cse", ops_after_cse([e.subs({qi: 0 for qi in q}) for e in mck], symbols))
    t0 = time.perf_counter()
    Ml, Al, _, _ = km.linearize(op_point=op, A_and_B=False, simplify=False)
    say("linearize_s", "%.4g" % (time.perf_counter() - t0))
    say("ops_linear", ops(Ml, symbols) + ops(Al, symbols))
    t0 = time.perf_counter()
    ops_cse = ops_after_cse(list(Ml) + list(Al), symbols)
    say("cse_s", "%.4g" % (time.perf_counter() - t0))
    say("ops_linear_cse", ops_cse)
    if len(sys.argv) > 2:
        # Rows n..2n-1 of M_l [q'; u'] = A_l [q; u]: M u' = -K q - C u up to the sign SymPy gives
        # the dynamic rows (Fr + Fr* = 0 has -M): normalised by the sign of M_11.
        sub = {**params, **op, **{qi: 0 for qi in q}}
        Mn = Ml[n:, n:].subs(sub).evalf()
        Kn = -Al[n:, :n].subs(sub).evalf()
        Cn = -Al[n:, n:].subs(sub).evalf()
        if Mn[0, 0] < 0:
            Mn, Kn, Cn = -Mn, -Kn, -Cn
        ours = read_matrices(sys.argv[2])
        diff, scale = 0.0, 0.0
        for a, b in ((Mn, ours["M"]), (Cn, ours["Q"]), (Kn, ours["K"])):
            for x, y in zip(a, b):
                diff = max(diff, abs(float(x) - float(y)))
                scale = max(scale, abs(float(y)))
        say("max_rel_diff", "%.3g" % (diff / scale))
    say("done", 1)


if __name__ == "__main__":
    main()
