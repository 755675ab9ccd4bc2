#!/usr/bin/env python3
"""Independent references for the closed-loop models of issue 15 (models/linkages/*.yaml).

Run `python3 tests/reference/loops_reference.py` from the repository root: it recomputes every
number and writes tests/data/reference/loops.json (deterministic; `--check` compares with the
file instead of writing it, `--out PATH` writes elsewhere). Needs only SymPy and mpmath (Debian
python3-sympy); no mbsgen code or output is used.

Every mechanism is computed by routes that share no code:

  A  tree coordinates and multipliers (SymPy symbolic derivatives, evaluated with mpmath at
     50 digits): the constrained statics  grad V(y) = Phi_y(y)^T lambda,  Phi(y) = 0  solved by
     Newton's method for (y, lambda); the null-space map T = [E; -Phi_yd^-1 Phi_yi] (rows in the
     tree's order); the reduced  M = T^T M_tree T  and  K = T^T (H_V - sum_k lambda_k H_Phi_k) T;
     "without the geometric stiffness"  K_wrong = T^T H_V T.  Phi = r_B - r_A (in-plane
     components) for a revolute between [A, B], Phi = |r_B - r_A| - L for a distance, so lambda
     is the reaction force on the body of marker B (world frame) resp. the rod's tension-signed
     multiplier (the force on B's body is lambda (r_B - r_A)/|r_B - r_A|).
  B  one minimal coordinate (the crank angle): the loop closed in closed form, V(theta), the
     kinetic energy T = 1/2 m(theta) theta_dot^2 from each body's centre and angle, equilibrium
     V'(theta0) = 0, omega^2 = V''(theta0)/m(theta0) (mpmath, numerical derivatives at 50 digits).
  C  reactions by hand: Newton-Euler statics of each body (force and moment balance), a linear
     system in the joint forces; the one equation left over is the equilibrium condition and
     its residual is checked.
  S  (pendulum) SymPy's own Linearizer on the non-minimal pendulum (KanesMethod with a
     configuration and a velocity constraint), as in sympy/physics/mechanics/tests/test_linearize.py.
  L  (ladder) minimal coordinates of the parallelogram chain (one absolute angle per level).

The script stops with an error when two routes disagree beyond 1e-30 (relative to the size of
the quantity), so every number written was obtained at least twice.
"""
import argparse
import json
import os
import sys

import mpmath
import sympy as sp
from mpmath import mp, mpf

mp.dps = 50
DIGITS = 20          # significant digits written to the JSON file
AGREE = mpf("1e-30")  # two routes must agree to this (relative); both are good to ~45 digits
CHOP = mpf("1e-35")  # a value below this (absolute, in SI units) is zero to working precision
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DEFAULT_OUT = os.path.join(ROOT, "tests", "data", "reference", "loops.json")
SCRIPT = "tests/reference/loops_reference.py"


def Q(s):
    """An exact rational from a decimal string (the model files' literals are exact too)."""
    return sp.Rational(s)


def agree(name, a, b, scale=None):
    a, b = mpf(a), mpf(b)
    s = max(abs(a), abs(b), mpf(1) if scale is None else mpf(scale))
    if abs(a - b) > AGREE * s:
        sys.exit("loops_reference: routes disagree on %s: %s vs %s" % (name, mp.nstr(a, 30), mp.nstr(b, 30)))


# ---------------------------------------------------------------------------------------------
# Route A: a planar tree with constraints, symbolic in the tree coordinates.

