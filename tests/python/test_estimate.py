"""The estimation API against the command line: the same files give the same points CSV, byte for
byte (17 significant digits), and the arrays hold exactly the numbers the CLI printed."""
import csv
import math
import os

import numpy as np
import pytest

import yawdepth
from conftest import assert_points_equal, run_cli

METHODS = ["paper", "exact", "fused", "window"] + (["refine"] if yawdepth.methodAvailable("refine") else [])


def cli_points(scene, out, *options):
    run_cli("estimate", "--camera", scene["camera"], "--rig", scene["rig"], "--motion", scene["motion"],
            "--tracks", scene["tracks"], "--out", out, *options)
    with open(out) as f:
        return f.read()


def python_estimate(scene, **keywords):
    """What `yawdepth estimate` does, written from the docs: load, check, apply the rig file, estimate."""
    camera = yawdepth.loadCameraFile(scene["camera"])
    rig_file = yawdepth.readRigFile(scene["rig"])
    motion = yawdepth.loadMotion(scene["motion"], rig_file)
    yawdepth.checkMotionSteps(motion, scene["motion"])
    yawdepth.applyRigFile(rig_file, motion)
    tracks = yawdepth.readTracksCsv(scene["tracks"])
    yawdepth.checkTracksAgainstMotion(tracks, motion, scene["tracks"])
    return yawdepth.estimatePoints(camera, rig_file.rig(), motion, tracks, **keywords)


def assert_array_equals_csv(points, text):
    rows = list(csv.DictReader(text.splitlines()))
    assert len(rows) == len(points)
    for row, p in zip(rows, points):
        assert int(row["id"]) == p["id"] and int(row["frame"]) == p["frame"]
        assert row["status"] == p["status"]
        for c in ("x", "y", "z", "xc", "yc", "zc", "sigma_zc"):
            if row[c] == "":
                assert math.isnan(p[c])
            else:
                assert float(row[c]) == p[c], (c, row[c], repr(p[c]))  # exact: 17 digits round-trip


@pytest.mark.parametrize("method", METHODS)
def test_same_points_as_cli(planar_scene, tmp_path, method):
    text = cli_points(planar_scene, tmp_path / "cli.csv", "--method", method)
    est = python_estimate(planar_scene, method=method)
    yawdepth.writePointsCsv(str(tmp_path / "py.csv"), est)
    assert (tmp_path / "py.csv").read_text() == text
    assert_array_equals_csv(est.points, text)
    assert (est.points["status"] == "ok").sum() >= 20  # the scene is measurable: not a comparison of NaNs
    # the array written back gives the same file too
    yawdepth.writePointsCsv(str(tmp_path / "py2.csv"), est.points)
    assert (tmp_path / "py2.csv").read_text() == text


def test_options_as_cli(planar_scene, tmp_path):
    text = cli_points(planar_scene, tmp_path / "cli.csv", "--method", "fused", "--sigma-px", "0.5", "--sigma-odom",
                      "0.002", "--min-parallax-px", "0.5", "--residual-check", "on", "--max-depth-sigma", "0.05")
    est = python_estimate(planar_scene, method="fused", sigma_px=0.5, sigma_odom=0.002, min_parallax_px=0.5,
                          residual_check=True, max_depth_sigma=0.05)
    assert_array_equals_csv(est.points, text)
    opts = yawdepth.PipelineOptions()
    opts.method = "window"
    opts.noise.sigma_px = 0.4
    text = cli_points(planar_scene, tmp_path / "cli2.csv", "--method", "window", "--sigma-px", "0.4")
    assert_array_equals_csv(python_estimate(planar_scene, options=opts).points, text)
    assert opts.noise.sigma_px == 0.4 and opts.method == "window"  # the options given are not changed
    noise = yawdepth.NoiseModel()  # a whole object, then a single value refining it, in either order
    assert_array_equals_csv(python_estimate(planar_scene, sigma_px=0.4, noise=noise, method="window").points, text)
    assert noise.sigma_px == yawdepth.NoiseModel().sigma_px  # not changed either


