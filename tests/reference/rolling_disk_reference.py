#!/usr/bin/env python3
"""Independent references for the rolling thin disk (nonholonomic constraints, issue 16).

Run `python3 tests/reference/rolling_disk_reference.py` from the repository root: it recomputes
every number and writes tests/data/reference/rolling_disk.json (deterministic; `--check` compares
with the file instead of writing it, `--out PATH` writes elsewhere). Needs only SymPy and mpmath;
no mbsgen code or output is used. Runs in 10-15 s.

The disk and its coordinates are those of SymPy's own test
sympy/physics/mechanics/tests/test_linearize.py::test_linearize_rolling_disc_kane (see
DEFINITIONS below for every axis and sign). Three routes that share no code:

  K  SymPy's KanesMethod and Linearizer, set up as in that test (q6 dependent through the contact
     condition, u4..u6 dependent through the rolling condition), once exactly as the test (thin
     uniform disk, I = m r^2/4, J = m r^2/2, and the test's A_sol matrix for m = r = g = 1 is
     asserted) and once with symbolic I (diametral) and J (polar) moments of inertia.
  N  Newton-Euler by hand in plain SymPy matrices (no sympy.physics): the disk's momentum and
     angular momentum balance about its centre with the contact force eliminated, the rolling
     condition v_C = omega x (C - P), the kinematics q' = f(q, u) written out; the Jacobian at the
     operating point. Its A must equal route K's identically (symbolic difference simplifies to 0)
     for general m, r, g, I, J, heading and spin rate.
  C  the closed form (derived below, in lean_yaw_closed_form): the lean/yaw-rate equations
         (I + m r^2) phi'' = m g r phi + (J + m r^2) w psi',   I psi'' = -J w phi'
     (phi lean, psi' yaw rate, w spin rate) give the characteristic polynomial of the full
     8-state model  lambda^6 (lambda^2 - c),  c = (m g r I - J (J + m r^2) w^2) / (I (I + m r^2)),
     so upright straight rolling is (neutrally) stable iff  w^2 > w_c^2 = m g r I / (J (J + m r^2)),
     for the thin uniform disk w_c^2 = g / (3 r) (v_c^2 = g r / 3). The classical result: Neimark &
     Fufaev, "Dynamics of Nonholonomic Systems" (AMS Translations 33, 1972), the rolling disc;
     O'Reilly, "The dynamics of rolling disks and sliding disks", Nonlinear Dynamics 10 (1996)
     287-305; K. T. and A. J. McDonald, "The rolling motion of a disk on a horizontal plane",
     arXiv:physics/0008227, sec. 2.5 (after Routh, Advanced Rigid Dynamics, art. 244).
     The charpoly of route K's A is checked against it symbolically; mpmath's eigenvalues of K's A
     (50 digits) against it numerically at three parameter sets.

The script stops with an error when two routes disagree (symbolically, or beyond 1e-30 relative
for numbers), so every number written was obtained at least twice.
"""
import argparse
import json
import os
import sys

import mpmath
import sympy as sp
from mpmath import mp, mpf

mp.dps = 50
DIGITS = 17           # significant digits written to the JSON file (a double round-trips)
AGREE = mpf("1e-30")  # two routes must agree to this (relative); both are good to ~45 digits
# mpmath's eigenvalues of a defective matrix: a Jordan block of size k for lambda = 0 perturbs the
# computed zeros by ~ (1e-50 |A|)^(1/k); the largest block away from w_c has k = 3, so ~1e-16.
ZERO_EIG = mpf("1e-12")
CHOP = mpf("1e-35")   # a value below this (absolute) is zero to working precision
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DEFAULT_OUT = os.path.join(ROOT, "tests", "data", "reference", "rolling_disk.json")
SCRIPT = "tests/reference/rolling_disk_reference.py"

# Plain symbols for the JSON strings and routes N and C: heading q1, spin rate w = q3' at the
# operating point, lambda for the characteristic polynomial.
m, r, g, I, J = sp.symbols("m r g I J", positive=True)
w, lam, Q1 = sp.symbols("w lambda q1", real=True)
STATE = ["q1", "q2", "q3", "q4", "q5", "u1", "u2", "u3"]

