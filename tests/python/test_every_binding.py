"""Every public binding (function, class, method, property) is named in this suite's tests, and the
leftovers are called here."""
import glob
import os
import re

import numpy as np
import pytest

import yawdepth

HERE = os.path.dirname(os.path.abspath(__file__))


def suite_text():
    return "\n".join(open(p).read() for p in glob.glob(os.path.join(HERE, "test_*.py")))


def test_every_binding_is_called_somewhere():
    text = suite_text()
    missing = []
    for name in yawdepth.__all__:
        if not re.search(rf"\b{name}\b", text):
            missing.append(name)
        obj = getattr(yawdepth, name)
        if isinstance(obj, type) and not issubclass(obj, BaseException):
            for member in vars(obj):
                if not member.startswith("_") and not re.search(rf"\.{member}\b|\b{member}=", text):
                    missing.append(f"{name}.{member}")
    assert not missing, f"not used by any test: {missing}"


def test_the_leftovers(tmp_path):
    camera = yawdepth.CameraModel.brown(600, 600, 320, 240, [0.01, 0, 0, 0], 640, 480)
    yawdepth.checkCameraPlausible(camera, "numbers")
    with pytest.raises(yawdepth.Error, match="implausible"):
        yawdepth.checkCameraPlausible(yawdepth.CameraModel.brown(600, 600, 5000, 240, [], 640, 480), "far")
    rig = yawdepth.YawRig(camera_offset=[0.1, 0, 0])
    np.testing.assert_array_equal(rig.cameraOffset.ravel(), [0.1, 0, 0])
    np.testing.assert_array_equal(rig.cameraRotation, np.eye(3))
    assert rig.axisAligned
    rf = yawdepth.RigFile()
    rf.camera_pose = [0, 0, 0, 0, 0.1, 0]
    rf.time_offset = 0.02
    assert rf.camera_pose.shape == (6, 1) and not rf.rig().axisAligned and rf.time_offset == 0.02
    rf.camera_pose = None
    log = yawdepth.MotionLog(np.array([[0, 0, 0, 0, 0, 0], [1, 0, 0, 0.05, 0, 0.01]], float))
    assert len(log) == 2 and not log.six_dof and log.yaw_column and log.images == [] and log.times == []
    log.images = ["a.png", "b.png"]
    log.times = [0.0, 0.1]
    yawdepth.writeMotionCsv(str(tmp_path / "m.csv"), log.samples)
    (tmp_path / "nyaw.csv").write_text("frame,x,y,z,heading\n0,0,0,0,0\n1,0,0,0.05,0\n")
    fixed = yawdepth.readMotionCsv(str(tmp_path / "nyaw.csv"), fixed_yaw=0.2)
    assert not fixed.yaw_column and (fixed.samples[:, 5] == 0.2).all()
    with pytest.raises(yawdepth.Error):
        yawdepth.checkTracksAgainstMotion(np.array([[5, 1, 10, 10]], float), log, "t.csv")
    for o in (yawdepth.NoiseModel(), yawdepth.GateOptions(), yawdepth.PipelineOptions(),
              yawdepth.DepthProviderOptions(), yawdepth.KltOptions(), yawdepth.ErrorAnalysisCase()):
        o.validate()
    n = yawdepth.NoiseModel()
    n.motion_noise = "absolute"
    n.sigma_heading, n.sigma_rot, n.odom_per_metre, n.rot_per_radian, n.rot_per_metre = 0.01, 0.01, 0, 0, 0
    n.pixel_correlation = 0.5
    n.validate()
    n.pixel_correlation = 1.0
    with pytest.raises(yawdepth.Error):
        n.validate()
    n.pixel_correlation = 0.0
    g = yawdepth.GateOptions()
    g.min_baseline = 1e-4
    r = yawdepth.ResidualCheckOptions()
    r.gate_probability, r.scale_sigma, r.min_tracks, r.correlated, r.reestimate_noise = 0.99, False, 5, False, False
    p = yawdepth.PipelineOptions()
    p.noise, p.gates, p.residual_check = n, g, r
    p.robust_threshold_px, p.outlier_threshold_px, p.threads, p.drop_unusable = 1.5, 3.0, 1, True
    assert p.noise.motion_noise == "absolute" and p.gates.min_baseline == 1e-4 and p.residual_check.min_tracks == 5
    assert yawdepth.methodAvailable("fused") and yawdepth.bestMethod() in ("fused", "refine")

    # the servo's other calls: options, odometry rows, a prior, the fused stream
    o = yawdepth.DepthProviderOptions()
    o.method, o.window, o.prior_depth, o.prior_relative_sigma = "fused", 10, 2.0, 1.0
    o.converged_relative_sigma, o.release_factor, o.revoke_sigmas, o.confirm_periods = 0.1, 2.0, 4.0, 3
    o.min_depth, o.max_depth, o.min_translation, o.max_skipped_periods = 0.05, 100.0, 0.002, 50
    o.initial_depth, o.max_missing_frames, o.noise = 0.0, 30, o.noise
    provider = yawdepth.DepthProvider(camera, yawdepth.YawRig(camera_pose=np.eye(4)), o)
    provider.setPrior(7, 3.0)
    provider.updateOdometry([0, 0, 0, 0, 0, 0], {7: (330.0, 250.0)})
    assert provider.depth(7) == 3.0 and provider.sigma(7) > 0 and not provider.converged(7)
    info = provider.info(7)
    assert isinstance(info, yawdepth.FeatureDepth) and isinstance(provider.estimate(7), yawdepth.PointEstimate)
    assert info.id == 7 and info.depth == 3.0 and info.sigma > 0 and info.status == "too_few_frames"
    assert np.isnan(info.estimate) and np.isnan(info.estimate_sigma) and info.revocations == 0
    e = provider.estimate(7)
    assert not e.ok and e.frame >= 0 and e.v_P.shape == (3,) and e.c_cov.shape == (3, 3) and e.parallax_px == e.parallax_px
    s = yawdepth.StreamOptions()
    s.method, s.noise, s.gates, s.window = "fused", n, g, 5
    s.robust_threshold_px, s.outlier_threshold_px, s.prior_depth, s.max_missing_frames = 1.0, 2.0, 3.0, 30
    assert s.prior_depth == 3.0 and s.noise.sigma_px == n.sigma_px
    with pytest.raises(AttributeError):  # one noise model: the per-method ones are gone
        s.fused_sigma_px = 0.4
    with pytest.raises(Exception, match="does not run frame by frame"):
        s.method = "paper"
    stream = yawdepth.StreamEstimator(camera, rig, s)
    stream.addFrame([0, 0, 0, 0, 0, 0], np.array([[1, 300.0, 200.0]]))
    stream.forget(1)
    assert stream.method == "fused" and stream.estimate(1).status == "too_few_frames"
    d = yawdepth.DetectorOptions()
    d.subpixel, d.subpixel_window, d.apriltag_decimate, d.threads = True, 0, 1.0, 1
    k = yawdepth.KltOptions()
    k.max_features, k.min_distance, k.quality, k.block_size, k.window = 100, 10.0, 0.01, 7, 21
    k.pyramid_levels, k.forward_backward_px, k.redetect_fraction, k.border_px = 3, 0.5, 0.8, 8.0
    k.gate_sigmas, k.sigma_px, k.min_depth = 4.0, 0.5, 0.1
    k.max_depth, k.guided_min_ncc, k.ambiguity_margin, k.guided_levels = float("inf"), 0.7, 0.1, 1
    assert k.guided == "auto"
    k.guided = "on"
    with pytest.raises(yawdepth.Error):
        k.guided = "sometimes"
    k.min_ncc, k.jump_sigmas = 0.9, 4.0
    k.validate()
    tracker = yawdepth.KltTracker(camera, k)
    image = (np.indices((480, 640)).sum(axis=0) % 255).astype(np.uint8)
    first = tracker.track(image)
    for f in first:
        tracker.setDepthHint(int(f[0]), 2.0, 0.1)
    second = tracker.track(image, cMp=np.eye(4), sigma_rot=0.001, sigma_trans=0.001)
    assert first.shape[1] == 3 and second.shape[1] == 3
    assert {"guided", "lost_ambiguous"} <= set(tracker.lastStats)
    assert tracker.lastStats["lost_appearance"] >= 0 and tracker.lastStats["split_jump"] >= 0
    c = yawdepth.CameraCalibrationOptions()
    c.fix_aspect_ratio, c.fix_principal_point, c.distortion, c.try_fisheye = False, False, "k5", False
    c.cv_folds, c.simpler_within, c.zero_tangential, c.drop_outliers = 5, 0.01, False, False
    c.outlier_ratio, c.outlier_min_px, c.min_views, c.min_points_per_view = 3.0, 0.5, 3, 6
    c.min_orientation_spread, c.fit_visp = 0.07, True
    assert c.distortion == "k5"
    with pytest.raises(yawdepth.Error):
        c.distortion = "k7"
    b = yawdepth.BoardLayout("apriltag:36h11:0.05")
    b.tags_x, b.tags_y, b.gap, b.first_tag_id, b.margin, b.outer_square = 2, 2, 0.0125, 0, 0, 0
    assert b.features().shape[0] == 4 * 5
    row = yawdepth.paperErrorCases()[0]
    assert isinstance(row, yawdepth.PaperErrorRow)
    case = yawdepth.ErrorAnalysisCase()
    case.u_offset, case.dz, case.delta_dz, case.delta_yaw, case.delta_u, case.delta_du = 10, 0.02, 1e-3, 1e-3, 0.1, 0.1
    assert isinstance(yawdepth.firstOrderDepthError(case), yawdepth.DepthErrorTerms)
    assert isinstance(yawdepth.monteCarloDepthError(case, 10), yawdepth.MonteCarloDepthError)
    assert row.view and row.input.kx > 0 and row.lateral_depth_error >= 0
    t = yawdepth.firstOrderDepthError(row.input)
    assert t.parallax_px != 0 and t.total > 0
    mc = yawdepth.monteCarloDepthError(row.input, 100)
    assert mc.bias_relative == mc.bias_relative


