"""Errors, memory, the GIL and the streaming form."""
import os
import sys
import threading
import time

import numpy as np
import pytest

import yawdepth
from conftest import run_cli, simulate


def cli_error(*args):
    """The one-line message `yawdepth` prints for a failing command (after 'error: ')."""
    r = run_cli(*args, check=False)
    assert r.returncode != 0
    line = r.stderr.strip().splitlines()[-1]
    assert ": error: " in line, line
    return line.split(": error: ", 1)[1]


def test_error_is_a_value_error_with_the_cli_message(planar_scene, tmp_path):
    assert issubclass(yawdepth.Error, ValueError)
    missing = str(tmp_path / "missing.yaml")
    expected = cli_error("estimate", "--camera", missing, "--rig", planar_scene["rig"], "--motion",
                         planar_scene["motion"], "--tracks", planar_scene["tracks"])
    with pytest.raises(yawdepth.Error) as e:
        yawdepth.loadCameraFile(missing)
    assert str(e.value) == expected
    dup = tmp_path / "dup.csv"
    dup.write_text("frame,id,u,v\n0,1,10,20\n0,1,11,21\n")
    expected = cli_error("estimate", "--camera", planar_scene["camera"], "--rig", planar_scene["rig"], "--motion",
                         planar_scene["motion"], "--tracks", str(dup))
    with pytest.raises(yawdepth.Error) as e:
        yawdepth.readTracksCsv(str(dup))
    assert str(e.value) == expected
    bad_rig = tmp_path / "rig.yaml"
    bad_rig.write_text("camera_ofset: [0, 0, 0]\n")
    expected = cli_error("estimate", "--camera", planar_scene["camera"], "--rig", str(bad_rig), "--motion",
                         planar_scene["motion"], "--tracks", planar_scene["tracks"])
    with pytest.raises(yawdepth.Error) as e:
        yawdepth.readRigFile(str(bad_rig))
    assert str(e.value) == expected


def test_errors_of_options_and_arrays(planar_scene):
    camera = yawdepth.loadCameraFile(planar_scene["camera"])
    rig = yawdepth.YawRig(camera_offset=[-0.1503, 0, 0])
    motion = yawdepth.readMotionCsv(planar_scene["motion"])
    tracks = yawdepth.readTracksCsv(planar_scene["tracks"])
    with pytest.raises(yawdepth.Error, match="method"):
        yawdepth.estimatePoints(camera, rig, motion, tracks, method="nope")
    with pytest.raises(yawdepth.Error):
        yawdepth.estimatePoints(camera, rig, motion, tracks, method="fused", sigma_px=-1)
    with pytest.raises(yawdepth.Error, match=r"\(N, 4\)"):
        yawdepth.estimatePoints(camera, rig, motion, tracks[:, :3], method="fused")
    with pytest.raises(yawdepth.Error, match="repeated"):
        yawdepth.estimatePoints(camera, rig, motion, np.vstack([tracks[:1], tracks[:1]]))
    with pytest.raises(yawdepth.Error, match="not an integer"):
        yawdepth.estimatePoints(camera, rig, motion, tracks + [0.5, 0, 0, 0])
    with pytest.raises(yawdepth.Error):  # a frame not in the motion (the C++ check)
        yawdepth.estimatePoints(camera, rig, motion.samples[:3], tracks, method="fused")
    with pytest.raises(yawdepth.Error, match="rigid"):
        yawdepth.YawRig(camera_pose=np.ones((4, 4)))
    with pytest.raises(TypeError):
        yawdepth.estimatePoints(camera, rig, motion, tracks, sigma_pix=1)


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_ten_thousand_estimates_do_not_grow_memory(planar_scene):
    """10 000 estimates (5 points x 10 frames, fused): resident memory grows by under 4 MB, and the
    inputs' reference counts are unchanged. Each call makes an Estimate, its points array, lists and
    C++ vectors of over 1 KB together: a leak of any of them would grow memory by over 10 MB."""
    camera = yawdepth.loadCameraFile(planar_scene["camera"])
    rig = yawdepth.YawRig(camera_offset=[-0.1503, 0, 0])
    motion = yawdepth.readMotionCsv(planar_scene["motion"]).samples
    tracks = yawdepth.readTracksCsv(planar_scene["tracks"])
    tracks = tracks[tracks[:, 1] < 5]
    refs = [sys.getrefcount(x) for x in (camera, rig, motion, tracks)]
    for _ in range(1000):  # warm-up: allocator pools, numpy's caches
        e = yawdepth.estimatePoints(camera, rig, motion, tracks, method="fused")
        e.points, e.outliers, e.c_cov
    before = rss_bytes()
    for _ in range(10000):
        e = yawdepth.estimatePoints(camera, rig, motion, tracks, method="fused")
        e.points, e.outliers, e.c_cov, e.warnings, e.motion
    grown = rss_bytes() - before
    assert grown < 4 * 1024 * 1024, f"memory grew by {grown} bytes over 10000 estimates"
    assert [sys.getrefcount(x) for x in (camera, rig, motion, tracks)] == refs
    assert (e.points["status"] == "ok").sum() >= 3


