#!/usr/bin/env python3
"""Independent reference for mbsgen/generator/model/parametric_chains.hpp's four_bar_linkage (issue 15 §4).

One minimal coordinate, the crank angle theta: the loop is closed in closed form (the
intersection of the circles about the crank's tip and the rocker's pivot, elbow up), the
potential V(theta) (gravity and the spring) and the kinetic energy T = 1/2 m(theta) theta_dot^2
are written out, and with mpmath at 50 digits:
  equilibrium  dV/dtheta = 0 near theta = 1 rad,
  frequency    omega^2 = V''(theta0) / m(theta0),
  wrong        omega^2 without the geometric stiffness: T_y^T K_tree T_y / m, with K_tree the
               Hessian of V in the tree's coordinates (th1, th2 = coupler relative to crank, th3)
               and T_y = d(th1, th2, th3)/dtheta (what a projection that ignores the
               constraint forces computes).
No mbsgen code is used. Prints the numbers the test
tests/generator/kernel_test.cpp (FourBarLinkage.*) compares with.
"""
from mpmath import mp, mpf, cos, sin, sqrt, atan2, diff, findroot, pi

mp.dps = 50
a, l1, l2, l3 = mpf("0.4"), mpf("0.1"), mpf("0.35"), mpf("0.25")
m, g, k, L0 = mpf("0.3"), mpf("9.81"), mpf("40"), mpf("0.1")
P = (a / 2, mpf("0.5"))  # spring anchor on the world


def closed(theta):
    """(A, B) of the closed loop at crank angle theta (elbow up)."""
    Ax, Ay = l1 * cos(theta), l1 * sin(theta)
    dx, dy = a - Ax, -Ay
    d = sqrt(dx * dx + dy * dy)
    along = (l2 * l2 - l3 * l3 + d * d) / (2 * d)
    h = sqrt(l2 * l2 - along * along)
    Bx, By = Ax + (along * dx - h * dy) / d, Ay + (along * dy + h * dx) / d
    return (Ax, Ay), (Bx, By)


def tree(theta):
    (Ax, Ay), (Bx, By) = closed(theta)
    th2 = atan2(By - Ay, Bx - Ax) - theta
    th3 = atan2(By, Bx - a)
    return theta, th2, th3


def potential_tree(th1, th2, th3):
    Ax, Ay = l1 * cos(th1), l1 * sin(th1)
    c1 = (Ax / 2, Ay / 2)
    c2 = (Ax + l2 / 2 * cos(th1 + th2), Ay + l2 / 2 * sin(th1 + th2))
    c3 = (a + l3 / 2 * cos(th3), l3 / 2 * sin(th3))
    spring = sqrt((c2[0] - P[0]) ** 2 + (c2[1] - P[1]) ** 2)
    return m * g * (c1[1] + c2[1] + c3[1]) + k / 2 * (spring - L0) ** 2


def potential(theta):
    return potential_tree(*tree(theta))


def mass(theta):
    """m(theta) = sum of m |dc/dtheta|^2 + I (d angle/dtheta)^2 over the three bars."""
    def centres(t):
        th1, th2, th3 = tree(t)
        Ax, Ay = l1 * cos(th1), l1 * sin(th1)
        return [(Ax / 2, Ay / 2), (Ax + l2 / 2 * cos(th1 + th2), Ay + l2 / 2 * sin(th1 + th2)),
                (a + l3 / 2 * cos(th3), l3 / 2 * sin(th3))], [th1, th1 + th2, th3]
    total = 0
    lengths = [l1, l2, l3]
    for i in range(3):
        vx = diff(lambda t: centres(t)[0][i][0], theta)
        vy = diff(lambda t: centres(t)[0][i][1], theta)
        w = diff(lambda t: centres(t)[1][i], theta)
        total += m * (vx * vx + vy * vy) + m * lengths[i] ** 2 / 12 * w * w
    return total


theta0 = findroot(lambda t: diff(potential, t), mpf(1))
M0 = mass(theta0)
K0 = diff(potential, theta0, 2)
y0 = tree(theta0)
T = [diff(lambda t: tree(t)[j], theta0) for j in range(3)]
H = [[diff(potential_tree, y0, tuple(1 if q in (i, j) and i != j else (2 if q == i == j else 0)
                                       for q in range(3))) for j in range(3)] for i in range(3)]
K_wrong = sum(T[i] * H[i][j] * T[j] for i in range(3) for j in range(3))
print("theta0 (th1) =", mp.nstr(theta0, 25))
print("th2 =", mp.nstr(y0[1], 25), " th3 =", mp.nstr(y0[2], 25))
print("M =", mp.nstr(M0, 25), " K =", mp.nstr(K0, 25))
print("omega^2 =", mp.nstr(K0 / M0, 25), " f [Hz] =", mp.nstr(sqrt(K0 / M0) / (2 * pi), 25))
print("without geometric stiffness: omega^2 =", mp.nstr(K_wrong / M0, 25))

# The pin's load on the rocker at the equilibrium, by statics of two bodies (no multipliers):
# the rocker turns about D, the coupler about A; the unknown F acts on the rocker at B and -F on
# the coupler at B; the spring pulls the coupler's middle towards P.
(Ax, Ay), (Bx, By) = closed(theta0)
c2 = ((Ax + Bx) / 2, (Ay + By) / 2)
c3 = ((a + Bx) / 2, By / 2)
dist = sqrt((c2[0] - P[0]) ** 2 + (c2[1] - P[1]) ** 2)
Fs = (-k * (dist - L0) * (c2[0] - P[0]) / dist, -k * (dist - L0) * (c2[1] - P[1]) / dist)
W = -m * g
# rocker, moments about D: (B - D) x F + (c3 - D) x (0, W) = 0
# coupler, moments about A: (B - A) x (-F) + (c2 - A) x (Fs + (0, W)) = 0
cross = lambda r, f: r[0] * f[1] - r[1] * f[0]
rB_D, rB_A = (Bx - a, By), (Bx - Ax, By - Ay)
rhs1 = -cross((c3[0] - a, c3[1]), (0, W))
rhs2 = cross((c2[0] - Ax, c2[1] - Ay), (Fs[0], Fs[1] + W))
# [[-rB_D.y, rB_D.x], [-rB_A.y, rB_A.x]] F = [rhs1, rhs2]
det = -rB_D[1] * rB_A[0] + rB_D[0] * rB_A[1]
Fx = (rhs1 * rB_A[0] - rB_D[0] * rhs2) / det
Fy = (-rB_D[1] * rhs2 + rB_A[1] * rhs1) / det
print("pin load on the rocker: Fx =", mp.nstr(Fx, 25), " Fy =", mp.nstr(Fy, 25))
# The world's load on the crank at O: the crank's weight, and -(the coupler's load on the crank)...
# the whole linkage less the rocker: F_O + F_D + W*3 + Fs = 0 with F_D from the rocker:
# rocker: F_D + F + (0, W) = 0.
FDx, FDy = -Fx, -Fy - W
FOx, FOy = -(FDx + Fs[0]), -(FDy + Fs[1] + 3 * W)
print("pivot load on the crank: Fx =", mp.nstr(FOx, 25), " Fy =", mp.nstr(FOy, 25))
