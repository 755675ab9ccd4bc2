#!/usr/bin/python3
"""A 7-axis arm with elastic joints, from its URDF (docs/urdf.md): the Franka Emika Panda of
models/robots/urdf/panda.urdf (kinematics and the inertial parameters identified by Gaz et al.,
IEEE RA-L 2019), every joint a torsion spring of 20 kN m/rad with 5 N m s/rad of damping (series
elastic joints with the motors held), at a pose. What a designer asks before building it:

  left   the natural frequencies of the first four modes as joint 2 (the shoulder) moves the arm
         out over the workspace (the springs' rest angle; the arm sags from it under gravity by
         τ_g/k, a few milliradians), so the lowest mode a controller must stay below;
  right  the frequency response from the shoulder torque to the flange's horizontal position at
         three of those poses.

usage: PYTHONPATH=build/ci/python MBSGEN=build/ci/generator/mbsgen /usr/bin/python3 \
           examples/python/elastic_arm.py [OUT.png]
(Debian python3-matplotlib; writes docs/urdf_elastic_arm.png by default)
"""
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import mbsgen  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "urdf_elastic_arm.png")
command = os.environ.get("MBSGEN", "mbsgen")

# The URDF as a model with joint springs: `mbsgen import` (the command a user runs once).
pose = {"panda_joint4": -1.8, "panda_joint6": 2.1}  # elbow bent, flange level (rad)
with tempfile.TemporaryDirectory() as work:
    model_file = os.path.join(work, "panda_elastic.yaml")
    subprocess.run([command, "import", os.path.join(ROOT, "models/robots/urdf/panda.urdf"), "--elastic", "all",
                    "--stiffness", "2e4", "--damping", "5", "--pose",
                    ",".join(f"{k}={v}" for k, v in pose.items()), "--out", model_file],
                   check=True, stderr=subprocess.DEVNULL)
    arm = mbsgen.Model(model_file)

    shoulder = np.linspace(-1.2, 1.2, 49)  # rad: the rest angle of joint 2
    frequencies = np.array([np.sort(arm.modes(panda_joint2_rest=a).natural_frequency_hz)[:4] for a in shoulder])
    hz = np.logspace(0, 3, 600)
    responses = {a: arm.frf("tau_panda_joint2", "panda_link8_x", hz, panda_joint2_rest=a).values for a in (-0.8, 0.0, 0.8)}

fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.4))
for k in range(4):
    left.plot(shoulder, frequencies[:, k], lw=2, label=f"mode {k + 1}")
left.set_xlabel("joint 2 (shoulder) angle [rad]")
left.set_ylabel("natural frequency [Hz]")
left.set_title("Modes over the workspace (joints 4, 6 at -1.8, 2.1 rad)", fontsize=10)
left.grid(True, alpha=0.3)
left.legend(fontsize=8, title="elastic joints, k = 20 kN m/rad", title_fontsize=8)
for a, h in responses.items():
    right.loglog(hz, np.abs(h), lw=1.6, label=f"joint 2 at {a:+.1f} rad")
right.set_xlabel("frequency [Hz]")
right.set_ylabel("|flange x / shoulder torque| [m/(N m)]")
right.set_title("Shoulder torque to the flange's x position", fontsize=10)
right.grid(True, which="both", alpha=0.3)
right.legend(fontsize=8)
fig.suptitle("Franka Emika Panda (models/robots/urdf/panda.urdf) with elastic joints, from its URDF", fontsize=11)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}: lowest mode {frequencies[:, 0].min():.2f}-{frequencies[:, 0].max():.2f} Hz over joint 2 in [-1.2, 1.2] rad")