def test_a_python_thread_runs_during_an_estimate(tmp_path):
    scene = simulate(str(tmp_path), "--frames", 20, "--points", 3000, "--sigma-px", 0.3, "--seed", 2)
    camera = yawdepth.loadCameraFile(scene["camera"])
    rig = yawdepth.readRigFile(scene["rig"]).rig()
    motion = yawdepth.readMotionCsv(scene["motion"])
    tracks = yawdepth.readTracksCsv(scene["tracks"])
    count = [0]
    stop = threading.Event()

    def counter():
        while not stop.is_set():
            count[0] += 1

    t = threading.Thread(target=counter)
    t.start()
    try:
        time.sleep(0.05)
        c0, t0 = count[0], time.perf_counter()
        e = yawdepth.estimatePoints(camera, rig, motion, tracks, method="fused")
        c1, t1 = count[0], time.perf_counter()
    finally:
        stop.set()
        t.join()
    assert t1 - t0 > 0.05, "the estimate is too short to tell"
    # Holding the GIL, the call would let the counter run for at most a switch interval (5 ms) or so.
    assert c1 - c0 > 1000, f"the thread counted {c1 - c0} during a {t1 - t0:.3f} s estimate"
    assert len(e.points) == 3000


def project(K, cMw, w_P):
    c_P = cMw[:3, :3] @ w_P + cMw[:3, 3]
    return K[0, 0] * c_P[0] / c_P[2] + K[0, 2], K[1, 1] * c_P[1] / c_P[2] + K[1, 2], c_P[2]


def test_depth_provider_on_a_simulated_camera():
    """A camera translating sideways past 4 points: DepthProvider's depths converge to the true ones."""
    camera = yawdepth.CameraModel.brown(600, 600, 320, 240, [], 640, 480)
    rig = yawdepth.YawRig(camera_pose=np.eye(4))  # the vision frame is the camera
    provider = yawdepth.DepthProvider(camera, rig)
    options = yawdepth.DepthProviderOptions()
    assert options.method == "window" and options.prior_depth == 1.0
    points = {1: [0.1, 0.1, 1.5], 2: [-0.1, 0.1, 2.0], 3: [0.1, -0.1, 1.0], 4: [-0.1, -0.1, 2.5]}
    rng = np.random.default_rng(1)
    K = camera.K
    for k in range(60):
        wMc = np.eye(4)
        wMc[:3, 3] = [0.005 * k, 0, 0.002 * k]
        cMw = np.linalg.inv(wMc)
        seen = {}
        for i, w_P in points.items():
            u, v, _ = project(K, cMw, np.array(w_P))
            seen[i] = (u + rng.normal(0, 0.2), v + rng.normal(0, 0.2))
        provider.update(wMc, seen)
    assert provider.periods == 60 and provider.estimatorFrames > 10
    for i, w_P in points.items():
        Z = project(K, np.linalg.inv(wMc), np.array(w_P))[2]
        info = provider.info(i)
        assert info.converged and provider.converged(i) and provider.status(i) == "ok"
        assert abs(provider.depth(i) - Z) < 3 * provider.sigma(i) + 1e-3, (i, provider.depth(i), Z)
        assert abs(provider.estimate(i).c_P[2] - Z) < 3 * provider.estimate(i).sigmaZ + 1e-3
    # the array form of the same period
    provider.update(wMc, np.array([[i, *seen[i]] for i in seen]))
    with pytest.raises(yawdepth.Error):
        provider.update(np.full((4, 4), np.nan), seen)


def test_stream_estimator_equals_batch_window(planar_scene):
    """Frame by frame through StreamEstimator(window) gives the batch window method's ok points."""
    camera = yawdepth.loadCameraFile(planar_scene["camera"])
    rig = yawdepth.readRigFile(planar_scene["rig"]).rig()
    motion = yawdepth.readMotionCsv(planar_scene["motion"]).samples
    tracks = yawdepth.readTracksCsv(planar_scene["tracks"])
    stream = yawdepth.StreamEstimator(camera, rig)
    assert stream.method == "window"
    for row in motion:
        at = tracks[tracks[:, 0] == row[0]]
        stream.addFrame(row, at[:, 1:])
    batch = yawdepth.estimatePoints(camera, rig, motion, tracks, method="window")
    ok = 0
    for p in batch.points:
        e = stream.estimate(int(p["id"]))
        if p["status"] == "ok":
            ok += 1
            np.testing.assert_allclose(e.c_P, [p["xc"], p["yc"], p["zc"]], rtol=1e-9)
    assert ok >= 20
    last = stream.estimateAt(int(batch.points[0]["id"]), motion[-1])
    assert last.frame == motion[-1][0]
