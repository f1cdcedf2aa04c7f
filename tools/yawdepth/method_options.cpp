#include "method_options.h"

#include "commands.h"

#include <cmath>
#include <cstdio>
#include <unistd.h>

#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/refine/refine.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth::cli {

std::string bestMethod() { return refineAvailable() ? "refine" : "fused"; }

void addMotionNoiseOptions(CLI::App *sub, MethodArgs &args)
{
  sub->add_option("--sigma-odom", args.noise.sigma_odom, "Odometry translation noise per increment, per axis (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-heading", args.noise.sigma_heading, "Heading noise per increment (rad), planar motion logs")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-rot", args.noise.sigma_rot, "Rotation noise per increment, per axis (rad), 6-DoF motion logs")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--motion-noise", [&args](const std::string &w) { args.noise.motion_noise = motionNoiseFromString(w); },
         "How the motion log errs: increment (odometry, VIO: --sigma-odom/--sigma-heading/--sigma-rot per increment, "
         "the errors accumulate) or absolute (forward kinematics, motion capture: the same sigmas per pose)")
      ->check(CLI::IsMember({"increment", "absolute"}))
      ->default_str("increment");
  args.sigma_yaw_option = sub->add_option("--sigma-yaw", args.noise.sigma_yaw,
                                          "Noise of each yaw reading (rad); 0 by default for a 6-DoF log without a yaw column")
                              ->check(FiniteNonNegative)
                              ->capture_default_str();
}

void addMethodOptions(CLI::App *sub, MethodArgs &args, const std::string &default_method)
{
  args.method = default_method;
  args.robust_px = RefineOptions().robust_threshold_px;
  args.outlier_px = RefineOptions().outlier_threshold_px;
  sub->add_option("--method", args.method,
                  "paper: eq. (5) on the last increment as published; exact: finite-increment two-view form (exact on "
                  "noise-free data); fused: recursive filter per feature over every frame (cheapest); window: "
                  "frame-by-frame smoother of every point with the last 10 frames' motion, older frames marginalised "
                  "(at the joint bound, what a servo loop gets); refine: joint MAP of every point with the motion over "
                  "all frames (Ceres)")
      ->check(CLI::IsMember({"paper", "exact", "fused", "window", "refine"}))
      ->capture_default_str();
  sub->add_option("--sigma-px", args.noise.sigma_px, "Pixel noise (px)")->check(FiniteNonNegative)->capture_default_str();
  addMotionNoiseOptions(sub, args);
  sub->add_option("--min-baseline", args.gates.min_baseline, "Camera translation below this is no_motion (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--min-parallax-px", args.gates.min_parallax_px, "Parallax below this is degenerate (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--robust-threshold-px", args.robust_px, "refine and window: scale of the robust loss (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--outlier-threshold-px", args.outlier_px,
                  "refine and window: observations with a larger reprojection error are flagged as outliers (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--threads", args.threads, "refine: threads of the solver (Ceres)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
}

NoiseModel noiseForLog(const MethodArgs &args, bool six_dof, bool yaw_column)
{
  NoiseModel n = args.noise;
  if (six_dof && !yaw_column && (args.sigma_yaw_option == nullptr || args.sigma_yaw_option->count() == 0))
    n.sigma_yaw = 0.0;
  return n;
}

namespace {

/* An observation no estimator can use: not finite, more than an image size outside the image, or
   outside what the lens model can undistort. */
bool unusableObservation(const CameraModel &camera, const Observation &ob)
{
  if (!std::isfinite(ob.u) || !std::isfinite(ob.v))
    return true;
  if (camera.width() > 0 && camera.height() > 0) {
    const double w = camera.width(), h = camera.height();
    if (ob.u < -w || ob.u > 2 * w || ob.v < -h || ob.v > 2 * h)
      return true;
  }
  Eigen::Vector2d m;
  return !camera.undistort(Eigen::Vector2d(ob.u, ob.v), m);
}

/* refine's progress on a terminal: one line, rewritten at most once a second and at each new stage,
   from the first report after 2 s (a short solve prints nothing); ended by a newline when the object goes. Not on a pipe
   or a file: a caller capturing stderr gets one line per problem, not a progress bar. */
class ProgressLine {
public:
  explicit ProgressLine(bool wanted) : active_(wanted && isatty(STDERR_FILENO)) {}
  ~ProgressLine()
  {
    if (printed_)
      std::fputc('\n', stderr);
  }
  ProgressLine(const ProgressLine &) = delete;
  ProgressLine &operator=(const ProgressLine &) = delete;

  std::function<void(const RefineProgress &)> callback()
  {
    if (!active_)
      return {};
    return [this](const RefineProgress &p) {
      if (p.seconds < 2.0 || (p.seconds < last_ + 1.0 && p.stage == stage_))
        return; // a new stage is shown at once, the same one at most once a second
      last_ = p.seconds;
      stage_ = p.stage;
      const char *stage = p.stage == RefineProgress::Stage::RobustSolve  ? "robust solve"
                          : p.stage == RefineProgress::Stage::FinalSolve ? "final solve"
                                                                         : "covariances";
      if (p.stage == RefineProgress::Stage::Covariance)
        std::fprintf(stderr, "\rrefine: %d points x %d frames, %s ... (%.0f s)%20s", p.points, p.frames, stage, p.seconds,
                     "");
      else
        std::fprintf(stderr, "\rrefine: %d points x %d frames, %s, iteration %d, cost %.6g (%.0f s)%8s", p.points,
                     p.frames, stage, p.iteration, p.cost, p.seconds, "");
      std::fflush(stderr);
      printed_ = true;
    };
  }

private:
  bool active_;
  bool printed_ = false;
  double last_ = 0;
  RefineProgress::Stage stage_ = RefineProgress::Stage::RobustSolve;
};

} // namespace

std::vector<PointEstimate> runMethod(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                                     const std::vector<Track> &tracks, const MethodArgs &args,
                                     std::vector<std::vector<bool>> &outliers, std::vector<MotionSample> *motion_estimate)
{
  // Observations that no method can use are taken out before estimation and reported as outliers:
  // the feature is estimated from the rest (a track left with none keeps them all, and its method
  // says why it failed).
  std::vector<std::vector<bool>> unusable(tracks.size());
  std::vector<Track> usable_tracks; // a copy only when some observation has to go
  bool any_unusable = false;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    unusable[i].assign(tracks[i].observations.size(), false);
    Track kept;
    kept.id = tracks[i].id;
    for (std::size_t k = 0; k < tracks[i].observations.size(); ++k) {
      unusable[i][k] = unusableObservation(camera, tracks[i].observations[k]);
      if (!unusable[i][k])
        kept.observations.push_back(tracks[i].observations[k]);
    }
    if (kept.observations.size() == tracks[i].observations.size() || kept.observations.empty()) {
      unusable[i].assign(tracks[i].observations.size(), false);
      continue;
    }
    if (!any_unusable)
      usable_tracks = tracks;
    any_unusable = true;
    usable_tracks[i] = std::move(kept);
  }
  std::vector<PointEstimate> estimates =
      runMethodOn(camera, rig, motion, any_unusable ? usable_tracks : tracks, args, outliers, motion_estimate);
  if (any_unusable) { // the flags back onto the original observations
    std::vector<std::vector<bool>> full(tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      full[i] = unusable[i];
      std::size_t kept = 0;
      for (std::size_t k = 0; k < tracks[i].observations.size(); ++k)
        if (!unusable[i][k]) {
          full[i][k] = i < outliers.size() && kept < outliers[i].size() && outliers[i][kept];
          ++kept;
        }
    }
    outliers = std::move(full);
  }
  return estimates;
}