DEFINITIONS = {
    "source": "SymPy's test_linearize_rolling_disc_kane (sympy/physics/mechanics/tests/test_linearize.py); "
              "the same frames, coordinates, speeds, constraints and operating point",
    "frames": "N inertial, right-handed, N.z points DOWN (gravity m g along +N.z), the ground is the plane "
              "z = 0, N.x and N.y horizontal. A = N rotated by q1 about N.z (yaw). B = A rotated by q2 about "
              "A.x (lean). C = B rotated by q3 about B.y (spin; C is fixed in the disk). The disk's axle "
              "(symmetry axis) is B.y = C.y; the disk's plane is spanned by B.x and B.z; B.x = A.x is "
              "horizontal (the heading line), B.z points from the centre to the contact point",
    "coordinates": {
        "q1": "yaw: rotation angle of A relative to N about N.z (down); q1 = 0: heading line A.x = N.x; "
              "positive q1 turns A.x from N.x towards N.y",
        "q2": "lean: rotation angle of B relative to A about A.x; upright q2 = 0. Centre minus contact "
              "point = r sin(q2) A.y - r cos(q2) A.z, so q2 > 0 moves the centre towards +A.y (the leaning "
              "side) and lowers it",
        "q3": "spin: rotation angle of the disk (C) relative to B about the axle B.y",
        "q4": "N.x coordinate of the disk CENTRE (not of the contact point: they differ by -r sin(q2) A.y)",
        "q5": "N.y coordinate of the disk centre",
        "q6": "N.z coordinate of the disk centre (dependent): q6 = -r cos(q2), the configuration "
              "constraint f_c = q6 - (centre - contact).N.z = 0 (the centre is r cos(q2) above the ground)",
    },
    "speeds": {
        "u1": "independent: omega_C.B.x, the disk's angular velocity in N along B.x; = q2' (lean rate)",
        "u2": "independent: omega_C.B.y (along the axle); = q3' + sin(q2) q1' (spin rate plus the axle "
              "component of the yaw rate)",
        "u3": "independent: omega_C.B.z; = cos(q2) q1' (the yaw rate's component in the disk plane)",
        "u4, u5, u6": "dependent: the centre's velocity in N along C.x, C.y, C.z; fixed by the rolling "
                      "condition v_P = v_centre + omega_C x (r B.z) = 0 (velocity constraints f_v = "
                      "v_P . C.x, C.y, C.z)",
        "kinematics": "q1' = u3/cos(q2), q2' = u1, q3' = u2 - tan(q2) u3, (q4', q5', q6') = the centre's "
                      "velocity in N; rolling gives v_centre = omega_C x (-r B.z) = r u1 B.y - r u2 B.x",
    },
    "independent": "coordinates q1..q5 (q6 dependent), speeds u1, u2, u3 (u4..u6 dependent); the "
                   "linearized state is x = [q1, q2, q3, q4, q5, u1, u2, u3], x' = A x (no inputs, B empty)",
    "body": "thin disk, mass m, radius r, inertia about the centre diag(I, J, I) in C (I diametral about "
            "C.x and C.z, J polar about the axle C.y); the test: I = m r^2/4, J = m r^2/2. Gravity m g N.z "
            "at the centre",
    "operating_point": "upright straight rolling: q2 = 0, q1' = 0, spin rate q3' = w (the symbol w here is "
                       "the test's Derivative(q3(t), t)), u1 = u3 = 0, u2 = w, centre velocity -r w A.x "
                       "(so w > 0 rolls the disk along -A.x = -(cos q1, sin q1, 0) at speed v = r w); "
                       "q1, q3, q4, q5 arbitrary (A depends on q1 only in the rows of q4', q5', and on "
                       "q3, q4, q5 not at all); the test's op point dicts (general q2, q1', q3') are used "
                       "and then q2 = 0, q1' = 0 substituted, as the test does",
}


def agree(name, a, b, scale=None):
    a, b = mp.mpmathify(a), mp.mpmathify(b)
    s = max(abs(a), abs(b), mpf(1) if scale is None else mpf(scale))
    if abs(a - b) > AGREE * s:
        sys.exit("rolling_disk_reference: routes disagree on %s: %s vs %s" % (name, mp.nstr(a, 30), mp.nstr(b, 30)))


def same(name, X, Y):
    if sp.simplify(sp.Matrix(X) - sp.Matrix(Y)) != sp.zeros(*sp.Matrix(X).shape):
        sys.exit("rolling_disk_reference: symbolic routes disagree on %s:\n%s\n%s" % (name, X, Y))