def test_six_dof_as_cli(arm_scene, tmp_path):
    for method in ("exact", "fused"):
        text = cli_points(arm_scene, tmp_path / f"{method}.csv", "--method", method)
        est = python_estimate(arm_scene, method=method)
        assert_array_equals_csv(est.points, text)
        assert est.motion.shape[1] == 8


def test_arrays_in_equal_files_in(planar_scene):
    """Estimating from arrays a script holds gives what the files give."""
    camera = yawdepth.loadCameraFile(planar_scene["camera"])
    rig = yawdepth.YawRig(camera_offset=[-0.1503, 0.0, 0.0])
    motion = yawdepth.readMotionCsv(planar_scene["motion"]).samples
    tracks = yawdepth.readTracksCsv(planar_scene["tracks"])
    assert motion.shape[1] == 6 and motion.dtype == np.float64 and tracks.shape[1] == 4
    a = yawdepth.estimatePoints(camera, rig, motion, tracks[::-1].copy(), method="fused")  # row order free
    b = python_estimate(planar_scene, method="fused")
    assert_points_equal(a.points, b.points)
    np.testing.assert_array_equal(a.c_cov, b.c_cov)
    ok = a.points["status"] == "ok"
    np.testing.assert_array_equal(np.sqrt(a.c_cov[ok, 2, 2]), a.points["sigma_zc"][ok])
    assert len(a.outliers) == len(a.points) and all(o.dtype == bool for o in a.outliers)
    np.testing.assert_array_equal(a.motion, motion)
    assert isinstance(a.warnings, list) and a.s0 > 0 and 0 <= a.outlier_share <= 1 and len(a) == 30


def test_camera_from_numbers_equals_file(planar_scene, tmp_path):
    cam = yawdepth.loadCameraFile(planar_scene["camera"])
    built = yawdepth.CameraModel.brown(cam.kx, cam.ky, cam.u0, cam.v0, cam.coefficients, cam.width, cam.height)
    yawdepth.saveCameraYaml(str(tmp_path / "a.yaml"), cam)
    yawdepth.saveCameraYaml(str(tmp_path / "b.yaml"), built)
    assert (tmp_path / "a.yaml").read_text() == (tmp_path / "b.yaml").read_text()
    np.testing.assert_array_equal(cam.K, [[cam.kx, 0, cam.u0], [0, cam.ky, cam.v0], [0, 0, 1]])
    assert cam.width > 0 and "CameraModel(" in repr(cam)
    fish = yawdepth.CameraModel.kannalaBrandt(400, 400, 320, 240, [0.1, 0.01, 0, 0], 640, 480)
    assert fish.distortion == "kannala_brandt" and fish.coefficients == [0.1, 0.01, 0, 0]
    yawdepth.saveRosCameraInfoYaml(str(tmp_path / "ros.yaml"), fish, "fish")
    assert yawdepth.loadCameraFile(str(tmp_path / "ros.yaml")).coefficients == fish.coefficients


