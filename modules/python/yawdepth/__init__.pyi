# Type stubs of the yawdepth Python module (docs/python.md). Arrays are float64 unless said.
from typing import Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
ArrayLike = npt.ArrayLike
#: Features of one period: {id: (u, v)} or an (K, 3) array [id, u (px), v (px)].
Features = Union[Mapping[int, Tuple[float, float]], ArrayLike]

class Error(ValueError):
    """yawdepth::Error: the C++ one-line message."""

class CameraModel:
    @staticmethod
    def brown(fx: float, fy: float, u0: float, v0: float, coeffs: Sequence[float] = ..., width: int = 0,
              height: int = 0) -> CameraModel: ...
    @staticmethod
    def kannalaBrandt(fx: float, fy: float, u0: float, v0: float, k: Sequence[float], width: int = 0,
                      height: int = 0) -> CameraModel: ...
    @property
    def kx(self) -> float: ...
    @property
    def ky(self) -> float: ...
    @property
    def u0(self) -> float: ...
    @property
    def v0(self) -> float: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def K(self) -> Array: ...
    @property
    def distortion(self) -> str: ...
    @property
    def coefficients(self) -> List[float]: ...

def loadCameraFile(path: str, camera_name: str = "") -> CameraModel: ...
def checkCameraPlausible(camera: CameraModel, what: str) -> None: ...
def saveCameraYaml(path: str, camera: CameraModel) -> None: ...
def saveRosCameraInfoYaml(path: str, camera: CameraModel, camera_name: str = "") -> None: ...

class YawRig:
    def __init__(self, camera_offset: Optional[ArrayLike] = None, camera_pose: Optional[ArrayLike] = None) -> None: ...
    @property
    def cameraOffset(self) -> Array: ...
    @property
    def cameraRotation(self) -> Array: ...
    @property
    def axisAligned(self) -> bool: ...
    def vMc(self, yaw: float) -> Array: ...
    def cMv(self, yaw: float) -> Array: ...

class RigFile:
    camera_offset: Array
    camera_pose: Optional[Array]
    yaw: Optional[float]
    yaw_offset: float
    time_offset: Optional[float]
    def __init__(self) -> None: ...
    def rig(self) -> YawRig: ...

def readRigFile(path: str) -> RigFile: ...
def writeRigFile(path: str, rig_file: RigFile) -> None: ...
def rigWarnings(rig_file: RigFile, rig_path: str) -> List[str]: ...

class MotionLog:
    samples: Array
    images: List[str]
    yaw_column: bool
    times: List[float]
    def __init__(self, samples: ArrayLike) -> None: ...
    @property
    def six_dof(self) -> bool: ...
    def __len__(self) -> int: ...

Motion = Union[MotionLog, ArrayLike]

def readMotionCsv(path: str, fixed_yaw: Optional[float] = None) -> MotionLog: ...
def loadMotion(path: str, rig_file: Optional[RigFile] = None, format: str = "auto", images: str = "",
               time_offset: Optional[float] = None, max_pose_gap: Optional[float] = None) -> MotionLog: ...
def checkMotionSteps(motion: MotionLog, motion_path: str) -> None: ...
def motionWarnings(motion: MotionLog, motion_path: str) -> List[str]: ...
def applyRigFile(rig_file: RigFile, motion: MotionLog) -> None: ...
def writeMotionCsv(path: str, motion: Motion) -> None: ...
def readTracksCsv(path: str) -> Array: ...
def writeTracksCsv(path: str, tracks: ArrayLike) -> None: ...
def checkTracksAgainstMotion(tracks: ArrayLike, motion: Motion, tracks_path: str) -> None: ...
def readPointsCsv(path: str) -> np.ndarray: ...
def writePointsCsv(path: str, points: Union[Estimate, np.ndarray]) -> None: ...

class NoiseModel:
    sigma_px: float
    sigma_odom: float
    sigma_heading: float
    sigma_yaw: float
    sigma_rot: float
    odom_per_metre: float
    rot_per_radian: float
    rot_per_metre: float
    motion_noise: str
    pixel_correlation: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class GateOptions:
    min_baseline: float
    min_parallax_px: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class ResidualCheckOptions:
    enabled: bool
    gate_probability: float
    scale_sigma: bool
    min_tracks: int
    correlated: bool
    reestimate_noise: bool
    def __init__(self) -> None: ...