# ---------------------------------------------------------------------------------------------
# Route K: SymPy's KanesMethod, as in test_linearize_rolling_disc_kane.

def kane_A(Idiam, Jpolar):
    """The test's disk with inertia diag(Idiam, Jpolar, Idiam); returns (A at q2 = q1' = 0 in the
    plain symbols q1, w, and A with the test's own dynamicsymbols, for the test's assertion)."""
    import sympy.physics.mechanics as me
    from sympy import cos, sin
    t = sp.Symbol("t")
    q1, q2, q3, q4, q5, q6 = q = me.dynamicsymbols("q1:7")
    q1d, q2d, q3d, q4d, q5d, q6d = qd = [qi.diff(t) for qi in q]
    u1, u2, u3, u4, u5, u6 = u = me.dynamicsymbols("u1:7")
    u1d, u2d, u3d, u4d, u5d, u6d = [ui.diff(t) for ui in u]
    N = me.ReferenceFrame("N")
    NO = me.Point("NO")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = A.orientnew("B", "Axis", [q2, A.x])
    C = B.orientnew("C", "Axis", [q3, B.y])
    CO = NO.locatenew("CO", q4 * N.x + q5 * N.y + q6 * N.z)
    w_c_n_qd = C.ang_vel_in(N)
    w_b_n_qd = B.ang_vel_in(N)
    C.set_ang_vel(N, u1 * B.x + u2 * B.y + u3 * B.z)
    v_co_n_qd = CO.pos_from(NO).dt(N)
    CO.set_vel(N, u4 * C.x + u5 * C.y + u6 * C.z)
    P = CO.locatenew("P", r * B.z)
    P.v2pt_theory(CO, N, C)
    f_c = sp.Matrix([q6 - me.dot(CO.pos_from(P), N.z)])
    f_v = sp.Matrix([me.dot(P.vel(N), uv) for uv in C])
    kindiffs = sp.Matrix([me.dot(w_c_n_qd - C.ang_vel_in(N), uv) for uv in B]
                         + [me.dot(v_co_n_qd - CO.vel(N), uv) for uv in N])
    qdots = sp.solve(kindiffs, qd)
    B.set_ang_vel(N, w_b_n_qd.subs(qdots))
    C.set_ang_acc(N, C.ang_vel_in(N).dt(B) + me.cross(B.ang_vel_in(N), C.ang_vel_in(N)))
    disc = me.RigidBody("Disc", CO, C, m, (me.inertia(C, Idiam, Jpolar, Idiam), CO))
    KM = me.KanesMethod(N, [q1, q2, q3, q4, q5], [u1, u2, u3], kd_eqs=kindiffs, q_dependent=[q6],
                        configuration_constraints=f_c, u_dependent=[u4, u5, u6], velocity_constraints=f_v)
    KM.kanes_equations([disc], [(CO, m * g * A.z)])
    lin = KM.to_linearizer()
    # The test's operating point (steady turning at general lean; u1d there is the uniform disk's,
    # but it is multiplied by sin(q2) or q1' terms that vanish at the upright point used below).
    q_op = {q6: -r * cos(q2)}
    u_op = {u1: 0, u2: sin(q2) * q1d + q3d, u3: cos(q2) * q1d, u4: -r * (sin(q2) * q1d + q3d) * cos(q3),
            u5: 0, u6: -r * (sin(q2) * q1d + q3d) * sin(q3)}
    qd_op = {q2d: 0, q4d: -r * (sin(q2) * q1d + q3d) * cos(q1), q5d: -r * (sin(q2) * q1d + q3d) * sin(q1), q6d: 0}
    ud_op = {u1d: 4 * g * sin(q2) / (5 * r) + sin(2 * q2) * q1d**2 / 2 + 6 * cos(q2) * q1d * q3d / 5,
             u2d: 0, u3d: 0, u4d: r * (sin(q2) * sin(q3) * q1d * q3d + sin(q3) * q3d**2),
             u5d: r * (4 * g * sin(q2) / (5 * r) + sin(2 * q2) * q1d**2 / 2 + 6 * cos(q2) * q1d * q3d / 5),
             u6d: -r * (sin(q2) * cos(q3) * q1d * q3d + cos(q3) * q3d**2)}
    Am, Bm = lin.linearize(op_point=[q_op, u_op, qd_op, ud_op], A_and_B=True, simplify=True)
    upright = sp.simplify(Am.subs({q1d: 0, q2: 0}))
    plain = upright.subs(q3d, w).subs(q1, Q1)
    return plain, upright, (q1, q3d, q1d, q2), Bm


