#!/usr/bin/env python3
"""Independent reference for models/linkages/slider_crank.yaml (issue 15 §4).

One minimal coordinate, the crank angle theta; the slider's position closes the loop in closed
form, xB = r cos(theta) + sqrt(l^2 - r^2 sin^2(theta)). With mpmath at 50 digits:
  equilibrium  dV/dtheta = 0 near theta = -0.8 rad (gravity and the slider's spring),
  frequency    omega^2 = V''(theta0) / m(theta0) (T = 1/2 m(theta) theta_dot^2),
  loads        every joint's by the statics of each body (no multipliers): the slider (spring,
               weight, the rod's pin force F, the guide's normal force N), the rod (moments about
               the crank pin A), the crank (forces at the pivot O).
No mbsgen code is used.
"""
from mpmath import mp, mpf, cos, sin, sqrt, atan2, diff, findroot, pi

mp.dps = 50
r, l = mpf("0.1"), mpf("0.3")
m1, m2, m3 = mpf("0.2"), mpf("0.4"), mpf("0.5")
g, k, L0, xa = mpf("9.81"), mpf("5"), mpf("0.1"), mpf("0.6")  # spring anchor at (xa, 0)


def geometry(t):
    A = (r * cos(t), r * sin(t))
    xB = r * cos(t) + sqrt(l * l - r * r * sin(t) ** 2)
    return A, (xB, mpf(0))


def potential(t):
    A, B = geometry(t)
    return (m1 * g * A[1] / 2 + m2 * g * (A[1] + B[1]) / 2 + k / 2 * (xa - B[0] - L0) ** 2)


def mass(t):
    def parts(u):
        A, B = geometry(u)
        phi = atan2(B[1] - A[1], B[0] - A[0])
        return [A[0] / 2, A[1] / 2, (A[0] + B[0]) / 2, (A[1] + B[1]) / 2, B[0], u, phi]
    d = [diff(lambda u: parts(u)[i], t) for i in range(7)]
    return (m1 * (d[0] ** 2 + d[1] ** 2) + m1 * r * r / 12 * d[5] ** 2 +
            m2 * (d[2] ** 2 + d[3] ** 2) + m2 * l * l / 12 * d[6] ** 2 + m3 * d[4] ** 2)


t0 = findroot(lambda t: diff(potential, t), mpf("-0.8"))
A, B = geometry(t0)
phi0 = atan2(B[1] - A[1], B[0] - A[0])
M0, K0 = mass(t0), diff(potential, t0, 2)
print("th1 =", mp.nstr(t0, 25), " th2 (rod relative) =", mp.nstr(phi0 - t0, 25), " x =", mp.nstr(B[0], 25))
print("omega^2 =", mp.nstr(K0 / M0, 25), " f [Hz] =", mp.nstr(sqrt(K0 / M0) / (2 * pi), 25))

# Statics. Slider: F + S + N + W3 = 0 along x and y; rod: G - F + W2 = 0 and moments about A.
S = k * (xa - B[0] - L0)               # the spring's force on the slider, along x (towards the anchor)
Fx = -S                                 # the rod's force on the slider at B
# rod moments about A: (B - A) x (-F) + ((B - A)/2) x (0, -m2 g) = 0
dx, dy = B[0] - A[0], B[1] - A[1]
# -(dx*Fy - dy*Fx) + (dx/2)*(-m2 g) = 0  ->  Fy = (dy*Fx - dx*m2*g/2) / dx
Fy = (dy * Fx - dx * m2 * g / 2) / dx
N = m3 * g - Fy                         # the guide's force on the slider, along y
Gx, Gy = Fx, Fy + m2 * g                # the crank's force on the rod at A
Px, Py = Gx, Gy + m1 * g                # the world's force on the crank at O
moment = -(A[0] * Gy - A[1] * Gx) + (A[0] / 2) * (-m1 * g)  # the crank's moments about O: 0
print("pin (rod on slider):", mp.nstr(Fx, 20), mp.nstr(Fy, 20))
print("guide (world on slider):", 0, mp.nstr(N, 20))
print("crank pin (crank on rod):", mp.nstr(Gx, 20), mp.nstr(Gy, 20))
print("pivot (world on crank):", mp.nstr(Px, 20), mp.nstr(Py, 20))
print("check: moment on the crank about O =", mp.nstr(moment, 5))
