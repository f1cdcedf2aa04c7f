#include <yawdepth/pipeline/pipeline.h>

#include "rig_doubts.h"
#include "variance_factor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/geometry/track_inputs.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

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

/* The tracks without the observations no method can use (a track left with none is kept empty). */
std::vector<Track> usableTracks(const CameraModel &camera, const std::vector<Track> &tracks)
{
  std::vector<Track> out = tracks;
  for (Track &t : out)
    t.observations.erase(std::remove_if(t.observations.begin(), t.observations.end(),
                                        [&](const Observation &ob) { return unusableObservation(camera, ob); }),
                         t.observations.end());
  return out;
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

/* The options `window` runs with. */
WindowOptions windowOptionsOf(const PipelineOptions &p)
{
  WindowOptions wo = jointOptions<WindowOptions>(p);
  wo.window = p.window;
  return wo;
}

/* The options `refine` runs with (after fused). */
RefineOptions refineOptionsOf(const PipelineOptions &p)
{
  RefineOptions ro = jointOptions<RefineOptions>(p);
  ro.threads = p.threads;
  ro.progress = p.progress;
  return ro;
}

/* The chosen method on the tracks as given. */
PipelineResult run(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                   const PipelineOptions &options)
{
  const std::vector<MotionSample> &motion = input.motion();
  PipelineResult r;
  if (options.method == Method::Window) {
    r.points = windowTracks(camera, rig, input, windowOptionsOf(options), &r.outliers);
    r.motion = motion;
    return r;
  }
  const bool refine = options.method == Method::Refine;
  TrackEstimatorOptions to;
  to.method = refine ? TrackMethod::Fused : trackMethodFromString(toString(options.method)); // refine starts from fused
  to.noise = options.noise;
  to.gates = options.gates;
  r.points = estimateTracks(camera, rig, input, to, &r.outliers);
  if (!refine) {
    r.motion = motion;
    return r;
  }
  RefineResult refined = refineWindow(camera, rig, input, r.points, refineOptionsOf(options));
  r.points = std::move(refined.points);
  r.outliers = std::move(refined.outliers);
  r.motion = std::move(refined.motion);
  return r;
}

/* An ok point most of whose observations were flagged, or with fewer than kMinConfirming left after
   any was: inconsistent (see estimatePoints()). */
constexpr std::size_t kMinConfirming = 3;
void markUnconfirmed(PipelineResult &r)
{
  for (std::size_t i = 0; i < r.points.size() && i < r.outliers.size(); ++i) {
    const std::vector<bool> &flags = r.outliers[i];
    const auto flagged = static_cast<std::size_t>(std::count(flags.begin(), flags.end(), true));
    if (r.points[i].ok() && flagged > 0 && (2 * flagged > flags.size() || flags.size() - flagged < kMinConfirming))
      r.points[i].status = Status::Inconsistent;
  }
}

/* The whole log against the noise model given (see estimatePoints()). */
constexpr double kMistakeS0 = 5;
constexpr double kMistakeOutlierShare = 0.3;
PipelineResult::Consistency wholeLog(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                     const PipelineResult &r, const PipelineOptions &options)
{
  PipelineResult::Consistency out;
  std::size_t flagged = 0, total = 0;
  for (const std::vector<bool> &flags : r.outliers) {
    flagged += static_cast<std::size_t>(std::count(flags.begin(), flags.end(), true));
    total += flags.size();
  }
  out.outlier_share = total > 0 ? static_cast<double>(flagged) / static_cast<double>(total) : 0.0;
  ResidualCheckOptions probe = options.residual_check;
  probe.scale_sigma = false;
  probe.correlated = false;
  std::vector<PointEstimate> points = r.points;
  const ResidualCheckResult c = checkResiduals(camera, rig, input, r.outliers, options.noise, probe, points);
  out.tracks_used = c.tracks_used;
  if (c.tracks_used >= options.residual_check.min_tracks)
    out.s0 = std::sqrt(c.variance_factor);
  out.mistake = out.s0 > kMistakeS0 || (total >= 20 && out.outlier_share > kMistakeOutlierShare);
  return out;
}

std::string figure(double v)
{
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

} // namespace

void PipelineOptions::validate() const
{
  const std::string name = toString(method);
  if (!methodAvailable(method))
    throw Error("method " + name + " is unavailable: this yawdepth was built without Ceres");
  // Each method's own rules, on the options it will run with.
  if (method == Method::Window) {
    windowOptionsOf(*this).validate();
  } else if (method == Method::Refine) {
    refineOptionsOf(*this).validate();
  } else {
    gates.validate();
  }
  noise.validateFor(method);
  if (threads < 1)
    throw Error("refine needs at least one thread");
  residual_check.validate();
  if (!(std::isfinite(max_depth_sigma) && max_depth_sigma >= 0))
    throw Error("the largest relative depth sigma must be finite and non-negative (0: no gate)");
}

PipelineOptions naturalFeatureOptions()
{
  PipelineOptions o;
  o.method = Method::Window;
  o.residual_check.enabled = true;
  o.max_depth_sigma = 0.05;
  return o;
}

bool methodAvailable(Method m) { return m != Method::Refine || refineAvailable(); }

Method bestMethod() { return refineAvailable() ? Method::Refine : Method::Fused; }

namespace {

/* The noise model the residuals say, and the factor on its pixel noise (1: the model given). The
   residuals are compared with a stand-in for the modelled variance that overstates the motion's
   part (see residual_check.h), so what they say is trusted in one direction more than the other:
   - larger (s0 > kReestimate, the residuals seeing the whole model: per-pose motion noise, or the
     pixels holding at least half of the variance): every sigma times s0 for per-pose motion noise
     (white: the residuals see all of it), the pixels' alone for per-increment noise (its drift hides
     in the fit);
   - smaller: only the pixel noise, only when the pixels hold at least kPixelShareToTighten of the
     modelled variance (so that the motion's stand-in cannot be what made the residuals small), the
     tracks' errors are not correlated (persistent errors hide in the fit), and s0^2 is below 1 by
     more than kEvidence of its standard errors and by more than kReestimate; the pixel variance then
     the part of s0^2 the pixels explain, the motion's part taken as modelled, s0^2 taken at the upper
     end of its evidence (s0^2 + kEvidence standard errors), and no change at all when that leaves the
     pixels no variance (the residuals then say the motion model is too large, not by how much the
     pixels' is).
   The pixel noise never below kMinPixelNoise. */
constexpr double kMinPixelNoise = 0.01; // px: no tracker is more precise than this
constexpr double kReestimate = 1.1;
constexpr double kMaxCorrelationToTighten = 0.5;
constexpr double kPixelShareToTighten = 0.8;
constexpr double kEvidence = 3;
struct Reestimated {
  NoiseModel noise;
  double pixel_scale = 1; // sigma_px's factor
  double gate_scale = 1;  // the gate at the model given, never tighter
  bool changed(const NoiseModel &given) const
  {
    return pixel_scale != 1.0 || noise.pixel_correlation != given.pixel_correlation;
  }
};
Reestimated pixelNoiseFromResiduals(const ResidualCheckResult &c, const PipelineOptions &options);

/* The tracker's errors' correlation below which a method that models it is run as if they were independent. */
constexpr double kMinModelledCorrelation = 0.05;

/* The noise model the residuals say: the pixel noise (pixelNoiseFromResiduals) and, for a method that
   models it and a model that does not set it, the correlation of the tracker's errors along a track
   (checkResiduals' estimate). */
Reestimated noiseFromResiduals(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                               const PipelineResult &r, const PipelineOptions &options)
{
  ResidualCheckOptions probe = options.residual_check;
  probe.scale_sigma = false;
  std::vector<PointEstimate> points = r.points; // the probe's gate must not change the result
  const ResidualCheckResult c = checkResiduals(camera, rig, input, r.outliers, options.noise, probe, points);
  Reestimated out = pixelNoiseFromResiduals(c, options);
  // Only where the residuals cannot show the tracker's errors whole (a modelled drift persists in them
  // as the tracker's slow part does: no TrackerErrorModel): where they can, the check's floor from
  // that model makes every method honest, and window weighing by the AR(1) part alone was less
  // accurate (Castle-simu: RMSE 1.42 of the model's bound against 1.12).
  if (modelsTrackerCorrelation(options.method) && options.noise.pixel_correlation == 0 &&
      options.residual_check.correlated && c.correlation >= kMinModelledCorrelation && !(c.error_model.variance > 0)) {
    out.noise.pixel_correlation = c.correlation;
    if (c.correlated_variance_factor > 1 && std::sqrt(c.correlated_variance_factor) > out.pixel_scale) {
      // The innovations say more noise than the model given: that, and the gate at the model given.
      out.pixel_scale = std::sqrt(c.correlated_variance_factor);
      out.noise.sigma_px = std::max(kMinPixelNoise, options.noise.sigma_px * out.pixel_scale);
      out.gate_scale = 1;
    }
  }
  return out;
}

/* The pixel noise the residuals say (the comment above kMinPixelNoise). */
Reestimated pixelNoiseFromResiduals(const ResidualCheckResult &c, const PipelineOptions &options)
{
  Reestimated out{options.noise};
  const double f2 = c.variance_factor;
  if (c.tracks_used < options.residual_check.min_tracks || !(f2 > 0))
    return out;
  const NoiseModel &n = options.noise;
  if (f2 > kReestimate * kReestimate) {
    if (n.motion_noise != MotionNoise::Absolute && c.pixel_share < 0.5)
      return out;
    const double s0 = std::sqrt(f2);
    out.pixel_scale = s0;
    out.noise.sigma_px = std::max(kMinPixelNoise, n.sigma_px * s0);
    if (n.motion_noise == MotionNoise::Absolute)
      for (double *v : {&out.noise.sigma_odom, &out.noise.sigma_heading, &out.noise.sigma_yaw, &out.noise.sigma_rot})
        *v *= s0;
    return out;
  }
  const bool strong = f2 < 1 / (kReestimate * kReestimate) && f2 + kEvidence * c.variance_factor_sigma < 1;
  if (!strong || c.pixel_share < kPixelShareToTighten || c.correlation >= kMaxCorrelationToTighten)
    return out;
  // The residuals bound the pixels' part from above only: take it at the largest s0^2 they do not rule
  // out (kEvidence standard errors above). When even that leaves the pixels nothing, the residuals are
  // smaller than the motion's modelled part alone: the motion model is what is too large, and how
  // small the pixel noise is cannot be told from them (a floor would be a guess): no change.
  const double px2 = (f2 + kEvidence * c.variance_factor_sigma - (1 - c.pixel_share)) / c.pixel_share;
  if (!(px2 > 0))
    return out;
  const double k = std::sqrt(px2);
  out.noise.sigma_px = std::max(kMinPixelNoise, n.sigma_px * k);
  out.pixel_scale = out.noise.sigma_px / n.sigma_px;
  out.gate_scale = 1 / (out.pixel_scale * out.pixel_scale);
  return out;
}

/* The method with the observations no method can use taken out first (see the file). */
PipelineResult runUsable(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                         const PipelineOptions &options)
{
  if (!options.drop_unusable)
    return run(camera, rig, input, options);
  const std::vector<Track> &tracks = input.tracks();
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
    return run(camera, rig, input, options);
  PipelineResult r = run(camera, rig, input.withFewer(usable_tracks), options);
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
  const TracksByFrame input = validateInputs(motion, tracks); // the one check of the inputs: every method assumes it
  PipelineResult r = runUsable(camera, rig, input, options);
  r.noise = options.noise;
  const bool whole_track = options.method == Method::Fused || options.method == Method::Window ||
                           options.method == Method::Refine;
  if (whole_track) {
    markUnconfirmed(r);
    r.consistency = wholeLog(camera, rig, input, r, options);
  }
  const PipelineResult::Consistency log = r.consistency; // a copy: a second run replaces r
  if (log.mistake) {
    ResidualCheckOptions gate = options.residual_check;
    gate.scale_sigma = false;
    gate.correlated = false;
    gate.gate_at_model = true;
    r.residuals = checkResiduals(camera, rig, input, r.outliers, options.noise, gate, r.points);
    const std::string residuals =
        !std::isfinite(log.s0) ? "most estimates fall behind cameras that saw them, and "
        : log.s0 > kMistakeS0  ? "their residuals are " + figure(log.s0) + " times the noise model's and "
                               : "";
    r.warnings.push_back("the tracks do not fit the motion log: " + residuals + figure(100 * log.outlier_share) +
                         " % of the observations were rejected (likely: tracks and motion a frame apart, angles in "
                         "degrees, a wrong rig (camera_offset or camera_pose, a sign, the yaw's sign or zero) or camera); " +
                         std::to_string(r.residuals.inconsistent) + " points that do not fit made inconsistent");
  } else if (options.residual_check.enabled && whole_track) {
    Reestimated model{options.noise};
    if (options.residual_check.reestimate_noise)
      model = noiseFromResiduals(camera, rig, input, r, options);
    if (model.changed(options.noise)) {
      PipelineOptions again = options;
      again.noise = model.noise;
      r = runUsable(camera, rig, input, again);
      markUnconfirmed(r);
      r.consistency = log;
    }
    r.residuals = pipeline_detail::checkResidualsGated(camera, rig, input, r.outliers, model.noise,
                                                       options.residual_check, model.gate_scale, r.points);
    r.residuals.noise_scale = model.pixel_scale;
    r.noise = model.noise;
  } else if (whole_track && log.s0 > pipeline_detail::kModelFitsS0) {
    r.warnings.push_back("the residuals are " + figure(log.s0) +
                         " times what the noise model allows: the sigmas are too small by about that (raise the "
                         "pixel noise, or let the residual check scale them)");
  }
  const std::vector<Track> usable = whole_track ? usableTracks(camera, tracks) : std::vector<Track>();
  if (whole_track)
    for (const pipeline_detail::RigDoubt &d : pipeline_detail::rigDoubts(camera, rig, input.withFewer(usable), options))
      r.warnings.push_back("with " + d.what + " flipped the tracks fit better (residuals " + figure(d.s0_alternative) +
                           (std::isfinite(d.s0_given) ? " instead of " + figure(d.s0_given) + " times the noise model"
                                                      : " times the noise model, where as given most tracks do not fit") +
                           "): check that sign");
  if (options.max_depth_sigma > 0)
    for (PointEstimate &p : r.points)
      if (p.ok() && !(p.sigmaZ() <= options.max_depth_sigma * p.c_P.z()))
        p.status = Status::Degenerate;
  return r;
}

} // namespace yawdepth