def route_K():
    # Exactly the test: thin uniform disk, then its A_sol for m = r = g = 1 and the zero spectrum.
    A_test, A_dyn, (q1, q3d, q1d, q2), Bm = kane_A(m * r**2 / 4, m * r**2 / 2)
    from sympy import cos, sin
    A_sol = sp.Matrix([[0, 0, 0, 0, 0, 0, 0, 1],
                       [0, 0, 0, 0, 0, 1, 0, 0],
                       [0, 0, 0, 0, 0, 0, 1, 0],
                       [sin(q1) * q3d, 0, 0, 0, 0, -sin(q1), -cos(q1), 0],
                       [-cos(q1) * q3d, 0, 0, 0, 0, cos(q1), -sin(q1), 0],
                       [0, sp.Rational(4, 5), 0, 0, 0, 0, 0, 6 * q3d / 5],
                       [0, 0, 0, 0, 0, 0, 0, 0],
                       [0, 0, 0, 0, 0, -2 * q3d, 0, 0]])
    unit = {m: 1, r: 1, g: 1}
    if A_dyn.subs(unit) != A_sol:
        sys.exit("rolling_disk_reference: KanesMethod does not reproduce the test's A_sol:\n%s" % A_dyn.subs(unit))
    if Bm.shape[1] != 0:
        sys.exit("rolling_disk_reference: the disk has no inputs, B should be empty")
    if sp.sympify(A_sol.subs(q3d, 1 / sp.sqrt(3))).eigenvals() != {0: 8}:
        sys.exit("rolling_disk_reference: the eigenvalues at w = 1/sqrt(3) are not all zero")
    # General inertia.
    A_gen = kane_A(I, J)[0]
    same("route K: general inertia at the uniform disk's values vs the test's set-up",
         A_gen.subs({I: m * r**2 / 4, J: m * r**2 / 2}), A_test)
    return A_test, A_gen


# ---------------------------------------------------------------------------------------------
# Route N: Newton-Euler by hand (plain matrices, B-frame components throughout).

def cross(a, b):
    return sp.Matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def route_N():
    q1, q2, q3, q4, q5, u1, u2, u3 = x = sp.symbols("q1 q2 q3 q4 q5 u1 u2 u3", real=True)
    ud = sp.Matrix(sp.symbols("ud1:4"))
    u = sp.Matrix([u1, u2, u3])                       # omega_C in B components
    Om = sp.Matrix([u1, sp.tan(q2) * u3, u3])         # omega_B = omega_C - q3' B.y
    rho = sp.Matrix([0, 0, -r])                       # centre minus contact point, constant in B
    n3 = sp.Matrix([0, sp.sin(q2), sp.cos(q2)])       # N.z (down) in B: A.z = sin q2 B.y + cos q2 B.z
    Iten = sp.diag(I, J, I)                           # axisymmetric: constant in B although C spins
    v = cross(u, rho)                                 # rolling: v_centre = omega x (centre - P)
    a = cross(ud, rho) + cross(Om, v)                 # d/dt in N of B components
    F = m * a - m * g * n3                            # contact force on the disk
    Hdot = Iten * ud + cross(Om, Iten * u)
    eqs = Hdot - cross(-rho, F)                       # moment of F about the centre, arm P - centre
    sol = sp.solve(list(eqs), list(ud), dict=True)[0]
    R = sp.Matrix([[sp.cos(q1), -sp.sin(q1), 0], [sp.sin(q1), sp.cos(q1), 0], [0, 0, 1]]) * \
        sp.Matrix([[1, 0, 0], [0, sp.cos(q2), -sp.sin(q2)], [0, sp.sin(q2), sp.cos(q2)]])
    vN = R * v
    f = sp.Matrix([u3 / sp.cos(q2), u1, u2 - sp.tan(q2) * u3, vN[0], vN[1],
                   sol[ud[0]], sol[ud[1]], sol[ud[2]]])
    op = {q2: 0, u1: 0, u2: w, u3: 0, q1: Q1}
    Jac = f.jacobian(sp.Matrix(x)).subs(op)
    # The operating point is a solution: f's accelerations vanish there (steady straight rolling).
    same("route N: steady straight rolling is a solution", f[5:, 0].subs(op), sp.zeros(3, 1))
    return sp.simplify(Jac)


