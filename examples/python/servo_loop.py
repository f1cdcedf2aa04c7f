#!/usr/bin/python3
"""A servo-style loop: a simulated camera moves toward 4 points; each control period feeds its pose
and the 4 pixels to yawdepth.DepthProvider and reads the depths an image-based servo would use.

    /usr/bin/python3 examples/python/servo_loop.py
"""
import numpy as np

import yawdepth

camera = yawdepth.CameraModel.brown(fx=600, fy=600, u0=320, v0=240, coeffs=[], width=640, height=480)
rig = yawdepth.YawRig(camera_pose=np.eye(4))  # no pan joint: the vision frame is the camera itself
provider = yawdepth.DepthProvider(camera, rig)  # DepthProviderOptions(): the C++ defaults

w_P = np.array([[0.1, 0.1, 1.0], [-0.1, 0.1, 1.0], [-0.1, -0.1, 1.2], [0.1, -0.1, 1.2]])  # the 4 points (m)
rng = np.random.default_rng(0)
wMc = np.eye(4)
for period in range(80):
    # the "robot": a little sideways and forward each period (a servo's velocity, integrated)
    wMc[:3, 3] += [0.004 * np.cos(period / 10), 0.002, 0.004]
    cMw = np.linalg.inv(wMc)
    c_P = w_P @ cMw[:3, :3].T + cMw[:3, 3]
    u = camera.kx * c_P[:, 0] / c_P[:, 2] + camera.u0 + rng.normal(0, 0.2, 4)
    v = camera.ky * c_P[:, 1] / c_P[:, 2] + camera.v0 + rng.normal(0, 0.2, 4)
    provider.update(wMc, {i: (u[i], v[i]) for i in range(4)})  # wMv: (4, 4) pose; {id: (u, v)} px
    if period % 20 == 19:
        depths = [f"{provider.depth(i):.3f}{'*' if provider.converged(i) else ' '}" for i in range(4)]
        truth = " ".join(f"{z:.3f}" for z in c_P[:, 2])
        print(f"period {period + 1:3d}: depth (m, * converged) {' '.join(depths)}   truth {truth}")
