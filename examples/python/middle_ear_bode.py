#!/usr/bin/python3
"""The middle ear's stapes velocity per ear-canal pressure from Python: the nominal model, the 5–95 %
band of 2,000 ears whose ligament and joint stiffnesses and dampings each vary by ×U(0.7, 1.3)
(one batch call on every core), and the reference band and measured points of
models/middle_ear/reference.csv (docs/middle-ear.md, "The reference band").

usage: PYTHONPATH=build/ci/python /usr/bin/python3 examples/python/middle_ear_bode.py [OUT.png]
(Debian python3-matplotlib; writes docs/python_middle_ear.png by default)
"""
import csv
import os
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import mbsgen  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "python_middle_ear.png")

ear = mbsgen.Model(os.path.join(ROOT, "models/middle_ear/middle_ear.yaml"))
hz = np.logspace(np.log10(100), np.log10(10000), 300)
nominal = ear.frf("P", "v_stapes", hz).values * 1e3  # (mm/s)/Pa

# Ligaments and joints: every stiffness and damping but the eardrum's and the cochlea's.
varied = [p for p in ear.parameters if p.name[:2] in ("k_", "d_") and "eardrum" not in p.name and "cochlea" not in p.name]
rng = np.random.default_rng(2026)
n = 2000
sets = {p.name: p.default * rng.uniform(0.7, 1.3, n) for p in varied}
t0 = time.perf_counter()
batch = ear.frf("P", "v_stapes", hz, params=sets)
seconds = time.perf_counter() - t0
ok = ~np.isnan(batch.values).any(axis=1)
magnitude = np.abs(batch.values[ok]) * 1e3
lo, median, hi = np.percentile(magnitude, [5, 50, 95], axis=0)

rows = []
with open(os.path.join(ROOT, "models/middle_ear/reference.csv"), encoding="utf-8") as f:
    rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
f_ref = np.array([float(r["f_hz"]) for r in rows])
band_lo = np.array([float(r["band_lo"]) for r in rows])
band_hi = np.array([float(r["band_hi"]) for r in rows])
points = {key: [(float(r["f_hz"]), float(r[key])) for r in rows if r[key]] for key in ("aibara", "goode")}
phase_rows = [r for r in rows if r["phase_min_deg"]]

fig, (ax, ph) = plt.subplots(2, 1, figsize=(8, 7.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
ax.fill_between(f_ref, band_lo, band_hi, color="0.85", label="reference band: lumped-model range + Aibara/Goode points")
ax.fill_between(hz, lo, hi, color="tab:blue", alpha=0.25,
                label=f"5–95 % of {ok.sum()} ears, ligaments and joints ×U(0.7, 1.3)")
ax.loglog(hz, median, color="tab:blue", lw=1, ls="--", label="median of those ears")
ax.loglog(hz, np.abs(nominal), color="k", lw=1.8, label="nominal model (models/middle_ear)")
ax.plot(*zip(*points["aibara"]), "o", color="tab:red", label="Aibara et al. 2001, 12 temporal bones (mean peak)")
ax.plot(*zip(*points["goode"]), "s", color="tab:green", mfc="none", label="Goode et al. 1994 (digitized, as velocity)")
ax.set_ylabel("|stapes velocity / ear-canal pressure| [(mm/s)/Pa]")
ax.set_title("Middle ear from Python: mbsgen.Model(...).frf, one batch call of "
             f"{n} parameter sets ({seconds:.1f} s)", fontsize=10)
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8, loc="lower center")
ph.fill_between([float(r["f_hz"]) for r in phase_rows], [float(r["phase_min_deg"]) for r in phase_rows],
                [float(r["phase_max_deg"]) for r in phase_rows], color="0.85", label="lumped-model phase range")
ph.semilogx(hz, np.degrees(np.angle(nominal)), color="k", lw=1.8, label="nominal model")
ph.set_xlabel("frequency [Hz]")
ph.set_ylabel("phase of V/P [deg]")
ph.grid(True, which="both", alpha=0.3)
ph.legend(fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}: {ok.sum()} of {n} sets, batch {seconds:.2f} s")