class PipelineOptions:
    method: str
    noise: NoiseModel
    gates: GateOptions
    robust_threshold_px: float
    outlier_threshold_px: float
    window: int
    threads: int
    drop_unusable: bool
    residual_check: ResidualCheckOptions
    max_depth_sigma: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class Estimate:
    @property
    def points(self) -> np.ndarray: ...
    @property
    def c_cov(self) -> Array: ...
    @property
    def outliers(self) -> List[npt.NDArray[np.bool_]]: ...
    @property
    def motion(self) -> Array: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def s0(self) -> float: ...
    @property
    def outlier_share(self) -> float: ...
    @property
    def tracks_used(self) -> int: ...
    @property
    def mistake(self) -> bool: ...
    @property
    def noise_scale(self) -> float: ...
    @property
    def variance_factor(self) -> float: ...
    @property
    def sigma_scale(self) -> float: ...
    @property
    def inconsistent(self) -> int: ...
    def __len__(self) -> int: ...

def estimatePoints(camera: CameraModel, rig: YawRig, motion: Motion, tracks: ArrayLike,
                   options: Optional[PipelineOptions] = None, *, method: str = ..., sigma_px: float = ...,
                   sigma_odom: float = ..., sigma_heading: float = ..., sigma_yaw: float = ...,
                   sigma_rot: float = ..., odom_per_metre: float = ..., rot_per_radian: float = ...,
                   rot_per_metre: float = ..., motion_noise: str = ..., pixel_correlation: float = ...,
                   min_baseline: float = ...,
                   min_parallax_px: float = ..., robust_threshold_px: float = ...,
                   outlier_threshold_px: float = ..., window: int = ..., threads: int = ...,
                   drop_unusable: bool = ..., residual_check: bool = ..., max_depth_sigma: float = ...,
                   noise: NoiseModel = ..., gates: GateOptions = ...) -> Estimate: ...
def methodAvailable(method: str) -> bool: ...
def bestMethod() -> str: ...
def noiseForMotionLog(noise: NoiseModel, six_dof: bool, yaw_column: bool, sigma_yaw_given: bool) -> NoiseModel: ...

class PointEstimate:
    @property
    def status(self) -> str: ...
    @property
    def frame(self) -> int: ...
    @property
    def c_P(self) -> Array: ...
    @property
    def v_P(self) -> Array: ...
    @property
    def c_cov(self) -> Array: ...
    @property
    def sigmaZ(self) -> float: ...
    @property
    def parallax_px(self) -> float: ...
    @property
    def ok(self) -> bool: ...

class FeatureDepth:
    id: int
    depth: float
    sigma: float
    converged: bool
    status: str
    estimate: float
    estimate_sigma: float
    revocations: int

class DepthProviderOptions:
    prior_depth: float
    prior_relative_sigma: float
    converged_relative_sigma: float
    release_factor: float
    revoke_sigmas: float
    confirm_periods: int
    min_depth: float
    max_depth: float
    min_translation: float
    max_skipped_periods: int
    noise: NoiseModel
    initial_depth: float
    max_missing_frames: int
    method: str
    window: int
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class DepthProvider:
    def __init__(self, camera: CameraModel, rig: YawRig, options: DepthProviderOptions = ...) -> None: ...
    def update(self, wMv: ArrayLike, points: Features, yaw: float = 0.0) -> None: ...
    def updateOdometry(self, odometry: ArrayLike, points: Features) -> None: ...
    def depth(self, id: int) -> float: ...
    def sigma(self, id: int) -> float: ...
    def status(self, id: int) -> str: ...
    def converged(self, id: int) -> bool: ...
    def info(self, id: int) -> FeatureDepth: ...
    def estimate(self, id: int) -> PointEstimate: ...
    def setPrior(self, id: int, Z: float) -> None: ...
    @property
    def periods(self) -> int: ...
    @property
    def estimatorFrames(self) -> int: ...

