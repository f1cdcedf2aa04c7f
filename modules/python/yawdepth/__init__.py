"""yawdepth: depth of 3D points from one moving camera of known motion (C++ on ViSP), from Python.

The names are the C++ names (docs/python.md); arrays are numpy float64, lengths in metres, angles in
radians, pixels in px. Errors of the C++ library are raised as ``yawdepth.Error`` (a subclass of
``ValueError``) with the C++ one-line message.

Files, as the command line reads them:
    camera = yawdepth.loadCameraFile("camera.yaml")                  # CameraModel
    rig_file = yawdepth.readRigFile("rig.yaml"); rig = rig_file.rig()  # RigFile, YawRig
    motion = yawdepth.loadMotion("motion.csv", rig_file)             # MotionLog
    yawdepth.checkMotionSteps(motion, "motion.csv"); yawdepth.applyRigFile(rig_file, motion)
    tracks = yawdepth.readTracksCsv("tracks.csv")                    # (M, 4) [frame, id, u, v]
    yawdepth.checkTracksAgainstMotion(tracks, motion, "tracks.csv")  # the CLI's message for a frame not in the log
    result = yawdepth.estimatePoints(camera, rig, motion, tracks, method="exact")
    result.points                                                    # structured array, the CSV's columns

or from numbers: CameraModel.brown(fx, fy, u0, v0, coeffs, width, height), YawRig(camera_offset=...)
or YawRig(camera_pose=vMc0), motion as an (N, 6) / (N, 8) array. The streaming form:
DepthProvider (servo) and StreamEstimator.
"""
from ._yawdepth import *  # noqa: F401,F403 (every public C++ binding)
from ._yawdepth import Error, Estimate, PipelineOptions
from . import _yawdepth
import copy as _copy

__all__ = [n for n in dir(_yawdepth) if not n.startswith("_")] + ["estimatePoints", "writePointsCsv"]

# The keywords of estimatePoints() and where each one is set: PipelineOptions itself, its noise
# (NoiseModel), gates (GateOptions) or residual check (ResidualCheckOptions.enabled).
_PIPELINE = ("method", "robust_threshold_px", "outlier_threshold_px", "window", "threads", "drop_unusable",
             "max_depth_sigma", "noise", "gates")
_NOISE = ("sigma_px", "sigma_odom", "sigma_heading", "sigma_yaw", "sigma_rot", "odom_per_metre",
          "rot_per_radian", "rot_per_metre", "motion_noise", "pixel_correlation")
_GATES = ("min_baseline", "min_parallax_px")


def estimatePoints(camera, rig, motion, tracks, options=None, **keywords):
    """Estimate every track's 3D point (C++ yawdepth::estimatePoints, what `yawdepth estimate` runs).

    camera: CameraModel. rig: YawRig.
    motion: MotionLog, or an (N, 6) float64 array [frame, x (m), y (m), z (m), heading (rad), yaw (rad)]
        or (N, 8) [frame, tx, ty, tz (m), tux, tuy, tuz (rad, theta-u of wMv), yaw (rad)]; frames
        strictly increasing, every observed frame in it.
    tracks: (M, 4) float64 [frame, id, u (px), v (px)] (observed, distorted pixels; any row order).
    options: PipelineOptions (None: PipelineOptions(), the C++ defaults), then any of these keywords,
        named as the command line's options: method ('paper', 'exact', 'fused', 'window', 'refine'),
        sigma_px, sigma_odom, sigma_heading, sigma_yaw, sigma_rot, odom_per_metre, rot_per_radian,
        rot_per_metre, motion_noise, pixel_correlation, min_baseline, min_parallax_px, robust_threshold_px,
        outlier_threshold_px, window, threads, drop_unusable, residual_check (bool), max_depth_sigma,
        noise (NoiseModel), gates (GateOptions).
    `noise` and `gates` objects are applied before the single values, whatever the order given.
    As the command line, a 6-DoF MotionLog without a yaw column gets sigma_yaw 0 unless sigma_yaw
    is given (as a keyword, or in a `noise` or `options` passed).

    Returns an Estimate: .points, a structured array with the points CSV's columns (id, frame, x, y,
    z, xc, yc, zc, sigma_zc: m; status: str), one row per track in id order; .c_cov (P, 3, 3) m^2;
    .outliers, .motion, .warnings and the consistency figures (see help(yawdepth.Estimate)).
    The GIL is released while the method runs. Raises yawdepth.Error with the C++ message.
    """
    sigma_yaw_given = options is not None or "sigma_yaw" in keywords or "noise" in keywords
    o = PipelineOptions() if options is None else _copy.copy(options)  # the caller's is not changed
    # whole objects first, then the single values (which may refine them), whatever the keywords' order
    for key in ("noise", "gates"):
        if key in keywords:
            setattr(o, key, keywords[key])
    for key, value in keywords.items():
        if key in ("noise", "gates"):
            continue
        if key in _NOISE:
            setattr(o.noise, key, value)
        elif key in _GATES:
            setattr(o.gates, key, value)
        elif key == "residual_check":
            o.residual_check.enabled = bool(value)
        elif key in _PIPELINE:
            setattr(o, key, value)
        else:
            raise TypeError(f"estimatePoints() got an unexpected keyword argument '{key}'")
    return _yawdepth._estimatePoints(camera, rig, motion, tracks, o, sigma_yaw_given)


def writePointsCsv(path, points):
    """Write points as the points CSV (header id,frame,x,y,z,xc,yc,zc,sigma_zc,status, 17 significant
    digits, numbers empty unless ok), atomically: `points` an Estimate (byte for byte what `yawdepth
    estimate --out` writes for it) or a structured points array."""
    if isinstance(points, Estimate):
        _yawdepth._writeEstimateCsv(path, points)
    else:
        _yawdepth.writePointsCsv(path, points)