def test_rig_and_files_round_trip(planar_scene, tmp_path):
    rf = yawdepth.readRigFile(planar_scene["rig"])
    np.testing.assert_array_equal(rf.camera_offset.ravel(), [-0.1503, 0, 0])
    assert rf.camera_pose is None and rf.yaw is None and rf.yaw_offset == 0
    rig = rf.rig()
    np.testing.assert_allclose(rig.vMc(0.0)[:3, 3], [-0.1503, 0, 0])
    np.testing.assert_allclose(rig.vMc(0.3) @ rig.cMv(0.3), np.eye(4), atol=1e-15)
    pose = np.eye(4)
    pose[:3, 3] = [0.1, 0.2, 0.3]
    posed = yawdepth.YawRig(camera_pose=pose)
    np.testing.assert_allclose(posed.vMc(0.0), pose)
    rf.yaw_offset = 0.01
    yawdepth.writeRigFile(str(tmp_path / "rig.yaml"), rf)
    assert yawdepth.readRigFile(str(tmp_path / "rig.yaml")).yaw_offset == 0.01
    motion = yawdepth.readMotionCsv(planar_scene["motion"])
    yawdepth.writeMotionCsv(str(tmp_path / "m.csv"), motion)
    np.testing.assert_array_equal(yawdepth.readMotionCsv(str(tmp_path / "m.csv")).samples, motion.samples)
    before = motion.samples[:, 5].copy()
    yawdepth.applyRigFile(rf, motion)
    np.testing.assert_array_equal(motion.samples[:, 5], before + 0.01)
    tracks = yawdepth.readTracksCsv(planar_scene["tracks"])
    yawdepth.writeTracksCsv(str(tmp_path / "t.csv"), tracks)
    np.testing.assert_array_equal(yawdepth.readTracksCsv(str(tmp_path / "t.csv")), tracks)
    est = yawdepth.estimatePoints(yawdepth.loadCameraFile(planar_scene["camera"]), rig, motion, tracks)
    yawdepth.writePointsCsv(str(tmp_path / "p.csv"), est)
    assert_points_equal(yawdepth.readPointsCsv(str(tmp_path / "p.csv")), est.points)
    assert yawdepth.motionWarnings(motion, "m.csv") == [] and yawdepth.rigWarnings(rf, "rig.yaml") == []


def test_defaults_are_the_cpp_ones():
    o = yawdepth.PipelineOptions()
    assert o.method == "fused" and o.noise.sigma_px == 0.3 and o.gates.min_parallax_px == 0.02
    assert not o.residual_check.enabled and o.max_depth_sigma == 0 and o.window == 10
    assert yawdepth.bestMethod() in ("fused", "refine")
    n = yawdepth.noiseForMotionLog(yawdepth.NoiseModel(), True, False, False)
    assert n.sigma_yaw == 0 and yawdepth.noiseForMotionLog(yawdepth.NoiseModel(), True, False, True).sigma_yaw > 0


def test_six_dof_without_yaw_column_as_cli(arm_scene, tmp_path):
    """A 6-DoF log without a yaw column: sigma_yaw 0 unless given (noiseForMotionLog), as the CLI."""
    lines = open(arm_scene["motion"]).read().splitlines()
    header = lines[0].split(",")
    k = header.index("yaw")
    noyaw = tmp_path / "noyaw.csv"
    noyaw.write_text("\n".join(",".join(c for j, c in enumerate(l.split(",")) if j != k) for l in lines) + "\n")
    scene = dict(arm_scene, motion=str(noyaw))
    assert not yawdepth.readMotionCsv(str(noyaw)).yaw_column
    text = cli_points(scene, tmp_path / "a.csv", "--method", "fused")
    assert_array_equals_csv(python_estimate(scene, method="fused").points, text)
    given = cli_points(scene, tmp_path / "b.csv", "--method", "fused", "--sigma-yaw", "0.001")
    assert given != text  # the policy matters on this log
    assert_array_equals_csv(python_estimate(scene, method="fused", sigma_yaw=0.001).points, given)


def test_the_docs_program_gives_the_cli_points(planar_scene, tmp_path):
    """docs/python.md's program for `yawdepth estimate ... --method exact`, run as written (C, R, M, T
    replaced by the scene's files): the CLI's points file, byte for byte."""
    from conftest import SOURCE
    text = open(os.path.join(SOURCE, "docs", "python.md")).read()
    start = text.index("```python\n", text.index("does, in Python:")) + len("```python\n")
    program = text[start:text.index("```", start)]
    for name, key in (("C", "camera"), ("R", "rig"), ("M", "motion"), ("T", "tracks")):
        program = program.replace(f'"{name}"', repr(planar_scene[key]))
    program = program.replace('"points.csv"', repr(str(tmp_path / "py.csv")))
    exec(compile(program, "docs/python.md", "exec"), {})
    assert (tmp_path / "py.csv").read_text() == cli_points(planar_scene, tmp_path / "cli.csv", "--method", "exact")
