#!/usr/bin/python3
"""The double pendulum's two natural frequencies against its mass ratio, from Python, beside the
closed form: point masses m1, m2 on massless rods l1, l2 (models/textbook/double_pendulum.yaml),
det(K − ω²M) = 0 with M = [[(m1+m2)l1², m2 l1 l2], [m2 l1 l2, m2 l2²]], K = diag((m1+m2)g l1, m2 g l2)
(the equations of motion of two point masses on massless rods, linearized about the hanging position).

usage: PYTHONPATH=build/ci/python /usr/bin/python3 examples/python/double_pendulum_modes.py [OUT.png]
(Debian python3-matplotlib; writes docs/python_double_pendulum.png by default)
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import mbsgen  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "python_double_pendulum.png")

pendulum = mbsgen.Model(os.path.join(ROOT, "models/textbook/double_pendulum.yaml"))
m1, l1, l2, g = 1.0, 1.0, 1.0, 9.81
ratios = np.logspace(-1, 1, 41)
computed = np.array([np.sort(pendulum.modes(m1=m1, m2=r * m1, l1=l1, l2=l2, g=g).natural_frequency_hz) for r in ratios])


def closed_form(m2):
    # ω² are the roots of det(K − ω²M) = a ω⁴ − b ω² + c
    a = (m1 + m2) * l1**2 * m2 * l2**2 - (m2 * l1 * l2) ** 2
    b = (m1 + m2) * l1**2 * m2 * g * l2 + m2 * l2**2 * (m1 + m2) * g * l1
    c = (m1 + m2) * g * l1 * m2 * g * l2
    w2 = np.sort(np.roots([a, -b, c]).real)
    return np.sqrt(w2) / (2 * np.pi)


exact = np.array([closed_form(r * m1) for r in ratios])
worst = np.max(np.abs(computed - exact) / exact)

fig, ax = plt.subplots(figsize=(7, 4.5))
for k, colour in ((0, "tab:blue"), (1, "tab:orange")):
    ax.semilogx(ratios, exact[:, k], color=colour, lw=3, alpha=0.35, label=f"mode {k + 1}: closed form det(K − ω²M) = 0")
    ax.semilogx(ratios, computed[:, k], "o", color=colour, ms=3.5, label=f"mode {k + 1}: mbsgen.Model(...).modes(m2=...)")
ax.set_xlabel("mass ratio m2/m1 [-] (m1 = 1 kg, l1 = l2 = 1 m, g = 9.81 m/s²)")
ax.set_ylabel("natural frequency [Hz]")
ax.set_title(f"Double pendulum from Python: largest relative difference to the closed form {worst:.1e}", fontsize=10)
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}: largest relative difference {worst:.2e}")