class StreamOptions:
    method: str
    noise: NoiseModel
    gates: GateOptions
    window: int
    robust_threshold_px: float
    outlier_threshold_px: float
    prior_depth: float
    max_missing_frames: int
    def __init__(self) -> None: ...

class StreamEstimator:
    def __init__(self, camera: CameraModel, rig: YawRig, options: StreamOptions = ...) -> None: ...
    def addFrame(self, row: ArrayLike, observations: Features) -> None: ...
    def estimate(self, id: int) -> PointEstimate: ...
    def estimateAt(self, id: int, row: ArrayLike) -> PointEstimate: ...
    def forget(self, id: int) -> None: ...
    @property
    def method(self) -> str: ...

Image = npt.NDArray[np.uint8]

def readGrayImage(path: str, camera: Optional[CameraModel] = None) -> Image: ...

class DetectorOptions:
    subpixel: bool
    subpixel_window: int
    apriltag_decimate: float
    threads: int
    def __init__(self) -> None: ...

class FrameDetection:
    @property
    def frame(self) -> int: ...
    @property
    def found(self) -> bool: ...
    @property
    def reason(self) -> str: ...
    @property
    def features(self) -> Array: ...
    @property
    def warnings(self) -> List[str]: ...

class PatternDetector:
    def __init__(self, pattern: str, options: DetectorOptions = ...) -> None: ...
    def setCamera(self, camera: CameraModel) -> None: ...
    def detect(self, image: Image, frame: int) -> FrameDetection: ...
    @staticmethod
    def toTracks(detections: Sequence[FrameDetection]) -> Array: ...

class KltOptions:
    max_features: int
    min_distance: float
    quality: float
    block_size: int
    window: int
    pyramid_levels: int
    forward_backward_px: float
    redetect_fraction: float
    border_px: float
    gate_sigmas: float
    sigma_px: float
    min_depth: float
    max_depth: float
    guided: str
    guided_min_ncc: float
    ambiguity_margin: float
    guided_levels: int
    min_ncc: float
    jump_sigmas: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class KltTracker:
    def __init__(self, camera: CameraModel, options: KltOptions = ...) -> None: ...
    def track(self, image: Image, cMp: Optional[ArrayLike] = None, sigma_rot: float = 0.0,
              sigma_trans: float = 0.0) -> Array: ...
    @property
    def lastStats(self) -> Dict[str, int]: ...
    def setDepthHint(self, id: int, depth: float, sigma: float) -> None: ...

def trackSequence(camera: CameraModel, rig: YawRig, motion: MotionLog, noise: NoiseModel,
                  options: KltOptions = ..., gate: bool = True,
                  images: Optional[Sequence[str]] = None) -> Tuple[Array, Dict[str, int]]: ...

class ErrorAnalysisCase:
    yaw: float
    depth: float
    u_offset: float
    dz: float
    kx: float
    delta_dz: float
    delta_yaw: float
    delta_u: float
    delta_du: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class DepthErrorTerms:
    parallax_px: float
    odometry: float
    yaw: float
    pixel: float
    parallax: float
    total: float

class MonteCarloDepthError:
    rms_relative: float
    median_abs_relative: float
    bias_relative: float
    samples: int

class PaperErrorRow:
    view: str
    input: ErrorAnalysisCase
    lateral_depth_error: float

def firstOrderDepthError(c: ErrorAnalysisCase) -> DepthErrorTerms: ...
def firstOrderDepthSigma(c: ErrorAnalysisCase) -> float: ...
def lateralRelativeError(delta_u: float, kx: float, u_offset: float, depth_relative_error: float) -> float: ...
def monteCarloDepthError(c: ErrorAnalysisCase, samples: int, seed: int = 1) -> MonteCarloDepthError: ...
def paperErrorCases() -> List[PaperErrorRow]: ...
def formatPaperTerm(v: float) -> str: ...
def formatPercent(v: float) -> str: ...

class BoardLayout:
    tags_x: int
    tags_y: int
    gap: float
    first_tag_id: int
    margin: float
    outer_square: float
    def __init__(self, pattern: str) -> None: ...
    def features(self) -> Array: ...

class CalibrationView:
    def __init__(self, name: str, features: ArrayLike) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def features(self) -> Array: ...