# ---------------------------------------------------------------------------------------------
# Route C: the closed form.

def lean_yaw_closed_form():
    """Characteristic polynomial of the full model from the lean/yaw-rate equations.

    Linearized about upright rolling at spin w (lean phi = q2, yaw rate psi' = u3, lean rate u1):
    the yaw equation is the vertical angular momentum balance about the centre: the contact force
    acts at the point right below the centre, so its moment has no vertical component, and the
    axle tilted by phi carries J w phi of vertical angular momentum: I psi'' + J w phi' = 0.
    The lean equation is the moment balance about the (moving) contact point along the heading:
    (I + m r^2) phi'' = m g r phi + (J w + m r^2 w) psi', gravity toppling, the gyroscopic moment
    of the spin and the centripetal force m v psi' (v = r w) at height r both righting a disk that
    steers into its lean. With s = lambda: lambda^2 (I + m r^2) = m g r + (J + m r^2) w (-J w / I),
    i.e. lambda^2 = c; the other five states add lambda^5 (q1, q3, q4, q5 ignorable, u2 constant)
    and the lean/yaw triple one more lambda (the family of steady turns)."""
    c = (m * g * r * I - J * (J + m * r**2) * w**2) / (I * (I + m * r**2))
    return c, lam**6 * (lam**2 - c), m * g * r * I / (J * (J + m * r**2))


def params(mm, rr, gg, ii, jj):
    return {m: mm, r: rr, g: gg, I: ii, J: jj}


def numeric_A(A, subs, wv):
    """A at 50 digits (mpmath matrix), heading q1 = 0."""
    At = A.subs(subs).subs({Q1: 0})
    return mp.matrix([[mpf(sp.N(At[i, j].subs(w, wv), 60)) for j in range(8)] for i in range(8)])


def lean_pair(c_val):
    """The lean-mode eigenvalues +-sqrt(c), ordered (re, im) ascending."""
    s = mp.sqrt(mp.mpc(c_val))
    return sorted([-s, s], key=lambda z: (z.real, z.imag))


def check_spectrum(name, A, subs, wv):
    """mpmath's eigenvalues of route K's A against route C; returns the lean pair."""
    c_sym, _, _ = lean_yaw_closed_form()
    c_val = mpf(sp.N(c_sym.subs(subs).subs(w, wv), 60))
    E = mp.eig(numeric_A(A, subs, wv), left=False, right=False)
    E = sorted(E, key=lambda z: -abs(z))
    pair = lean_pair(c_val)
    num = sorted(E[:2], key=lambda z: (mp.re(z), mp.im(z)))
    scale = max(abs(c_val), 1)
    for k in range(2):
        agree("%s lean eigenvalue %d (re)" % (name, k), mp.re(num[k]), mp.re(pair[k]), scale)
        agree("%s lean eigenvalue %d (im)" % (name, k), mp.im(num[k]), mp.im(pair[k]), scale)
    small = max(abs(z) for z in E[2:])
    if small > ZERO_EIG:
        sys.exit("rolling_disk_reference: %s: a zero eigenvalue computed as %s" % (name, mp.nstr(small, 5)))
    return c_val, pair


def cplx(z):
    z = mp.mpc(z)
    return {"re": z.real, "im": z.imag}


def sstr(e):
    return sp.sstr(sp.simplify(e))


# ---------------------------------------------------------------------------------------------