class PlanarTree:
    """Bodies (mass, I_zz about the centre, centre (x, y), absolute angle) as SymPy expressions
    in the tree coordinates y; potential V(y); constraint equations Phi(y) (list)."""

    def __init__(self, coords):
        self.y = list(coords)
        self.bodies = []
        self.V = sp.Integer(0)
        self.Phi = []

    def body(self, name, mass, izz, centre, angle):
        self.bodies.append((name, sp.sympify(mass), sp.sympify(izz), [sp.sympify(c) for c in centre],
                            sp.sympify(angle)))
        self.V += sp.sympify(mass) * G * sp.sympify(centre[1])

    def build(self):
        y, n = self.y, len(self.y)
        M = sp.zeros(n, n)
        for _, m, izz, c, ang in self.bodies:
            Jc = sp.Matrix([[sp.diff(c[i], q) for q in y] for i in range(2)])
            Jw = sp.Matrix([[sp.diff(ang, q) for q in y]])
            M += m * Jc.T * Jc + izz * Jw.T * Jw
        grad = [sp.diff(self.V, q) for q in y]
        hess = [[sp.diff(gi, q) for q in y] for gi in grad]
        jac = [[sp.diff(p, q) for q in y] for p in self.Phi]
        hphi = [[[sp.diff(row[j], q) for q in y] for j in range(n)] for row in jac]
        f = lambda e: sp.lambdify([y], e, modules="mpmath")
        self.f_M = f([[M[i, j] for j in range(n)] for i in range(n)])
        self.f_grad, self.f_hess = f(grad), f(hess)
        self.f_phi, self.f_jac, self.f_hphi = f(self.Phi), f(jac), f(hphi)
        return self

    def statics(self, y_guess, lam_guess=None):
        """Newton on (grad V - Phi_y^T lam, Phi) = 0 for (y, lam)."""
        n, m = len(self.y), len(self.Phi)
        y = [mpf(v) for v in y_guess]
        lam = self.multipliers(y) if lam_guess is None else [mpf(v) for v in lam_guess]
        for _ in range(100):
            g, H, J, Hp, phi = self.f_grad(y), self.f_hess(y), self.f_jac(y), self.f_hphi(y), self.f_phi(y)
            r = [g[i] - sum(J[k][i] * lam[k] for k in range(m)) for i in range(n)] + list(phi)
            A = mp.zeros(n + m, n + m)
            for i in range(n):
                for j in range(n):
                    A[i, j] = H[i][j] - sum(lam[k] * Hp[k][i][j] for k in range(m))
                for k in range(m):
                    A[i, n + k] = -J[k][i]
                    A[n + k, i] = J[k][i]
            d = mp.lu_solve(A, mp.matrix(r))
            y = [y[i] - d[i] for i in range(n)]
            lam = [lam[k] - d[n + k] for k in range(m)]
            if mp.norm(d) < mpf(10) ** (-mp.dps + 5):
                return y, lam
        sys.exit("loops_reference: Newton on the constrained statics did not converge")

    def multipliers(self, y):
        """lam from grad V = Phi_y^T lam by least squares (exact when y is an equilibrium)."""
        J, g = mp.matrix(self.f_jac(y)), mp.matrix(self.f_grad(y))
        return list(mp.lu_solve(J * J.T, J * g))

    def reduce(self, y, lam, independent):
        """M, K, K_wrong in the independent coordinates (indices into y), and T."""
        n, m = len(self.y), len(self.Phi)
        dep = [i for i in range(n) if i not in independent]
        J = mp.matrix(self.f_jac(y))
        Jd = mp.matrix([[J[k, j] for j in dep] for k in range(m)])
        Ji = mp.matrix([[J[k, j] for j in independent] for k in range(m)])
        X = -(mp.inverse(Jd) * Ji)
        T = mp.zeros(n, len(independent))
        for c, i in enumerate(independent):
            T[i, c] = 1
        for r, i in enumerate(dep):
            for c in range(len(independent)):
                T[i, c] = X[r, c]
        H, Hp = mp.matrix(self.f_hess(y)), self.f_hphi(y)
        Hg = mp.matrix(H)
        for k in range(m):
            Hg -= lam[k] * mp.matrix(Hp[k])
        Mt = mp.matrix(self.f_M(y))
        return T.T * Mt * T, T.T * Hg * T, T.T * H * T, T


def eigen_omegas(Mr, Kr):
    """omega^2 of K x = omega^2 M x (symmetric, M positive definite), ascending."""
    L = mp.cholesky(Mr)
    Li = mp.inverse(L)
    E, _ = mp.eigsy(Li * Kr * Li.T)
    return sorted(E[i] for i in range(E.rows))


def freq(w2):
    w = mp.sqrt(w2)
    return {"omega2_per_s2": w2, "omega_rad_per_s": w, "f_Hz": w / (2 * mp.pi)}


def spring_V(k, L0, P, Q_):
    return k / 2 * (sp.sqrt((Q_[0] - P[0]) ** 2 + (Q_[1] - P[1]) ** 2) - L0) ** 2


def cross(r, f):
    return r[0] * f[1] - r[1] * f[0]


def solve_statics(rows, rhs, unknowns, drop):
    """Solve the Newton-Euler rows (each a dict unknown -> coefficient) except row `drop`, and
    return the solution and the residual of the dropped row (the equilibrium condition)."""
    keep = [i for i in range(len(rows)) if i != drop]
    A = mp.matrix([[rows[i].get(u, 0) for u in unknowns] for i in keep])
    x = mp.lu_solve(A, mp.matrix([rhs[i] for i in keep]))
    sol = {u: x[j] for j, u in enumerate(unknowns)}
    res = sum(rows[drop].get(u, 0) * sol[u] for u in unknowns) - rhs[drop]
    return sol, res


G = Q("9.81")
g_mp = mpf("9.81")


# ---------------------------------------------------------------------------------------------
# 1. Parallelogram four-bar (models/linkages/four_bar_parallelogram.yaml).

