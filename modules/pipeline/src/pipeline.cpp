#include <yawdepth/pipeline/pipeline.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

namespace {

/* The smallest pixel noise and robust scale the weighted methods accept: zero (or a denormal)
   would give infinite weights and NaN uncertainties, not an answer. */
constexpr double kMinWeightPx = 1e-6;

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

/* WindowOptions or RefineOptions with what the pipeline's options share with them. */
template <class Options> Options jointOptions(const PipelineOptions &p)
{
  Options o;
  o.noise = p.noise;
  o.gates = p.gates;
  o.robust_threshold_px = p.robust_threshold_px;
  o.outlier_threshold_px = p.outlier_threshold_px;
  return o;
}

/* The chosen method on the tracks as given. */
PipelineResult run(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                   const std::vector<Track> &tracks, const PipelineOptions &options)
{
  PipelineResult r;
  if (options.method == Method::Window) {
    WindowOptions wo = jointOptions<WindowOptions>(options);
    wo.window = options.window;
    r.points = windowTracks(camera, rig, motion, tracks, wo, &r.outliers);
    r.motion = motion;
    return r;
  }
  const bool refine = options.method == Method::Refine;
  TrackEstimatorOptions to;
  to.method = refine ? Method::Fused : options.method; // refine starts from fused
  to.two_view.noise = options.noise;
  to.two_view.gates = options.gates;
  r.points = estimateTracks(camera, rig, motion, tracks, to, &r.outliers);
  if (!refine) {
    r.motion = motion;
    return r;
  }
  RefineOptions ro = jointOptions<RefineOptions>(options);
  ro.threads = options.threads;
  ro.progress = options.progress;
  RefineResult refined = refineWindow(camera, rig, motion, tracks, r.points, ro);
  r.points = std::move(refined.points);
  r.outliers = std::move(refined.outliers);
  r.motion = std::move(refined.motion);
  return r;
}

} // namespace

void PipelineOptions::validate() const
{
  noise.validate();
  gates.validate();
  const bool weighted = method == Method::Fused || method == Method::Window || method == Method::Refine;
  const std::string name = toString(method);
  if (!methodAvailable(method))
    throw Error("method " + name + " is unavailable: this yawdepth was built without Ceres");
  if (weighted && !(noise.sigma_px >= kMinWeightPx))
    throw Error("pixel noise " + std::to_string(noise.sigma_px) + " px: method " + name +
                " needs at least 1e-6 px (it weighs every observation by it)");
  if ((method == Method::Window || method == Method::Refine) && !(robust_threshold_px >= kMinWeightPx))
    throw Error("method " + name + " needs a robust threshold of at least 1e-6 px (the scale of its robust loss)");
  if (method == Method::Window && !(outlier_threshold_px >= kMinWeightPx))
    throw Error("method window needs an outlier threshold of at least 1e-6 px");
  if (method == Method::Window && window < 2)
    throw Error("method window needs a window of at least 2 frames");
  if (threads < 1)
    throw Error("refine needs at least one thread");
  residual_check.validate();
  if (!(std::isfinite(max_depth_sigma) && max_depth_sigma >= 0))
    throw Error("the largest relative depth sigma must be finite and non-negative (0: no gate)");
}

bool methodAvailable(Method m) { return m != Method::Refine || refineAvailable(); }

Method bestMethod() { return refineAvailable() ? Method::Refine : Method::Fused; }

