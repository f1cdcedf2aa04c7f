"""Detection, KLT tracking and the error analysis against the command line (`measure --tracks-out`,
`track`, `error-analysis`) on the same rendered images: the same tracks files, byte for byte."""
import math
import os

import numpy as np
import pytest

import yawdepth
from conftest import CALIB, run_cli, simulate

PATTERN = "chessboard:7x5:0.02"


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    """6 rendered frames of a chessboard on a textured wall (for both detection and KLT)."""
    d = str(tmp_path_factory.mktemp("images"))
    return simulate(d, "--frames", 6, "--pattern", PATTERN, "--wall", 0.05, "--supersampling", 2, "--step", 0.01)


def load(scene):
    camera = yawdepth.loadCameraFile(scene["camera"])
    rig_file = yawdepth.readRigFile(scene["rig"])
    motion = yawdepth.loadMotion(scene["motion"], rig_file)
    yawdepth.checkMotionSteps(motion, scene["motion"])
    yawdepth.applyRigFile(rig_file, motion)
    return camera, rig_file.rig(), motion


def test_detection_as_measure(images, tmp_path):
    run_cli("measure", "--camera", images["camera"], "--rig", images["rig"], "--motion", images["motion"],
            "--pattern", PATTERN, "--tracks-out", tmp_path / "cli.csv", "--out", tmp_path / "points.csv", "--quiet")
    camera, rig, motion = load(images)
    detector = yawdepth.PatternDetector(PATTERN)
    detector.setCamera(camera)
    detections = []
    for row, path in zip(motion.samples, motion.images):
        image = yawdepth.readGrayImage(path, camera)
        assert image.dtype == np.uint8 and image.shape == (camera.height, camera.width)
        d = detector.detect(image, int(row[0]))
        assert d.found, d.reason
        assert d.features.shape == (35, 3)
        detections.append(d)
    tracks = yawdepth.PatternDetector.toTracks(detections)
    yawdepth.writeTracksCsv(str(tmp_path / "py.csv"), tracks)
    assert (tmp_path / "py.csv").read_text() == (tmp_path / "cli.csv").read_text()
    # a numpy image that is not C-contiguous (a view) gives the same features
    image = yawdepth.readGrayImage(motion.images[0], camera)
    flipped = np.ascontiguousarray(image[:, ::-1])[:, ::-1]
    again = yawdepth.PatternDetector(PATTERN)
    again.setCamera(camera)
    np.testing.assert_array_equal(again.detect(flipped, 0).features, detections[0].features)
    nothing = yawdepth.PatternDetector(PATTERN).detect(np.zeros((480, 640), np.uint8), 9)
    assert not nothing.found and nothing.reason and nothing.features.shape == (0, 3)
    with pytest.raises(yawdepth.Error):
        yawdepth.PatternDetector("chessboard:7x5")
    with pytest.raises(yawdepth.Error, match="2-D"):
        detector.detect(np.zeros((4, 4, 3), np.uint8), 0)


def test_klt_as_track(images, tmp_path):
    run_cli("track", "--camera", images["camera"], "--rig", images["rig"], "--motion", images["motion"],
            "--out", tmp_path / "cli.csv", "--quiet")
    camera, rig, motion = load(images)
    noise = yawdepth.noiseForMotionLog(yawdepth.NoiseModel(), motion.six_dof, motion.yaw_column, False)
    tracks, totals = yawdepth.trackSequence(camera, rig, motion, noise, yawdepth.KltOptions())
    yawdepth.writeTracksCsv(str(tmp_path / "py.csv"), tracks)
    assert (tmp_path / "py.csv").read_text() == (tmp_path / "cli.csv").read_text()
    assert len(tracks) > 100 and totals["detected"] > 100
    # frame by frame, ungated: the same as the sequence without the gate
    tracker = yawdepth.KltTracker(camera)
    seen = []
    for row, path in zip(motion.samples, motion.images):
        f = tracker.track(yawdepth.readGrayImage(path))
        seen.append(np.column_stack([np.full(len(f), row[0]), f]))
        assert tracker.lastStats["tracked"] + tracker.lastStats["detected"] == len(f)
    rows = np.vstack(seen)
    ungated, _ = yawdepth.trackSequence(camera, rig, motion, noise, gate=False)
    ids, counts = np.unique(rows[:, 1], return_counts=True)
    kept = rows[np.isin(rows[:, 1], ids[counts >= 2])]
    kept = kept[np.lexsort((kept[:, 0], kept[:, 1]))]
    np.testing.assert_array_equal(kept, ungated)
    with pytest.raises(yawdepth.Error):
        tracker.track(np.zeros((10, 10), np.uint8))  # not the camera's size