def parallelogram():
    l, d = Q("0.3"), Q("0.5")
    m1, m2, m3 = Q("0.2"), Q("0.5"), Q("0.3")
    th1, th2, th3 = sp.symbols("th1 th2 th3")
    s = PlanarTree([th1, th2, th3])
    A = (l * sp.cos(th1), l * sp.sin(th1))
    s.body("crank", m1, m1 * l**2 / 12, (A[0] / 2, A[1] / 2), th1)
    s.body("coupler", m2, m2 * d**2 / 12, (A[0] + d / 2 * sp.cos(th1 + th2), A[1] + d / 2 * sp.sin(th1 + th2)),
           th1 + th2)
    s.body("rocker", m3, m3 * l**2 / 12, (d + l / 2 * sp.cos(th3), l / 2 * sp.sin(th3)), th3)
    B_coupler = (A[0] + d * sp.cos(th1 + th2), A[1] + d * sp.sin(th1 + th2))
    B_rocker = (d + l * sp.cos(th3), l * sp.sin(th3))
    s.Phi = [B_rocker[0] - B_coupler[0], B_rocker[1] - B_coupler[1]]  # r_B - r_A, B on the rocker
    s.build()
    y0 = [-mp.pi / 2, mp.pi / 2, -mp.pi / 2]
    lam = s.multipliers(y0)
    g = s.f_grad(y0)
    J = s.f_jac(y0)
    res = max(abs(g[i] - sum(J[k][i] * lam[k] for k in range(2))) for i in range(3))
    agree("parallelogram statics residual", res, 0)
    Mr, Kr, Kw, T = s.reduce(y0, lam, [0])
    w2 = Kr[0, 0] / Mr[0, 0]
    # Closed form: crank and rocker turn by theta, the coupler translates on a circle of radius l:
    # T = 1/2 (m1 l^2/3 + m3 l^2/3 + m2 l^2) theta_dot^2, V = -(m1/2 + m2 + m3/2) g l cos(theta).
    mm1, mm2, mm3, ll = mpf("0.2"), mpf("0.5"), mpf("0.3"), mpf("0.3")
    closed = 3 * g_mp * (mm1 + 2 * mm2 + mm3) / (2 * ll * (mm1 + 3 * mm2 + mm3))
    agree("parallelogram omega^2", w2, closed)
    # Route C: the rocker (moments about D) and the coupler (moments about A) carry the pin.
    # The pin's force F on the rocker at B: rocker hangs vertically, so F_x l = 0; the coupler
    # (horizontal, weight at its middle): F_y = -m2 g / 2.
    agree("parallelogram pin x", lam[0], 0)
    agree("parallelogram pin y", lam[1], -mm2 * g_mp / 2)
    return {
        "model": "models/linkages/four_bar_parallelogram.yaml",
        "what": "parallelogram four-bar hanging down (crank = rocker = 0.3 m, ground = coupler = 0.5 m, "
                "uniform bars 0.2, 0.5, 0.3 kg, g = 9.81); the coupler translates without turning",
        "routes": "A (tree coordinates, multipliers) and the closed form "
                  "omega^2 = 3 g (m1 + 2 m2 + m3) / (2 l (m1 + 3 m2 + m3))",
        "closed_form": "omega^2 = 3*g*(m1 + 2*m2 + m3)/(2*l*(m1 + 3*m2 + m3)) = 36.7875 1/s^2",
        "operating_point": {"th1": y0[0], "th2": y0[1], "th3": y0[2]},
        "independent_coordinates": ["th1"],
        "null_space_map_T": [T[i, 0] for i in range(3)],
        "reduced_M_kg_m2": Mr[0, 0],
        "reduced_K_N_m": Kr[0, 0],
        "frequency": freq(w2),
        "without_geometric_stiffness": dict(freq(Kw[0, 0] / Mr[0, 0]), note=(
            "equal to the true one here: with th1 independent, T = [1, -1, 1] is constant along the "
            "motion, so T^T (sum lambda_k H_Phi_k) T = -(lambda^T Phi_y) d2y/dtheta2 = 0; the loop "
            "is loaded (lambda != 0) but its geometric stiffness vanishes in this direction")),
        "multipliers": {"constraint": "pin", "convention": "Phi = r_B - r_A (x, y), lambda = force on "
                        "the rocker (marker B's body), world frame, N", "lambda": lam},
    }


# ---------------------------------------------------------------------------------------------
# 2. Loaded four-bar (models/linkages/four_bar.yaml and four_bar_given.yaml).

FB = dict(a="0.4", l1="0.1", l2="0.35", l3="0.25", m="0.3", k="40", L0="0.1", Px="0.2", Py="0.5")


def four_bar_tree():
    a, l1, l2, l3, m, k, L0 = (Q(FB[x]) for x in ("a", "l1", "l2", "l3", "m", "k", "L0"))
    P = (Q(FB["Px"]), Q(FB["Py"]))
    th1, th2, th3 = sp.symbols("th1 th2 th3")
    s = PlanarTree([th1, th2, th3])
    A = (l1 * sp.cos(th1), l1 * sp.sin(th1))
    c2 = (A[0] + l2 / 2 * sp.cos(th1 + th2), A[1] + l2 / 2 * sp.sin(th1 + th2))
    s.body("crank", m, m * l1**2 / 12, (A[0] / 2, A[1] / 2), th1)
    s.body("coupler", m, m * l2**2 / 12, c2, th1 + th2)
    s.body("rocker", m, m * l3**2 / 12, (a + l3 / 2 * sp.cos(th3), l3 / 2 * sp.sin(th3)), th3)
    s.V += spring_V(k, L0, P, c2)
    Bc = (A[0] + l2 * sp.cos(th1 + th2), A[1] + l2 * sp.sin(th1 + th2))
    Br = (a + l3 * sp.cos(th3), l3 * sp.sin(th3))
    s.Phi = [Br[0] - Bc[0], Br[1] - Bc[1]]
    return s.build()


