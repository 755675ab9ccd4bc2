#!/usr/bin/python3
"""The Whipple bicycle's eigenvalues against its forward speed, from Python, beside the benchmark:
[Meijaard2007] Table 2 at v = 0, 1, …, 10 m/s (recomputed at 40 digits; docs/test-references.md,
"The Whipple bicycle") and its stability boundaries, the weave speed v_w = 4.29238253634111 m/s and
the capsize speed v_c = 6.02426201538837 m/s. The model (models/bicycle/whipple_benchmark.yaml) has
rolling contacts whose holonomic part closes a loop: the package loads its compiled kernels.

usage: PYTHONPATH=build/ci/python /usr/bin/python3 examples/python/bicycle_eigenvalues.py [OUT.png]
(Debian python3-matplotlib; writes docs/python_bicycle.png by default)
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import mbsgen  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "python_bicycle.png")

# [Meijaard2007] Table 2 (docs/test-references.md): castering, capsize, and the weave pair.
TABLE = {
    0: [-5.530943717653935, -3.131643247906556, 3.131643247906556, 5.530943717653935],
    1: [-7.110080146374408, -3.134231250665784, 3.526961709900694 + 0.80774027519931j],
    2: [-8.673879848317372, -3.071586456415143, 2.682345175127453 + 1.680662965906758j],
    3: [-10.35101467245923, -2.633661372536653, 1.706756056639735 + 2.315824473843244j],
    4: [-12.15861426576444, -1.429444273613257, 0.4132533152112413 + 3.079108186032054j],
    5: [-14.07838969279825, -0.3228664290040871, -0.7753418821958419 + 4.464867713788225j],
    6: [-16.08537123098028, -0.004066900769703362, -1.526444865841417 + 5.876730605987084j],
    7: [-18.15788466125202, 0.1026817057476642, -2.138756442583634 + 7.195259133298043j],
    8: [-20.27940894394566, 0.1432787976571295, -2.693486835810948 + 8.460379713969336j],
    9: [-22.43788559040859, 0.157901840309173, -3.216754022524907 + 9.693773515317822j],
    10: [-24.624596350174, 0.1610533865317155, -3.720168404372876 + 10.90681139476288j],
}
V_WEAVE, V_CAPSIZE = 4.29238253634111, 6.02426201538837

bicycle = mbsgen.Model(os.path.join(ROOT, "models/bicycle/whipple_benchmark.yaml"))
speeds = np.linspace(0, 10, 201)
curves = []
for v in speeds:
    m = bicycle.modes(all=True, v=v)
    finite = [lam for lam, kind in zip(m.eigenvalues, m.kinds) if kind == "finite"]
    curves.append(finite)

# The four lean–steer eigenvalues (the others are the ignorable coordinates' zeros and infinities).
worst = 0.0
for v, expected in TABLE.items():
    r = bicycle.modes(all=True, v=float(v))
    got = np.array([lam for lam, kind in zip(r.eigenvalues, r.kinds) if kind == "finite"])
    for e in expected:
        worst = max(worst, np.min(np.abs(got - e)))

fig, ax = plt.subplots(figsize=(11, 5))
for v, lams in zip(speeds, curves):
    lams = np.array(lams)
    ax.plot([v] * len(lams), lams.real, ".", color="tab:blue", ms=2.5)
    ax.plot([v] * len(lams), np.abs(lams.imag), ".", color="tab:orange", ms=2.5)
ax.plot([], [], ".", color="tab:blue", label="Re λ, mbsgen.Model(...).modes(v=...)")
ax.plot([], [], ".", color="tab:orange", label="|Im λ|, mbsgen.Model(...).modes(v=...)")
for v, expected in TABLE.items():
    e = np.array(expected, dtype=complex)
    ax.plot([v] * len(e), e.real, "o", mfc="none", color="k", ms=7)
    ax.plot([v] * len(e), np.abs(e.imag), "s", mfc="none", color="k", ms=7)
ax.plot([], [], "o", mfc="none", color="k", label="Re λ, Meijaard et al. 2007, Table 2")
ax.plot([], [], "s", mfc="none", color="k", label="|Im λ|, Meijaard et al. 2007, Table 2")
ax.axvline(V_WEAVE, color="tab:green", ls="--", label=f"weave speed v_w = {V_WEAVE:.3f} m/s")
ax.axvline(V_CAPSIZE, color="tab:red", ls="--", label=f"capsize speed v_c = {V_CAPSIZE:.3f} m/s")
ax.axhline(0, color="0.5", lw=0.8)
ax.set_ylim(-10, 10)
ax.set_xlabel("forward speed v [m/s]")
ax.set_ylabel("eigenvalue λ [1/s]")
ax.set_title(f"Whipple bicycle from Python (compiled kernels): largest difference to Table 2 {worst:.1e} 1/s",
             fontsize=10)
ax.grid(True, alpha=0.3)
ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}: evaluation {bicycle.evaluation}, largest difference to Table 2 {worst:.2e} 1/s")