def test_error_analysis_as_cli():
    out = run_cli("error-analysis", "--depth", 0.6, "--monte-carlo", 1000, "--seed", 3).stdout.split("\n")
    header, values = out[0].split(), out[1].split()
    cells = dict(zip(header[1:], [v for v in " ".join(values[1:]).replace(" %", "%").split()]))
    c = yawdepth.ErrorAnalysisCase()
    c.depth = 0.6
    t = yawdepth.firstOrderDepthError(c)
    assert yawdepth.formatPaperTerm(t.odometry) == cells["odometry"]
    assert yawdepth.formatPaperTerm(t.yaw) == cells["yaw"]
    assert yawdepth.formatPaperTerm(t.pixel) == cells["pixel"]
    assert yawdepth.formatPaperTerm(t.parallax) == cells["parallax"]
    assert yawdepth.formatPercent(t.total).replace(" ", "") == cells["total"]
    assert yawdepth.formatPercent(yawdepth.firstOrderDepthSigma(c)).replace(" ", "") == cells["1sigma_fo"]
    mc = yawdepth.monteCarloDepthError(c, 1000, 3)
    assert mc.samples == 1000
    assert yawdepth.formatPercent(mc.rms_relative).replace(" ", "") == cells["mc_rms"]
    assert yawdepth.formatPercent(mc.median_abs_relative).replace(" ", "") == cells["mc_median"]
    rows = yawdepth.paperErrorCases()
    assert [r.view for r in rows][:2] == ["front", "side"] or len(rows) >= 2
    assert math.isclose(yawdepth.lateralRelativeError(0.1, 1700, 10, 0.05), 0.1 / 1700 + 10 / 1700 * 0.05)
    bad = yawdepth.ErrorAnalysisCase()
    bad.depth = -1
    with pytest.raises(yawdepth.Error):
        bad.validate()


def test_camera_calibration_as_cli(tmp_path):
    """calibrate-camera on the 8 real photographs of tests/data/franka-eye-in-hand: the same camera
    file (OpenCV YAML and ViSP XML) and RMS."""
    folder = os.path.join(os.path.dirname(CALIB), "tests", "data", "franka-eye-in-hand")
    paths = [os.path.join(folder, f"franka_image-{i}.png") for i in range(1, 9)]
    out = run_cli("calibrate-camera", "--pattern", "chessboard:9x6:0.0236", "--out", tmp_path / "cli", "--quiet",
                  *paths).stdout
    board = yawdepth.BoardLayout("chessboard:9x6:0.0236")
    assert board.features().shape == (54, 4)
    det = yawdepth.detectCalibrationViews(board, paths, [yawdepth.readGrayImage(p) for p in paths])
    assert len(det.views) == 8 and det.failures == [] and det.width > 0
    cal = yawdepth.calibrateCamera(board, det.views, det.width, det.height, yawdepth.CameraCalibrationOptions())
    yawdepth.saveCameraYaml(str(tmp_path / "py.yaml"), cal.camera)
    assert (tmp_path / "py.yaml").read_text() == (tmp_path / "cli.yaml").read_text()
    assert f"RMS reprojection error: {cal.rms_px:.4f} px (8 views, 432 points)" in out
    assert cal.views_used == 8 and len(cal.view_rms_px) == 8 and cal.intrinsics_covariance.shape == (12, 12)
    assert cal.uncertainty_grid.shape == (6, 8) and any(chosen for _, _, chosen in cal.models)
    assert yawdepth.projectionUncertainty(cal, cal.camera.u0, cal.camera.v0) > 0
    yawdepth.saveVispCameraXml(str(tmp_path / "py.xml"), cal)
    assert yawdepth.loadCameraFile(str(tmp_path / "py.xml")).kx == yawdepth.loadCameraFile(str(tmp_path / "cli.xml")).kx
    view = yawdepth.CalibrationView("again", det.views[0].features)
    np.testing.assert_array_equal(view.features, det.views[0].features)
    with pytest.raises(yawdepth.Error, match="too few views"):
        yawdepth.calibrateCamera(board, det.views[:2], det.width, det.height)