def four_bar_minimal():
    """Route B: theta0, omega^2 and dy/dtheta from the closed-form loop (elbow up)."""
    a, l1, l2, l3, m, k, L0, Px, Py = (mpf(FB[x]) for x in ("a", "l1", "l2", "l3", "m", "k", "L0", "Px", "Py"))

    def loop(t):
        Ax, Ay = l1 * mp.cos(t), l1 * mp.sin(t)
        dx, dy = a - Ax, -Ay
        dd = mp.hypot(dx, dy)
        along = (l2**2 - l3**2 + dd**2) / (2 * dd)
        h = mp.sqrt(l2**2 - along**2)
        Bx, By = Ax + (along * dx - h * dy) / dd, Ay + (along * dy + h * dx) / dd
        return (Ax, Ay), (Bx, By)

    def parts(t):
        (Ax, Ay), (Bx, By) = loop(t)
        return [Ax / 2, Ay / 2, (Ax + Bx) / 2, (Ay + By) / 2, (a + Bx) / 2, By / 2,
                t, mp.atan2(By - Ay, Bx - Ax), mp.atan2(By, Bx - a)]

    def V(t):
        p = parts(t)
        sl = mp.hypot(p[2] - Px, p[3] - Py)
        return m * g_mp * (p[1] + p[3] + p[5]) + k / 2 * (sl - L0) ** 2

    def mass(t):
        d = [mp.diff(lambda u: parts(u)[i], t) for i in range(9)]
        lens = (l1, l2, l3)
        return sum(m * (d[2 * b] ** 2 + d[2 * b + 1] ** 2) + m * lens[b] ** 2 / 12 * d[6 + b] ** 2 for b in range(3))

    t0 = mp.findroot(lambda t: mp.diff(V, t), mpf(1))
    p = parts(t0)
    y = [t0, p[7] - t0, p[8]]
    return t0, y, mp.diff(V, t0, 2) / mass(t0), loop(t0)


def four_bar_newton_euler(t0, loop):
    """Route C: joint forces by the statics of the crank, coupler and rocker. Unknowns: O (world
    on crank), A (crank on coupler), B (coupler on rocker), D (world on rocker)."""
    a, l1, l2, l3, m, k, L0, Px, Py = (mpf(FB[x]) for x in ("a", "l1", "l2", "l3", "m", "k", "L0", "Px", "Py"))
    (Ax, Ay), (Bx, By) = loop
    W = -m * g_mp
    c1, c2, c3 = (Ax / 2, Ay / 2), ((Ax + Bx) / 2, (Ay + By) / 2), ((a + Bx) / 2, By / 2)
    sl = mp.hypot(c2[0] - Px, c2[1] - Py)
    Fs = (-k * (sl - L0) * (c2[0] - Px) / sl, -k * (sl - L0) * (c2[1] - Py) / sl)  # spring on coupler
    u = ["Ox", "Oy", "Ax", "Ay", "Bx", "By", "Dx", "Dy"]
    rows, rhs = [], []
    # crank: O + (-A) + W = 0; moments about O: (A - O) x (-A_force) + c1 x W = 0
    rows += [{"Ox": 1, "Ax": -1}, {"Oy": 1, "Ay": -1}, {"Ax": Ay, "Ay": -Ax}]
    rhs += [0, -W, -cross(c1, (0, W))]
    # coupler: A - B + W + Fs = 0; moments about A: (B - A) x (-B_force) + (c2 - A) x (W + Fs) = 0
    rB = (Bx - Ax, By - Ay)
    rows += [{"Ax": 1, "Bx": -1}, {"Ay": 1, "By": -1}, {"Bx": rB[1], "By": -rB[0]}]
    rhs += [-Fs[0], -W - Fs[1], -cross((c2[0] - Ax, c2[1] - Ay), (Fs[0], Fs[1] + W))]
    # rocker: D + B + W = 0; moments about D: (B - D) x B_force + (c3 - D) x W = 0
    rows += [{"Dx": 1, "Bx": 1}, {"Dy": 1, "By": 1}, {"Bx": -By, "By": Bx - a}]
    rhs += [0, -W, -cross((c3[0] - a, c3[1]), (0, W))]
    sol, res = solve_statics(rows, rhs, u, drop=2)  # the crank's moment: the equilibrium condition
    agree("four-bar crank moment residual", res, 0)
    return sol, Fs