namespace {

/* The noise model scaled by s (the pixel noise at least kMinPixelNoise): every sigma when the motion
   errs per pose (white: the residuals see all of it), only the pixels' when it errs per increment (its
   drift mostly hides in the fit: the residuals do not say it was wrong). */
constexpr double kMinPixelNoise = 0.01; // px: no tracker is more precise than this
NoiseModel scaledNoise(const NoiseModel &n, double s)
{
  NoiseModel out = n;
  out.sigma_px = std::max(kMinPixelNoise, n.sigma_px * s);
  if (n.motion_noise == MotionNoise::Absolute)
    for (double *v : {&out.sigma_odom, &out.sigma_heading, &out.sigma_yaw, &out.sigma_rot})
      *v *= s;
  return out;
}

/* s0 when the residuals see the whole noise model and say it is off by more than kReestimate (see
   ResidualCheckOptions::reestimate_noise), else 1. */
constexpr double kReestimate = 1.1;
constexpr double kMaxCorrelationToTighten = 0.5;
double noiseScaleFromResiduals(const CameraModel &camera, const YawRig &rig, const std::vector<Track> &tracks,
                               const PipelineResult &r, const PipelineOptions &options)
{
  ResidualCheckOptions probe = options.residual_check;
  probe.scale_sigma = false;
  std::vector<PointEstimate> points = r.points; // the probe's gate must not change the result
  const ResidualCheckResult c = checkResiduals(camera, rig, r.motion, tracks, r.outliers, options.noise, probe, points);
  const bool sees_all = options.noise.motion_noise == MotionNoise::Absolute || c.pixel_share >= 0.5;
  const double s0 = std::sqrt(c.variance_factor);
  if (c.tracks_used < options.residual_check.min_tracks || !sees_all || !(s0 > 0) ||
      std::abs(std::log(s0)) <= std::log(kReestimate))
    return 1.0;
  // Errors that persist from frame to frame hide in the fit: small residuals then do not say the
  // tracker is precise, and the model is not made tighter.
  if (s0 < 1 && c.correlation >= kMaxCorrelationToTighten)
    return 1.0;
  return s0;
}

/* The method with the observations no method can use taken out first (see the file). */
PipelineResult runUsable(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                         const std::vector<Track> &tracks, const PipelineOptions &options)
{
  if (!options.drop_unusable)
    return run(camera, rig, motion, tracks, options);
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
  if (!any_unusable)
    return run(camera, rig, motion, tracks, options);
  PipelineResult r = run(camera, rig, motion, usable_tracks, options);
  // The flags back onto the original observations.
  std::vector<std::vector<bool>> full(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    full[i] = unusable[i];
    std::size_t kept = 0;
    for (std::size_t k = 0; k < tracks[i].observations.size(); ++k)
      if (!unusable[i][k]) {
        full[i][k] = i < r.outliers.size() && kept < r.outliers[i].size() && r.outliers[i][kept];
        ++kept;
      }
  }
  r.outliers = std::move(full);
  return r;
}

} // namespace

PipelineResult estimatePoints(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                              const std::vector<Track> &tracks, const PipelineOptions &options)
{
  options.validate();
  PipelineResult r = runUsable(camera, rig, motion, tracks, options);
  const bool whole_track = options.method == Method::Fused || options.method == Method::Window ||
                           options.method == Method::Refine;
  if (options.residual_check.enabled && whole_track) {
    NoiseModel noise = options.noise;
    const double s0 = options.residual_check.reestimate_noise ? noiseScaleFromResiduals(camera, rig, tracks, r, options) : 1.0;
    if (s0 != 1.0) {
      PipelineOptions again = options;
      again.noise = scaledNoise(options.noise, s0);
      noise = again.noise;
      r = runUsable(camera, rig, motion, tracks, again);
    }
    ResidualCheckOptions check = options.residual_check;
    check.gate_scale = s0 < 1 ? 1 / (s0 * s0) : 1.0; // the gate at the model given, never tighter
    r.residuals = checkResiduals(camera, rig, r.motion, tracks, r.outliers, noise, check, r.points);
    r.residuals.noise_scale = s0;
  }
  if (options.max_depth_sigma > 0)
    for (PointEstimate &p : r.points)
      if (p.ok() && !(p.sigmaZ() <= options.max_depth_sigma * p.c_P.z()))
        p.status = Status::Degenerate;
  return r;
}

} // namespace yawdepth