def test_case(A_test):
    """Part 1: the SymPy test's disk (m = r = g = 1), A as a function of w, spin rates 0.5,
    1/sqrt(3), 1, 2."""
    unit = params(1, 1, 1, sp.Rational(1, 4), sp.Rational(1, 2))
    A1 = A_test.subs({m: 1, r: 1, g: 1})
    rates = [("0.5", sp.Rational(1, 2)), ("1/sqrt(3)", 1 / sp.sqrt(3)), ("1", sp.Integer(1)), ("2", sp.Integer(2))]
    at = {}
    for label, wv in rates:
        Ae = A1.subs(w, wv)
        ev = sp.Matrix(Ae.subs(Q1, 0)).eigenvals()
        exact = sorted(((k, v) for k, v in ev.items()), key=lambda kv: sp.default_sort_key(kv[0]))
        entry = {"w": mpf(sp.N(wv, 60)),
                 "A_at_q1_0": [[mpf(sp.N(Ae[i, j].subs(Q1, 0), 60)) for j in range(8)] for i in range(8)],
                 "eigenvalues_exact": {sp.sstr(k): v for k, v in exact}}
        if wv == 1 / sp.sqrt(3):
            entry["eigenvalues"] = [cplx(0)] * 8
            entry["note"] = "all 8 zero, checked symbolically (eigenvals() == {0: 8}, as the test asserts); " \
                            "Jordan blocks 5, 2, 1 (rank A = 5)"
        else:
            _, pair = check_spectrum("test disk w=%s" % label, A_test, unit, wv)
            entry["eigenvalues"] = [cplx(0)] * 6 + [cplx(z) for z in pair]
        at["w = " + label] = entry
    return {
        "what": "SymPy's test disk: m = r = g = 1, I = 1/4, J = 1/2; A (8 x 8, state x = [q1, q2, q3, q4, q5, "
                "u1, u2, u3]) as a function of the spin rate w and the heading q1, equal to the test's A_sol "
                "(asserted) with Derivative(q3(t), t) written w",
        "A_exact": [[sp.sstr(A1[i, j]) for j in range(8)] for i in range(8)],
        "lean_eigenvalues_squared": sstr(lean_yaw_closed_form()[0].subs(unit)),
        "critical_w": "1/sqrt(3)",
        "at": at,
    }


def disk_case(name, A_gen, subs, rates, note):
    c_sym, _, wc2_sym = lean_yaw_closed_form()
    wc2 = mpf(sp.N(wc2_sym.subs(subs), 60))
    rr = mpf(sp.N(subs[r], 60))
    wc = mp.sqrt(wc2)
    # Route C's w_c against route K's A: the lean pair vanishes there, so c(w_c) from K's charpoly.
    Ak = A_gen.subs(subs).subs(Q1, 0)
    cpK = sp.Poly(sp.simplify(Ak.charpoly(lam).as_expr(lam)), lam).all_coeffs()  # lambda^8 - c lambda^6
    cK = sp.lambdify(w, -cpK[2], modules="mpmath")
    agree("%s: K's lean coefficient at w_c" % name, cK(wc), 0, abs(cK(0)))
    out = {"what": note,
           "parameters": {str(k): mpf(sp.N(v, 60)) for k, v in subs.items()},
           "critical_w_rad_per_s": wc, "critical_w2_per_s2": wc2, "critical_speed_m_per_s": wc * rr,
           "lean_eigenvalues": []}
    for wv in rates:
        if wv == "critical":
            out["lean_eigenvalues"].append({"w": wc, "lambda": [cplx(0), cplx(0)],
                                            "note": "the lean pair is a double zero at w_c"})
            continue
        wv = mpf(wv)
        c_val, pair = check_spectrum("%s w=%s" % (name, mp.nstr(wv, 5)), A_gen, subs, sp.Float(wv, 60))
        agree("%s: K's lean coefficient at w=%s" % (name, mp.nstr(wv, 5)), cK(wv), c_val)
        out["lean_eigenvalues"].append({"w": wv, "lambda_squared": c_val, "lambda": [cplx(z) for z in pair]})
    return out