def four_bar():
    s = four_bar_tree()
    t0, yB, w2B, loop = four_bar_minimal()
    y, lam = s.statics([1.0, -0.45, 1.95])
    for i in range(3):
        agree("four-bar y%d" % i, y[i], yB[i])
    Mr, Kr, Kw, T = s.reduce(y, lam, [0])
    w2 = Kr[0, 0] / Mr[0, 0]
    agree("four-bar omega^2", w2, w2B)
    ne, Fs = four_bar_newton_euler(t0, loop)
    agree("four-bar pin x", lam[0], ne["Bx"], 1)
    agree("four-bar pin y", lam[1], ne["By"], 1)
    vec = lambda x, yv: {"x": x, "y": yv, "z": mpf(0)}
    return {
        "model": "models/linkages/four_bar.yaml (type: equilibrium) and models/linkages/four_bar_given.yaml "
                 "(type: given, the same point)",
        "what": "four-bar (ground 0.4, crank 0.1, coupler 0.35, rocker 0.25 m, bars 0.3 kg) under gravity "
                "and a spring (k = 40 N/m, rest length 0.1 m, anchor (0.2, 0.5) to the coupler's middle) "
                "at its equilibrium near th1 = 1 rad, elbow up; input T = 0",
        "routes": "A (tree coordinates, multipliers, Newton at 50 digits), B (crank angle, closed-form "
                  "loop, V''/m), C (Newton-Euler statics of each body for the joint forces)",
        "operating_point": {"th1": y[0], "th2": y[1], "th3": y[2]},
        "independent_coordinates": ["th1"],
        "null_space_map_T": [T[i, 0] for i in range(3)],
        "reduced_M_kg_m2": Mr[0, 0],
        "reduced_K_N_m": Kr[0, 0],
        "frequency": freq(w2),
        "without_geometric_stiffness": dict(freq(Kw[0, 0] / Mr[0, 0]), note=(
            "K_wrong = T^T H_V T, H_V the Hessian of V in (th1, th2, th3): what a projection that drops "
            "sum lambda_k d2Phi_k/dy2 computes; wrong by a factor %s in omega^2" % mp.nstr(Kw[0, 0] / Kr[0, 0], 6))),
        "geometric_stiffness_N_m": Kr[0, 0] - Kw[0, 0],
        "multipliers": {"constraint": "pin", "convention": "Phi = r_B - r_A (x, y), lambda = force of the "
                        "coupler on the rocker (marker B's body), world frame, N", "lambda": lam},
        "reactions_N": {
            "note": "force (world frame) on the named body; every torque is 0 (revolute joints at the body "
                    "frames' origins, planar loads)",
            "pin (coupler on rocker, at the rocker's tip)": vec(ne["Bx"], ne["By"]),
            "crank pivot (world on crank, at O)": vec(ne["Ox"], ne["Oy"]),
            "coupler joint (crank on coupler, at A)": vec(ne["Ax"], ne["Ay"]),
            "rocker pivot (world on rocker, at D)": vec(ne["Dx"], ne["Dy"]),
            "spring (on the coupler, at its middle)": vec(Fs[0], Fs[1]),
        },
    }


# ---------------------------------------------------------------------------------------------
# 3. Slider-crank (models/linkages/slider_crank.yaml).

SC = dict(r="0.1", l="0.3", m1="0.2", m2="0.4", m3="0.5", k="5", L0="0.1", xa="0.6")


