#pragma once
/*!
  \file pipeline.h
  \brief One entry point for every estimation method: tracks and the motion log in, points, outlier
  flags and the motion as estimated out. The command line (`yawdepth estimate`, `measure`) and the
  benchmarks run their methods through estimatePoints().

  What it owns, so that no caller repeats it:
  - the method choice (yawdepth::Method: paper, exact, fused, window, refine) and whether this
    build has it (refine needs Ceres);
  - the observations no method can use (not finite, more than an image size outside the image, or
    outside what the lens model can undistort): taken out before estimation and flagged as
    outliers, so that one broken pixel does not spoil a feature;
  - refine's start: `fused` on the same tracks, then the joint refinement;
  - the tracker's correlated errors for the methods that model them (modelsTrackerCorrelation(),
    core/types.h): when the model leaves NoiseModel::pixel_correlation 0, the residual check runs and
    the residuals cannot show the tracker's errors whole (a drifting motion: no
    ResidualCheckResult::error_model), the correlation is measured from them and the method run again
    with it;
  - the outlier flags per observation and the motion as the method estimated it (refine's refined
    rows; the measured rows for the others).
*/
#include <functional>
#include <vector>
#include <string>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/pipeline/residual_check.h>
#include <yawdepth/refine/refine.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

/*! \brief Options of estimatePoints(): the method and what every method shares. */
struct PipelineOptions {
  Method method = Method::Fused; //!< The method (bestMethod() is the most accurate this build has).
  NoiseModel noise;              //!< Noise of pixels, motion and yaw readings.
  GateOptions gates;             //!< no_motion / degenerate gates.
  double robust_threshold_px = RefineOptions().robust_threshold_px;   //!< window, refine: scale of the robust loss (px).
  double outlier_threshold_px = RefineOptions().outlier_threshold_px; //!< window, refine: larger reprojection errors are outliers (px).
  int window = WindowOptions().window; //!< window: frames kept in the window (>= 2).
  int threads = 1;                     //!< refine: solver threads.
  /*! refine: called as the solve goes (RefineOptions::progress); empty: not called. */
  std::function<void(const RefineProgress &)> progress;
  /*! Take out the observations no method can use and flag them as outliers (see the file); false
      gives them to the method as they are. */
  bool drop_unusable = true;
  /*! After fused, window or refine: every ok point against its whole track (noise from the
      residuals, the tracks that are not one point made `inconsistent`; residual_check.h). Off by
      default; paper and exact are never checked. */
  ResidualCheckOptions residual_check;
  /*! An ok point whose relative depth sigma (sigma_Z / Z, after the residual check) exceeds this is
      `degenerate`: the frames do not resolve its depth to the precision asked (e.g. 0.05 for a point
      cloud whose points should be within 10 % at 2 sigma). 0: no such gate. */
  double max_depth_sigma = 0;
  /*!
    \brief Throws yawdepth::Error, one line, when the options cannot give an answer: the method's own
    rules on the options it runs with (WindowOptions::validate(), RefineOptions::validate(); for
    fused a pixel noise under kMinWeightPx: it weighs every observation by it), a bad noise model or
    gate, a negative or non-finite max_depth_sigma, fewer than one thread, a pixel correlation for a
    method that does not model it, or refine in a build without Ceres.
  */
  void validate() const;
};

/*! \brief What estimatePoints() returns. */
struct PipelineResult {
  std::vector<PointEstimate> points;       //!< One per track, same order, at the track's last observation.
  std::vector<std::vector<bool>> outliers; //!< Per track and observation: rejected (or unusable).
  std::vector<MotionSample> motion;        //!< The motion as estimated (refine) or as given (the others).
  ResidualCheckResult residuals;           //!< The residual check's findings (defaults when it did not run).
  /*! The noise model of the final run and of the points' covariances: the one given, or the one the
      residual check said (see estimatePoints(); its pixel noise never under 0.01 px). */
  NoiseModel noise;
  /*! \brief fused, window, refine: the whole log against the noise model given (see estimatePoints()). */
  struct Consistency {
    double s0 = 1;            //!< sqrt of the median chi-square ratio of the tracks at the model given (1: not measured)
    double outlier_share = 0; //!< share of the observations flagged as outliers or unusable
    int tracks_used = 0;      //!< tracks in s0
    bool mistake = false;     //!< the tracks do not fit the motion: points gated at the model given (see estimatePoints())
  };
  Consistency consistency; //!< The whole log against the noise model given (defaults for paper and exact).
  /*! One line each, for the user: what the data say is wrong (empty: nothing). */
  std::vector<std::string> warnings;
};

/*!
  \brief The options for natural features (a tracker's corners: `measure --features klt`'s defaults,
  which the benchmarks on such tracks use too): `window` (linear in the tracks, honest with the check,
  the most accurate on them: docs/accuracy.md), the residual check on (T-junctions and silhouettes are
  not points), and an ok point's depth resolved to 5 % at 1 sigma (a point cloud: within 10 % at 2
  sigma). The noise model is the default one: set it for the data.
*/
PipelineOptions naturalFeatureOptions();

/*! \brief Whether this build has the method (every one but refine always; refine with Ceres). */
bool methodAvailable(Method m);
/*! \brief The most accurate method this build has: refine with Ceres, else fused. */
Method bestMethod();

/*!
  \brief Estimate every track's point with the chosen method.
  \param camera Camera model (observed pixels are undistorted with it).
  \param rig Yaw rig.
  \param motion Motion-log rows sorted by strictly increasing frame; every observed frame must be in it.
  \param tracks The features; a track with fewer than two observations gets `too_few_frames`.
  \param options The method and its options (validated first).
  \throws yawdepth::Error for bad options or inconsistent input (an observed frame not in the log).

  After fused, window and refine, whatever the residual check's option, two rules:
  - **Unconfirmed points**: an ok point most of whose observations were flagged as outliers (or
    unusable), or with fewer than three left after any was flagged, is `inconsistent`: what is left
    cannot confirm it.
  - **The whole log against the noise model** (the residual check's s0 at the model given, on the
    motion as given): when s0 exceeds 5, or more than 30 % of the observations were flagged, the
    tracks do not fit the motion (a frame offset between tracks and motion, angles in degrees, a
    wrong rig or camera: no tracker is that far off its model): a warning, the noise model is not
    re-estimated from such residuals, and every ok point whose track fails the residual check's gate
    at the model given is `inconsistent` (Consistency::mistake). When s0 exceeds 1.5 without the
    residual check, a warning that the sigmas are too small by about s0.
*/
PipelineResult estimatePoints(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                              const std::vector<Track> &tracks, const PipelineOptions &options);

} // namespace yawdepth