def test_result_fields(planar_scene):
    """The result objects' remaining fields, on a real estimate and a real calibration."""
    camera = yawdepth.loadCameraFile(planar_scene["camera"])
    rig = yawdepth.readRigFile(planar_scene["rig"]).rig()
    motion = yawdepth.readMotionCsv(planar_scene["motion"])
    tracks = yawdepth.readTracksCsv(planar_scene["tracks"])
    e = yawdepth.estimatePoints(camera, rig, motion, tracks, method="fused", residual_check=True)
    assert isinstance(e, yawdepth.Estimate)
    assert e.tracks_used >= 0 and e.mistake in (True, False) and e.noise_scale > 0 and e.variance_factor > 0
    assert e.sigma_scale >= 1 and e.inconsistent >= 0
    folder = os.path.join(os.path.dirname(HERE), "data", "franka-eye-in-hand")
    paths = [os.path.join(folder, f"franka_image-{i}.png") for i in range(1, 9)]
    board = yawdepth.BoardLayout("chessboard:9x6:0.0236")
    det = yawdepth.detectCalibrationViews(board, paths, [yawdepth.readGrayImage(p) for p in paths])
    assert isinstance(det, yawdepth.CalibrationDetections) and det.warnings == []
    assert all(isinstance(v, yawdepth.CalibrationView) and v.name for v in det.views)
    cal = yawdepth.calibrateCamera(board, det.views, det.width, det.height)
    assert isinstance(cal, yawdepth.CameraCalibration) and len(cal.std_devs) == 12 and cal.std_devs[0] > 0
    assert cal.orientation_spread > 0 and 0 < cal.coverage <= 1 and isinstance(cal.notes, list) and cal.model_reason
    assert cal.visp_rms_without >= cal.visp_rms_with > 0
    d = yawdepth.PatternDetector("chessboard:9x6:0.0236").detect(yawdepth.readGrayImage(paths[0]), 3)
    assert isinstance(d, yawdepth.FrameDetection) and d.frame == 3 and isinstance(d.warnings, list)