def slider_crank():
    r, l, m1, m2, m3, k, L0, xa = (Q(SC[x]) for x in ("r", "l", "m1", "m2", "m3", "k", "L0", "xa"))
    th1, th2, x = sp.symbols("th1 th2 x")
    s = PlanarTree([th1, th2, x])
    A = (r * sp.cos(th1), r * sp.sin(th1))
    s.body("crank", m1, m1 * r**2 / 12, (A[0] / 2, A[1] / 2), th1)
    s.body("rod", m2, m2 * l**2 / 12, (A[0] + l / 2 * sp.cos(th1 + th2), A[1] + l / 2 * sp.sin(th1 + th2)), th1 + th2)
    s.body("slider", m3, 0, (x, 0), 0)
    s.V += spring_V(k, L0, (xa, 0), (x, 0))
    s.Phi = [x - (A[0] + l * sp.cos(th1 + th2)), 0 - (A[1] + l * sp.sin(th1 + th2))]
    s.build()
    y, lam = s.statics([-1.2, 1.5, 0.32])
    Mr, Kr, Kw, T = s.reduce(y, lam, [0])
    w2 = Kr[0, 0] / Mr[0, 0]

    # Route B: the crank angle; x = r cos(t) + sqrt(l^2 - r^2 sin^2 t).
    rr, ll, n1, n2, n3, kk, LL, xx = (mpf(SC[v]) for v in ("r", "l", "m1", "m2", "m3", "k", "L0", "xa"))

    def parts(t):
        Ax, Ay = rr * mp.cos(t), rr * mp.sin(t)
        xB = Ax + mp.sqrt(ll**2 - Ay**2)
        return [Ax / 2, Ay / 2, (Ax + xB) / 2, Ay / 2, xB, t, mp.atan2(-Ay, xB - Ax)]

    def V(t):
        p = parts(t)
        return n1 * g_mp * p[1] + n2 * g_mp * p[3] + kk / 2 * (abs(xx - p[4]) - LL) ** 2

    def mass(t):
        d = [mp.diff(lambda u: parts(u)[i], t) for i in range(7)]
        return (n1 * (d[0]**2 + d[1]**2) + n1 * rr**2 / 12 * d[5]**2 + n2 * (d[2]**2 + d[3]**2)
                + n2 * ll**2 / 12 * d[6]**2 + n3 * d[4]**2)

    t0 = mp.findroot(lambda t: mp.diff(V, t), mpf("-1.2"))
    p = parts(t0)
    agree("slider-crank th1", y[0], t0)
    agree("slider-crank th2", y[1], p[6] - t0)
    agree("slider-crank x", y[2], p[4])
    agree("slider-crank omega^2", w2, mp.diff(V, t0, 2) / mass(t0))

    # Route C: unknowns O (world on crank), A (crank on rod), B (rod on slider), N (guide on slider,
    # along y; the frictionless guide has no x force and the point-mass slider needs no torque).
    Ax, Ay, xB = rr * mp.cos(t0), rr * mp.sin(t0), p[4]
    S = kk * (abs(xx - xB) - LL) * (1 if xx > xB else -1)  # the spring's force on the slider, along x
    u = ["Ox", "Oy", "Ax", "Ay", "Bx", "By", "N"]
    rows, rhs = [], []
    rows += [{"Ox": 1, "Ax": -1}, {"Oy": 1, "Ay": -1}, {"Ax": Ay, "Ay": -Ax}]          # crank
    rhs += [0, n1 * g_mp, -cross((Ax / 2, Ay / 2), (0, -n1 * g_mp))]
    rB = (xB - Ax, -Ay)
    rows += [{"Ax": 1, "Bx": -1}, {"Ay": 1, "By": -1}, {"Bx": rB[1], "By": -rB[0]}]     # rod, about A
    rhs += [0, n2 * g_mp, -cross((rB[0] / 2, rB[1] / 2), (0, -n2 * g_mp))]
    rows += [{"Bx": 1}, {"By": 1, "N": 1}]                                               # slider
    rhs += [-S, n3 * g_mp]
    ne, res = solve_statics(rows, rhs, u, drop=2)
    agree("slider-crank crank moment residual", res, 0)
    agree("slider-crank pin x", lam[0], ne["Bx"], 1)
    agree("slider-crank pin y", lam[1], ne["By"], 1)
    vec = lambda a_, b_: {"x": a_, "y": b_, "z": mpf(0)}
    return {
        "model": "models/linkages/slider_crank.yaml",
        "what": "slider-crank (crank 0.1 m 0.2 kg, rod 0.3 m 0.4 kg uniform, slider 0.5 kg point mass on the "
                "world x axis) under gravity and a spring (k = 5 N/m, rest length 0.1 m, anchor (0.6, 0)) on "
                "the slider, at its equilibrium near th1 = -1.2 rad",
        "routes": "A (tree coordinates, multipliers), B (crank angle, closed-form loop, V''/m), "
                  "C (Newton-Euler statics of each body)",
        "operating_point": {"th1": y[0], "th2": y[1], "x": y[2]},
        "independent_coordinates": ["th1"],
        "null_space_map_T": [T[i, 0] for i in range(3)],
        "reduced_M_kg_m2": Mr[0, 0],
        "reduced_K_N_m": Kr[0, 0],
        "frequency": freq(w2),
        "without_geometric_stiffness": freq(Kw[0, 0] / Mr[0, 0]),
        "multipliers": {"constraint": "pin", "convention": "Phi = r_B - r_A (x, y), lambda = force of the "
                        "rod on the slider (marker B's body), world frame, N", "lambda": lam},
        "reactions_N": {
            "note": "force (world frame) on the named body; every torque is 0 (revolute joints at the body "
                    "frames' origins; the slider is a point mass: its guide carries no torque)",
            "pin (rod on slider, at B)": vec(ne["Bx"], ne["By"]),
            "guide normal force (world on slider)": vec(mpf(0), ne["N"]),
            "crank pin (crank on rod, at A)": vec(ne["Ax"], ne["Ay"]),
            "crank pivot (world on crank, at O)": vec(ne["Ox"], ne["Oy"]),
            "spring (on the slider)": vec(S, mpf(0)),
        },
    }


# ---------------------------------------------------------------------------------------------
# 4. Pendulum in two Cartesian coordinates and a distance constraint.