def zero_spectrum(A_gen):
    """Part 3: count and structure of the zero eigenvalues (exact)."""
    unit = params(1, 1, 1, sp.Rational(1, 4), sp.Rational(1, 2))
    blocks = {}
    for label, wv in (("w = 1", 1), ("w = 1/sqrt(3)", 1 / sp.sqrt(3))):
        Ae = A_gen.subs(unit).subs({Q1: 0, w: wv})
        _, Jf = Ae.jordan_form()
        sizes, k = [], 0
        while k < 8:
            s = 1
            while k + s < 8 and Jf[k + s - 1, k + s] == 1:
                s += 1
            if Jf[k, k] == 0:
                sizes.append(s)
            k += s
        blocks[label] = {"rank_A": Ae.rank(), "zero_jordan_blocks": sorted(sizes, reverse=True)}
    rank_gen = A_gen.rank(simplify=True)
    if rank_gen != 5 or blocks["w = 1"]["zero_jordan_blocks"] != [3, 2, 1]:
        sys.exit("rolling_disk_reference: unexpected zero structure %s, rank %d" % (blocks, rank_gen))
    return {
        "count": "6 of the 8 eigenvalues are exactly zero for every w with w^2 != w_c^2 (charpoly "
                 "lambda^6 (lambda^2 - c), symbolic); all 8 at w^2 = w_c^2",
        "why": [
            "q1 (heading), q3 (spin angle), q4, q5 (the centre's horizontal position) are ignorable: no "
            "equation depends on q3, q4, q5 (their columns of A are zero) and q1 enters only the rows of "
            "q4', q5' (the direction of travel): 4 zeros",
            "u2 (spin rate): its row of A is zero, the spin rate is constant to first order: 1 zero",
            "the lean/yaw-rate triple (q2, u1, u3) has charpoly lambda (lambda^2 - c): a neighbouring steady "
            "turn (u1 = 0, lean and yaw rate in the ratio m g r q2 + (J + m r^2) w u3 = 0) is again a "
            "steady motion: 1 zero",
        ],
        "structure": "rank A = %d for general parameters, so only 3 eigenvectors for the zero eigenvalue: "
                     "Jordan chains steady turn -> heading q1 -> lateral position (3), spin-rate change u2 -> "
                     "(q3, position along the track) (2), and one more combination of q3, q4, q5 (1). A "
                     "numerical eigensolver returns these zeros only to ~eps^(1/3) (~1e-5 in doubles; "
                     "at w_c the block of 5 gives ~eps^(1/5) ~ 1e-3)" % rank_gen,
        "jordan_test_disk": blocks,
    }


def build():
    A_test, A_gen = route_K()
    A_N = route_N()
    same("A: route K (KanesMethod) vs route N (Newton-Euler by hand), general m, r, g, I, J, q1, w", A_gen, A_N)
    c, cp, wc2 = lean_yaw_closed_form()
    same("charpoly: route K vs route C", [A_gen.charpoly(lam).as_expr(lam)], [cp])
    same("thin uniform disk: w_c^2 = g/(3 r)", [wc2.subs({I: m * r**2 / 4, J: m * r**2 / 2})], [g / (3 * r)])
    same("thin hoop: w_c^2 = g/(4 r)", [wc2.subs({I: m * r**2 / 2, J: m * r**2})], [g / (4 * r)])
    R3, G9 = sp.Rational(3, 10), sp.Rational(981, 100)
    uniform = params(2, R3, G9, 2 * R3**2 / 4, 2 * R3**2 / 2)
    nonuni = params(2, R3, G9, sp.Rational(4, 10) * 2 * R3**2, sp.Rational(7, 10) * 2 * R3**2)
    return {
        "definitions": DEFINITIONS,
        "routes": "K (SymPy KanesMethod + Linearizer as in the test; the test's A_sol asserted), N (Newton-Euler "
                  "by hand in plain SymPy matrices; A identical to K's symbolically for general m, r, g, I, J, "
                  "q1, w), C (closed form from the lean/yaw-rate equations; K's charpoly equals "
                  "lambda^6 (lambda^2 - c) symbolically, mpmath's eigenvalues of K's A agree to 1e-30)",
        "general_A": {
            "what": "A (x' = A x, x = [q1, q2, q3, q4, q5, u1, u2, u3]) at upright rolling with spin rate w and "
                    "heading q1, any m, r, g, I (diametral), J (polar)",
            "A_exact": [[sp.sstr(A_gen[i, j]) for j in range(8)] for i in range(8)],
            "charpoly": sp.sstr(cp) + "   with c = " + sp.sstr(c),
            "lean_eigenvalues": "lambda = +-sqrt(c), c = (m g r I - J (J + m r^2) w^2) / (I (I + m r^2)); real "
                                "pair (unstable) for w^2 < w_c^2, imaginary pair (neutral) above",
            "critical_w2": sp.sstr(wc2) + "  (thin uniform disk I = m r^2/4, J = m r^2/2: g/(3 r), "
                           "critical forward speed v_c = r w_c = sqrt(g r / 3); thin hoop I = m r^2/2, J = m r^2: g/(4 r), both checked symbolically)",
            "sources": "Neimark & Fufaev, Dynamics of Nonholonomic Systems (AMS, 1972); O'Reilly, Nonlinear "
                       "Dynamics 10 (1996) 287-305; McDonald & McDonald, arXiv:physics/0008227 sec. 2.5; Routh, "
                       "Advanced Rigid Dynamics art. 244. The general-inertia form was derived here (route C) "
                       "and checked against routes K and N, not copied from these",
        },
        "sympy_test_disk": test_case(A_test),
        "uniform_disk_m2_r0.3": disk_case(
            "uniform", A_gen, uniform, ["0", "2", "3", "critical", "4", "10"],
            "thin uniform disk m = 2 kg, r = 0.3 m, g = 9.81 m/s^2, I = m r^2/4, J = m r^2/2; w_c^2 = g/(3 r) = 10.9"),
        "nonuniform_disk_m2_r0.3": disk_case(
            "non-uniform", A_gen, nonuni, ["0", "2", "critical", "4", "10"],
            "axisymmetric disk m = 2 kg, r = 0.3 m, g = 9.81 m/s^2, I = 0.4 m r^2 (diametral), J = 0.7 m r^2 "
            "(polar); w_c^2 = g I / (r J (J/(m r^2) + 1)) = g 0.4 / (0.3 * 0.7 * 1.7)"),
        "zero_eigenvalues": zero_spectrum(A_gen),
    }


