#!/usr/bin/python3
"""Estimate points from arrays a script holds, and plot each depth with its 2-sigma bar.

    /usr/bin/python3 examples/python/estimate_and_plot.py [OUT.png]

A camera (numbers), a rig (camera 15 cm beside the yaw axis), a robot driving 10 frames straight
ahead while the camera pans, 30 random points: the pixels are projected here with numpy and given
noise, then yawdepth.estimatePoints() measures them.
"""
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import yawdepth  # noqa: E402

camera = yawdepth.CameraModel.brown(fx=600, fy=600, u0=320, v0=240, coeffs=[], width=640, height=480)
rig = yawdepth.YawRig(camera_offset=[-0.15, 0.0, 0.0])  # optical centre in the vision frame at yaw 0 (m)

# motion: (N, 6) [frame, x, y, z, heading, yaw]: 2 cm forward (+Z) per frame, the camera panning
frames = np.arange(10)
motion = np.column_stack([frames, 0 * frames, 0 * frames, 0.02 * frames, 0 * frames, 0.01 * frames]).astype(float)

# 30 points in the world (m), seen from every frame
rng = np.random.default_rng(4)
w_P = np.column_stack([rng.uniform(-0.6, 0.6, 30), rng.uniform(-0.4, 0.4, 30), rng.uniform(1.0, 3.0, 30)])
rows = []
for f, x, y, z, heading, yaw in motion:
    wMv = np.eye(4)
    wMv[:3, 3] = [x, y, z]  # heading 0: the vision frame's axes are the world's
    cMw = np.linalg.inv(wMv @ rig.vMc(yaw))
    c_P = w_P @ cMw[:3, :3].T + cMw[:3, 3]
    u = camera.kx * c_P[:, 0] / c_P[:, 2] + camera.u0 + rng.normal(0, 0.3, 30)
    v = camera.ky * c_P[:, 1] / c_P[:, 2] + camera.v0 + rng.normal(0, 0.3, 30)
    rows += [[f, i, u[i], v[i]] for i in range(30)]
tracks = np.array(rows)  # (M, 4) [frame, id, u (px), v (px)]

result = yawdepth.estimatePoints(camera, rig, motion, tracks, method="fused", sigma_px=0.3)
p = result.points
ok = p["status"] == "ok"
print(f"{ok.sum()} of {len(p)} points ok; warnings: {result.warnings}")

# the truth at the last frame, for the plot
wMv = np.eye(4)
wMv[:3, 3] = motion[-1, 1:4]
cMw = np.linalg.inv(wMv @ rig.vMc(motion[-1, 5]))
truth = (w_P @ cMw[:3, :3].T + cMw[:3, 3])[:, 2]

fig, ax = plt.subplots(figsize=(7, 4))
ax.errorbar(p["id"][ok], p["zc"][ok], yerr=2 * p["sigma_zc"][ok], fmt="o", ms=3, capsize=2, label="estimate ± 2σ")
ax.plot(p["id"], truth[p["id"]], "k+", label="truth")
ax.set_xlabel("feature id")
ax.set_ylabel("depth zc at the last frame (m)")
ax.legend()
out = sys.argv[1] if len(sys.argv) > 1 else "depths.png"
fig.savefig(out, dpi=100, bbox_inches="tight")
print(f"wrote {out}")