def test_hand_eye_as_cli(tmp_path):
    """calibrate-rig --hand-eye eye-in-hand on the franka photographs: the same rig file."""
    folder = os.path.join(os.path.dirname(CALIB), "tests", "data", "franka-eye-in-hand")
    paths = [os.path.join(folder, f"franka_image-{i}.png") for i in range(1, 9)]
    run_cli("calibrate-camera", "--pattern", "chessboard:9x6:0.0236", "--out", tmp_path / "cam", "--quiet", *paths)
    motion_path = os.path.join(folder, "motion.csv")
    run_cli("calibrate-rig", "--hand-eye", "eye-in-hand", "--camera", tmp_path / "cam.yaml", "--motion", motion_path,
            "--pattern", "chessboard:9x6:0.0236", "--out", tmp_path / "cli.yaml")
    camera = yawdepth.loadCameraFile(str(tmp_path / "cam.yaml"))
    board = yawdepth.BoardLayout("chessboard:9x6:0.0236")
    motion = yawdepth.loadMotion(motion_path)
    detector = yawdepth.PatternDetector("chessboard:9x6:0.0236")
    detector.setCamera(camera)
    views = []
    for row, path in zip(motion.samples, motion.images):
        d = detector.detect(yawdepth.readGrayImage(path, camera), int(row[0]))
        if d.found:
            views.append(yawdepth.HandEyeView(yawdepth.wMv(row), d.features, path))
    options = yawdepth.HandEyeOptions()
    options.setup = "eye-in-hand"
    cal = yawdepth.calibrateHandEye(camera, board, views, options)
    assert yawdepth.handEyeRigYaml(cal) == (tmp_path / "cli.yaml").read_text()
    assert cal.camera_pose.shape == (4, 4) and cal.views == len(views) and cal.rms_px > 0
    np.testing.assert_allclose(cal.camera_pose[:3, 3], [0.0577148, -0.0339261, -0.0422745], atol=0.005)
    assert views[0].rMe.shape == (4, 4) and views[0].features.shape[1] == 3 and views[0].name == motion.images[0]
    assert cal.camera_pose_sigma.shape == (6,) and cal.target_pose.shape == (4, 4) and cal.target_pose_sigma[0] >= 0
    assert cal.initial_rms_px > 0 and cal.points > 0 and len(cal.view_rms_px) == len(cal.view_names)
    assert isinstance(cal, yawdepth.HandEyeCalibration) and isinstance(cal.skipped, list)
    assert cal.pose_correction_mm >= 0 and cal.pose_correction_deg >= 0
    o = yawdepth.HandEyeOptions()
    o.min_points_per_view, o.max_rms_px, o.sigma_px, o.sigma_pose_translation = 6, 20.0, 0.3, 1e-3
    o.sigma_pose_rotation, o.max_pose_correction_sigmas, o.check_board_scale = 0.002, 10.0, True
    with pytest.raises(yawdepth.Error):
        o.setup = "eye-on-foot"
    with pytest.raises(yawdepth.Error):
        yawdepth.calibrateHandEye(camera, board, views[:1], o)
    rig = yawdepth.YawRig(camera_pose=cal.camera_pose)
    a, b = motion.samples[0], motion.samples[1]
    np.testing.assert_allclose(yawdepth.curMprev(rig, a, b),
                               np.linalg.inv(yawdepth.wMc(rig, b)) @ yawdepth.wMc(rig, a), atol=1e-12)