def pendulum_cartesian():
    L, m = Q("0.8"), Q("0.5")
    x, y = sp.symbols("x y")
    s = PlanarTree([x, y])
    s.body("bob", m, 0, (x, y), 0)
    s.Phi = [sp.sqrt(x**2 + y**2) - L]
    s.build()
    y0 = [mpf(0), -mpf("0.8")]
    lam = s.multipliers(y0)
    Mr, Kr, Kw, T = s.reduce(y0, lam, [0])
    w2 = Kr[0, 0] / Mr[0, 0]
    agree("pendulum omega^2", w2, g_mp / mpf("0.8"))
    agree("pendulum K_wrong", Kw[0, 0], 0)

    # Route S: SymPy's Linearizer on the non-minimal pendulum (after SymPy's
    # test_linearize_pendulum_kane_nonminimal; here with gravity along -y, hanging at (0, -L)).
    import sympy.physics.mechanics as me
    q1, q2 = me.dynamicsymbols("q1:3")
    q1d, q2d = me.dynamicsymbols("q1:3", level=1)
    u1, u2 = me.dynamicsymbols("u1:3")
    u1d, u2d = me.dynamicsymbols("u1:3", level=1)
    Ls, ms, gs = sp.symbols("L m g", positive=True)
    N = me.ReferenceFrame("N")
    pN = me.Point("N*")
    pN.set_vel(N, 0)
    P = pN.locatenew("P", q1 * N.x + q2 * N.y)
    P.set_vel(N, P.pos_from(pN).dt(N))
    kde = sp.Matrix([q1d - u1, q2d - u2])
    f_c = sp.Matrix([P.pos_from(pN).magnitude() - Ls])
    f_v = sp.Matrix([P.vel(N).dot(P.pos_from(pN))])  # no velocity along the rod
    KM = me.KanesMethod(N, q_ind=[q1], u_ind=[u1], q_dependent=[q2], u_dependent=[u2],
                        configuration_constraints=f_c, velocity_constraints=f_v, kd_eqs=kde)
    KM.kanes_equations([me.Particle("bob", P, ms)], [(P, -ms * gs * N.y)])
    op = {q1: 0, q2: -Ls, u1: 0, u2: 0, u1d: 0, u2d: 0}
    Amat = KM.linearize(op_point=op, A_and_B=True, simplify=True)[0]
    Amat = sp.simplify(Amat)
    expected = sp.Matrix([[0, 1], [-gs / Ls, 0]])
    if sp.simplify(Amat - expected) != sp.zeros(2, 2):
        sys.exit("loops_reference: SymPy's non-minimal pendulum gives A = %s" % Amat)
    w2S = -Amat[1, 0].subs({gs: G, Ls: L})
    agree("pendulum omega^2 (SymPy)", w2, sp.N(w2S, 50))
    return {
        "model": "models/linkages/pendulum_cartesian.yaml",
        "what": "point mass 0.5 kg at (x, y) held at L = 0.8 m from the origin by a distance constraint, "
                "gravity -y, hanging (x = 0, y = -L); the whole stiffness is geometric",
        "routes": "A (tree coordinates, multipliers) and S (SymPy KanesMethod.linearize of the non-minimal "
                  "pendulum: A = [[0, 1], [-g/L, 0]] exactly, in (x, x_dot))",
        "sympy_A": "[[0, 1], [-g/L, 0]]",
        "operating_point": {"x": y0[0], "y": y0[1]},
        "independent_coordinates": ["x"],
        "null_space_map_T": [T[i, 0] for i in range(2)],
        "reduced_M_kg": Mr[0, 0],
        "reduced_K_N_per_m": Kr[0, 0],
        "frequency": freq(w2),
        "without_geometric_stiffness": dict(freq(Kw[0, 0] / Mr[0, 0]), note="0: no stiffness at all"),
        "multipliers": {"constraint": "rod", "convention": "Phi = |r_B - r_A| - L, B the bob; the force on "
                        "the bob is lambda (r_B - r_A)/|r_B - r_A|; Phi = (|d|^2 - L^2)/2 would give "
                        "lambda/L", "lambda": lam},
        "reactions_N": {"rod on the bob": {"x": mpf(0), "y": -lam[0], "z": mpf(0)}},
    }


# ---------------------------------------------------------------------------------------------
# 5. The ladder of N parallelogram loops (bench/ladder_model.py, = mbsgen/generator/model/parametric_chains.hpp ladder(n)).

LD = dict(h="0.2", w="0.3", m="0.2", k="2")


def ladder_tree(n):
    """Route A on the tree of bench/ladder_model.py: rails a_i, b_i (relative angles), rungs r_i."""
    h, w, m, k = (Q(LD[v]) for v in ("h", "w", "m", "k"))
    coords, s = [], None
    syms = {}
    for i in range(1, n + 1):
        for name in ("a%d" % i, "b%d" % i, "r%d" % i):
            syms[name] = sp.Symbol(name)
            coords.append(syms[name])
    s = PlanarTree(coords)
    base = {"a": (sp.Integer(0), sp.Integer(0)), "b": (w, sp.Integer(0))}
    ang = {"a": sp.Integer(0), "b": sp.Integer(0)}
    y0 = []
    for i in range(1, n + 1):
        tips = {}
        for side in ("a", "b"):
            q = syms["%s%d" % (side, i)]
            ang[side] = ang[side] + q
            p0 = base[side]
            s.body("%s%d" % (side, i), m, m * h**2 / 12,
                   (p0[0] + h / 2 * sp.cos(ang[side]), p0[1] + h / 2 * sp.sin(ang[side])), ang[side])
            tips[side] = (p0[0] + h * sp.cos(ang[side]), p0[1] + h * sp.sin(ang[side]))
            base[side] = tips[side]
            hanging = -sp.pi / 2 if i == 1 else 0
            s.V += k / 2 * (q - hanging) ** 2
        r = syms["r%d" % i]
        ra = ang["a"] + r
        s.body("rung%d" % i, m, m * w**2 / 12,
               (tips["a"][0] + w / 2 * sp.cos(ra), tips["a"][1] + w / 2 * sp.sin(ra)), ra)
        end = (tips["a"][0] + w * sp.cos(ra), tips["a"][1] + w * sp.sin(ra))
        s.Phi += [tips["b"][0] - end[0], tips["b"][1] - end[1]]
        y0 += [-mp.pi / 2 if i == 1 else mpf(0)] * 2 + [mp.pi / 2]
    return s.build(), y0