class CalibrationDetections:
    width: int
    height: int
    views: List[CalibrationView]
    failures: List[str]
    warnings: List[str]

def detectCalibrationViews(board: BoardLayout, names: Sequence[str], images: Sequence[Image],
                           options: DetectorOptions = ...) -> CalibrationDetections: ...

class CameraCalibrationOptions:
    fix_aspect_ratio: bool
    fix_principal_point: bool
    distortion: str
    try_fisheye: bool
    cv_folds: int
    simpler_within: float
    zero_tangential: bool
    drop_outliers: bool
    outlier_ratio: float
    outlier_min_px: float
    min_views: int
    min_points_per_view: int
    min_orientation_spread: float
    fit_visp: bool
    def __init__(self) -> None: ...

class CameraCalibration:
    camera: CameraModel
    rms_px: float
    std_devs: List[float]
    intrinsics_covariance: Array
    views_used: int
    view_rms_px: List[float]
    orientation_spread: float
    coverage: float
    notes: List[str]
    model_reason: str
    models: List[Tuple[str, float, bool]]
    uncertainty_grid: Array
    visp_rms_without: float
    visp_rms_with: float

def calibrateCamera(board: BoardLayout, views: Sequence[CalibrationView], width: int, height: int,
                    options: CameraCalibrationOptions = ...) -> CameraCalibration: ...
def projectionUncertainty(calibration: CameraCalibration, u: float, v: float) -> float: ...
def saveVispCameraXml(path: str, calibration: CameraCalibration, camera_name: Optional[str] = None) -> None: ...

def wMv(row: ArrayLike) -> Array: ...
def wMc(rig: YawRig, row: ArrayLike) -> Array: ...
def curMprev(rig: YawRig, prev: ArrayLike, cur: ArrayLike) -> Array: ...

class HandEyeView:
    def __init__(self, rMe: ArrayLike, features: ArrayLike, name: str = "") -> None: ...
    @property
    def rMe(self) -> Array: ...
    @property
    def features(self) -> Array: ...
    @property
    def name(self) -> str: ...

class HandEyeOptions:
    setup: str
    min_points_per_view: int
    max_rms_px: float
    sigma_px: float
    sigma_pose_translation: float
    sigma_pose_rotation: float
    max_pose_correction_sigmas: float
    check_board_scale: bool
    def __init__(self) -> None: ...

class HandEyeCalibration:
    camera_pose: Array
    target_pose: Array
    camera_pose_sigma: Array
    target_pose_sigma: Array
    rms_px: float
    initial_rms_px: float
    views: int
    points: int
    view_rms_px: List[float]
    view_names: List[str]
    skipped: List[str]
    pose_correction_mm: float
    pose_correction_deg: float

def calibrateHandEye(camera: CameraModel, board: BoardLayout, views: Sequence[HandEyeView],
                     options: HandEyeOptions = ...) -> HandEyeCalibration: ...
def handEyeRigYaml(calibration: HandEyeCalibration) -> str: ...

class RigView:
    def __init__(self, row: ArrayLike, features: ArrayLike) -> None: ...
    @property
    def row(self) -> Array: ...
    @property
    def features(self) -> Array: ...

class RigCalibrationOptions:
    initial_offset: Array
    use_initial_offset: bool
    initial_yaw_offset: float
    board_square: bool
    estimate_axis: bool
    min_yaw_span: float
    min_distinct_yaws: int
    min_baseline: float
    min_points_per_view: int
    max_rms_px: float
    max_offset: float
    max_offset_sigma: float
    check_board_scale: bool
    def __init__(self) -> None: ...

class RigCalibration:
    camera_offset: Array
    camera_offset_sigma: Array
    yaw_axis: Array
    yaw_axis_sigma: Array
    yaw_offset: float
    yaw_offset_sigma: float
    rms_px: float
    view_rms_px: List[float]
    views: int
    points: int
    yaw_span: float
    distinct_yaws: int
    baseline: float

def calibrateRig(camera: CameraModel, board: BoardLayout, views: Sequence[RigView],
                 options: RigCalibrationOptions = ...) -> RigCalibration: ...
def rigCalibrationYaml(calibration: RigCalibration) -> str: ...