std::vector<PointEstimate> runMethodOn(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                                       const std::vector<Track> &tracks, const MethodArgs &args,
                                       std::vector<std::vector<bool>> &outliers, std::vector<MotionSample> *motion_estimate)
{
  args.noise.validate();
  args.gates.validate();
  const bool refine = args.method == "refine", window = args.method == "window";
  if (refine && !refineAvailable())
    throw Error("method refine is unavailable: this yawdepth was built without Ceres");
  // fused and refine weigh every observation by the pixel noise: zero (or a denormal) would give
  // infinite weights and NaN uncertainties, not an answer.
  constexpr double kMinSigmaPx = 1e-6;
  if ((refine || window || args.method == "fused") && !(args.noise.sigma_px >= kMinSigmaPx))
    throw Error("--sigma-px " + std::to_string(args.noise.sigma_px) + ": methods fused, window and refine need a pixel "
                "noise of at least 1e-6 px (they weigh every observation by it)");
  if ((refine || window) && !(args.robust_px >= kMinSigmaPx))
    throw Error("--robust-threshold-px must be at least 1e-6 px for " + args.method + " (the scale of its robust loss)");
  if (window && !(args.outlier_px >= kMinSigmaPx))
    throw Error("--outlier-threshold-px must be at least 1e-6 px for window");
  if (window) {
    WindowOptions wo;
    wo.noise = args.noise;
    wo.gates = args.gates;
    wo.robust_threshold_px = args.robust_px;
    wo.outlier_threshold_px = args.outlier_px;
    if (motion_estimate)
      *motion_estimate = motion;
    return windowTracks(camera, rig, motion, tracks, wo, &outliers);
  }
  TrackEstimatorOptions options;
  options.method = refine ? Method::Fused : methodFromString(args.method);
  options.two_view.noise = args.noise;
  options.two_view.gates = args.gates;
  std::vector<PointEstimate> estimates = estimateTracks(camera, rig, motion, tracks, options, &outliers);
  if (refine) {
    RefineOptions ro;
    ro.noise = args.noise;
    ro.gates = args.gates;
    ro.robust_threshold_px = args.robust_px;
    ro.outlier_threshold_px = args.outlier_px;
    ro.threads = args.threads;
    ProgressLine line(args.progress);
    ro.progress = line.callback();
    RefineResult r = refineWindow(camera, rig, motion, tracks, estimates, ro);
    estimates = std::move(r.points);
    outliers = std::move(r.outliers);
    if (motion_estimate)
      *motion_estimate = std::move(r.motion);
  } else if (motion_estimate) {
    *motion_estimate = motion;
  }
  return estimates;
}

std::vector<Track> rejectedObservations(const std::vector<Track> &tracks, const std::vector<std::vector<bool>> &outliers)
{
  std::vector<Track> rejected;
  for (std::size_t i = 0; i < tracks.size() && i < outliers.size(); ++i) {
    Track t;
    t.id = tracks[i].id;
    for (std::size_t k = 0; k < tracks[i].observations.size() && k < outliers[i].size(); ++k)
      if (outliers[i][k])
        t.observations.push_back(tracks[i].observations[k]);
    if (!t.observations.empty())
      rejected.push_back(t);
  }
  return rejected;
}

} // namespace yawdepth::cli