def fmt(v):
    if isinstance(v, bool):
        return None
    if isinstance(v, int) or (isinstance(v, sp.Basic) and v.is_Integer):
        return str(int(v))                            # counts, ranks, multiplicities
    if isinstance(v, sp.Basic) and v.is_number:
        v = mpf(sp.N(v, 60))
    if isinstance(v, (mp.mpf, int)) and not isinstance(v, bool):
        v = mpf(v)
        if abs(v) < CHOP:
            return "0"
        return mp.nstr(v, DIGITS, strip_zeros=True, min_fixed=-4, max_fixed=8)
    return None


def dump(obj, indent=0):
    pad, inner = "  " * indent, "  " * (indent + 1)
    if isinstance(obj, dict):
        if obj and len(obj) <= 2 and all(fmt(v) is not None for v in obj.values()):
            return "{" + ", ".join(json.dumps(str(k)) + ": " + fmt(v) for k, v in obj.items()) + "}"
        items = [inner + json.dumps(str(k)) + ": " + dump(v, indent + 1) for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, (list, tuple)):
        if all(fmt(v) is not None for v in obj):
            return "[" + ", ".join(fmt(v) for v in obj) + "]"
        if all(isinstance(v, str) for v in obj) and sum(len(v) for v in obj) < 120:
            return "[" + ", ".join(json.dumps(v) for v in obj) + "]"
        if all(isinstance(v, dict) and len(v) <= 2 and all(fmt(x) is not None for x in v.values()) for v in obj):
            return "[" + ", ".join(dump(v) for v in obj) + "]"
        return "[\n" + ",\n".join(inner + dump(v, indent + 1) for v in obj) + "\n" + pad + "]"
    f = fmt(obj)
    return f if f is not None else json.dumps(obj)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=DEFAULT_OUT)
    ap.add_argument("--check", action="store_true", help="compare with the file instead of writing it")
    args = ap.parse_args()
    data = {
        "provenance": {
            "script": SCRIPT,
            "command": "python3 " + SCRIPT,
            "tools": "SymPy %s, mpmath %s; no mbsgen code" % (sp.__version__, mpmath.__version__),
            "precision": "exact (SymPy) where written as strings; numbers by mpmath at 50 digits, written "
                         "with %d significant digits, agreeing between two independent routes to 1e-30 "
                         "relative; values below 1e-35 written as 0" % DIGITS,
            "units": "SI: rad, m, kg, s; the test disk is dimensionless (m = r = g = 1)",
        },
    }
    data.update(build())
    text = dump(data) + "\n"
    if args.check:
        with open(args.out) as f:
            if f.read() != text:
                sys.exit("rolling_disk_reference: %s differs from what the script computes" % args.out)
        print("%s: up to date" % args.out)
        return
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    tmp = args.out + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, args.out)
    print("wrote %s" % args.out)


if __name__ == "__main__":
    main()