def ladder_minimal(n):
    """Route L: one absolute angle phi_i per level (rails parallel, rungs translate), deviation
    psi_i from hanging: bar centres p_{i-1} + h/2 e(phi_i), rung centre p_i + (w/2, 0), joint
    springs k (psi_i - psi_{i-1})^2 / 2 on each rail; M and K at psi = 0, symbolically."""
    h, w, m, k = (Q(LD[v]) for v in ("h", "w", "m", "k"))
    psi = sp.symbols("psi1:%d" % (n + 1))
    phi = [p - sp.pi / 2 for p in psi]
    T = 0
    V = 0
    px, py = sp.Integer(0), sp.Integer(0)
    dt = [sp.Symbol("d%d" % i) for i in range(n)]  # rates
    vx, vy = sp.Integer(0), sp.Integer(0)
    for i in range(n):
        ex, ey = sp.cos(phi[i]), sp.sin(phi[i])
        dex, dey = -sp.sin(phi[i]) * dt[i], sp.cos(phi[i]) * dt[i]
        cx, cy = px + h / 2 * ex, py + h / 2 * ey
        cvx, cvy = vx + h / 2 * dex, vy + h / 2 * dey
        T += 2 * (m * (cvx**2 + cvy**2) / 2 + m * h**2 / 24 * dt[i] ** 2)   # two rail bars
        V += 2 * m * G * cy
        px, py, vx, vy = px + h * ex, py + h * ey, vx + h * dex, vy + h * dey
        T += m * (vx**2 + vy**2) / 2                                         # the rung translates
        V += m * G * py
        V += 2 * k / 2 * (psi[i] - (psi[i - 1] if i else 0)) ** 2
    at0 = {p: 0 for p in psi}
    M = sp.Matrix(n, n, lambda i, j: sp.diff(T, dt[i], dt[j]).subs(at0))
    K = sp.Matrix(n, n, lambda i, j: sp.diff(V, psi[i], psi[j]).subs(at0))
    tomp = lambda A: mp.matrix([[mpf(sp.N(A[i, j], 60)) for j in range(n)] for i in range(n)])
    return tomp(M), tomp(K)


def ladder(n):
    Mm, Km = ladder_minimal(n)
    wL = eigen_omegas(Mm, Km)
    s, y0 = ladder_tree(n)
    lam = s.multipliers(y0)
    g = s.f_grad(y0)
    J = s.f_jac(y0)
    res = max(abs(g[i] - sum(J[k][i] * lam[k] for k in range(len(lam)))) for i in range(len(g)))
    agree("ladder statics residual", res, 0)
    independent = [3 * i for i in range(n)]  # a_i
    Mr, Kr, Kw, _ = s.reduce(y0, lam, independent)
    wA = eigen_omegas(Mr, Kr)
    for i in range(n):
        agree("ladder omega^2 %d" % i, wA[i], wL[i])
    mm = mpf(LD["m"])
    for i in range(n):
        agree("ladder pin %d x" % i, lam[2 * i], 0)
        agree("ladder pin %d y" % i, lam[2 * i + 1], -mm * g_mp / 2)
    wW = eigen_omegas(Mr, Kw)
    return {
        "model": "bench/ladder_model.py --loops %d (the same model as mbsgen/generator/model/parametric_chains.hpp ladder(%d))" % (n, n),
        "what": "planar ladder of %d parallelogram loops hanging straight: rails of bars h = 0.2 m, rungs "
                "w = 0.3 m, every bar 0.2 kg uniform, joint springs k = 2 N m/rad relaxed when hanging, "
                "g = 9.81; pin_i joins rung i's end to rail b's bar i" % n,
        "routes": "A (3N tree coordinates, 2N multipliers, independent a_1..a_N) and L (N absolute level "
                  "angles, symbolic M and K)",
        "operating_point": {"a1": -mp.pi / 2, "b1": -mp.pi / 2, "r_i": mp.pi / 2, "a_i, b_i (i > 1)": mpf(0)},
        "frequencies": [freq(v) for v in wA],
        "without_geometric_stiffness_omega2": wW,
        "multipliers": {"convention": "pin_i: Phi = r_B - r_A, B = rail b's bar i; lambda = force of the "
                        "rung on that bar, world frame, N; every pin carries half its rung's weight",
                        "lambda_each_pin": [mpf(0), -mm * g_mp / 2]},
    }


# ---------------------------------------------------------------------------------------------

def fmt(v):
    if isinstance(v, sp.Basic):
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
        items = [inner + json.dumps(k) + ": " + dump(v, indent + 1) for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, (list, tuple)):
        if all(fmt(v) is not None for v in obj):
            return "[" + ", ".join(fmt(v) for v in obj) + "]"
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
            "precision": "mpmath at 50 digits; every number written with %d significant digits, agreeing "
                         "between two independent routes to 1e-30 relative; values below 1e-35 written as 0" % DIGITS,
            "units": "SI: rad, m, kg, s, N",
            "frames": "planar models in the x-y plane, gravity -y, angles from the x axis about z",
        },
        "four_bar_parallelogram": parallelogram(),
        "four_bar": four_bar(),
        "slider_crank": slider_crank(),
        "pendulum_cartesian": pendulum_cartesian(),
        "ladder_10": ladder(10),
    }
    text = dump(data) + "\n"
    if args.check:
        with open(args.out) as f:
            if f.read() != text:
                sys.exit("loops_reference: %s differs from what the script computes" % args.out)
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