def test_rig_calibration_as_cli(tmp_path):
    """calibrate-rig on 7 rendered views of a board while the camera pans 24 degrees: the same rig file."""
    camera_path = str(tmp_path / "wide.yaml")
    yawdepth.saveCameraYaml(camera_path, yawdepth.CameraModel.brown(400, 400, 320, 240, [], 640, 480))
    run_cli("simulate", "--camera", camera_path, "--rig", os.path.join(CALIB, "paper_rig.yaml"), "--out-dir",
            tmp_path / "rig", "--frames", 7, "--pattern", "chessboard:7x5:0.04", "--board-distance", 1.0,
            "--board-offset-x", 0.18, "--supersampling", 2, "--step", 0.03, "--yaw", -0.2, "--yaw-rate", 0.07)
    motion_path = str(tmp_path / "rig" / "motion.csv")
    run_cli("calibrate-rig", "--camera", camera_path, "--motion", motion_path, "--pattern", "chessboard:7x5:0.04",
            "--out", tmp_path / "cli.yaml")
    camera = yawdepth.loadCameraFile(camera_path)
    board = yawdepth.BoardLayout("chessboard:7x5:0.04")
    motion = yawdepth.loadMotion(motion_path)
    detector = yawdepth.PatternDetector("chessboard:7x5:0.04")
    detector.setCamera(camera)
    views = []
    for row, path in zip(motion.samples, motion.images):
        d = detector.detect(yawdepth.readGrayImage(path, camera), int(row[0]))
        if d.found:
            views.append(yawdepth.RigView(row, d.features))
    cal = yawdepth.calibrateRig(camera, board, views, yawdepth.RigCalibrationOptions())
    assert isinstance(cal, yawdepth.RigCalibration)
    text = yawdepth.rigCalibrationYaml(cal)
    assert text == (tmp_path / "cli.yaml").read_text()
    (tmp_path / "py.yaml").write_text(text)
    assert abs(yawdepth.readRigFile(str(tmp_path / "py.yaml")).camera_offset[0, 0] + 0.1503) < 0.005
    np.testing.assert_array_equal(views[0].row, motion.samples[0])
    assert views[0].features.shape == (35, 3) and cal.views == 7 and cal.points == 245 and cal.distinct_yaws == 7
    assert cal.rms_px < 0.5 and len(cal.view_rms_px) == 7 and cal.yaw_span > 0.35 and cal.baseline > 0.1
    assert cal.camera_offset.shape == (3,) and cal.camera_offset_sigma[0] > 0 and abs(cal.yaw_axis[1]) > 0.99
    assert cal.yaw_axis_sigma.shape == (3,) and cal.yaw_offset_sigma > 0 and abs(cal.yaw_offset) < 0.05
    o = yawdepth.RigCalibrationOptions()
    o.initial_offset, o.use_initial_offset, o.initial_yaw_offset, o.board_square = [-0.15, 0, 0], True, 0.0, False
    o.estimate_axis, o.min_yaw_span, o.min_distinct_yaws, o.min_baseline = False, 0.7, 3, 0.02
    o.min_points_per_view, o.max_rms_px, o.max_offset, o.max_offset_sigma = 4, 3.0, 2.0, 0.05
    o.check_board_scale = True
    np.testing.assert_array_equal(o.initial_offset.ravel(), [-0.15, 0, 0])
    with pytest.raises(yawdepth.Error, match="span"):
        yawdepth.calibrateRig(camera, board, views, o)  # 24 degrees < the 40 asked
