#include "rig_doubts.h"

#include "variance_factor.h"

#include <algorithm>
#include <cmath>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/pipeline/residual_check.h>

namespace yawdepth {
namespace pipeline_detail {

namespace {

constexpr double kBetter = 1.21;     // s0^2 lower by this factor (s0 by 1.1)
constexpr double kEvidence = 3;      // and by this many standard errors
constexpr double kMinLever = 0.01;   // m
constexpr double kMinYawSpan = 0.05; // rad
constexpr double kMinTrackShare = 0.99; // an alternative that explains fewer tracks than this share...
constexpr double kDecisive = 4;         // ...must lower s0^2 by this factor (s0 by 2)

struct Fit {
  double f2 = 0, f2_sigma = 0;
  bool measured = false;
  std::vector<TrackResidual> tracks; // per track; dof 0 where the check did not use it
};

Fit fit(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input, const PipelineOptions &options)
{
  TrackEstimatorOptions to;
  to.method = TrackMethod::Fused;
  to.noise = options.noise;
  to.gates = options.gates;
  std::vector<std::vector<bool>> outliers;
  std::vector<PointEstimate> points = estimateTracks(camera, rig, input, to, &outliers);
  ResidualCheckOptions probe = options.residual_check;
  probe.scale_sigma = false;
  probe.correlated = false;
  const ResidualCheckResult c = checkResiduals(camera, rig, input, outliers, options.noise, probe, points);
  Fit f;
  f.measured = c.tracks_used >= options.residual_check.min_tracks;
  f.f2 = c.variance_factor;
  f.f2_sigma = c.variance_factor_sigma;
  f.tracks = c.tracks;
  return f;
}

/* The tracks a fit's residual check used. */
int used(const Fit &f)
{
  return static_cast<int>(std::count_if(f.tracks.begin(), f.tracks.end(), [](const TrackResidual &t) { return t.dof >= 1; }));
}

YawRig leverNegated(const YawRig &rig)
{
  if (rig.axisAligned())
    return YawRig(Eigen::Vector3d(-rig.cameraOffset()));
  vpHomogeneousMatrix vMc0 = rig.vMc(0.0);
  for (unsigned i = 0; i < 3; ++i)
    vMc0[i][3] = -vMc0[i][3];
  return YawRig(vMc0);
}

} // namespace

std::vector<RigDoubt> rigDoubts(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                const PipelineOptions &options)
{
  const std::vector<MotionSample> &motion = input.motion();
  const std::vector<Track> &tracks = input.tracks();
  std::vector<RigDoubt> out;
  if (motion.size() < 3)
    return out;
  const auto [lo, hi] = std::minmax_element(motion.begin(), motion.end(),
                                            [](const MotionSample &a, const MotionSample &b) { return a.yaw < b.yaw; });
  const bool yaw_turns = hi->yaw - lo->yaw >= kMinYawSpan;
  // The yaw's sign matters when the yaw turns or stays away from 0 (a camera looking sideways).
  const bool yaw_matters = yaw_turns || std::max(std::abs(hi->yaw), std::abs(lo->yaw)) >= kMinYawSpan;
  double body_turn = 0; // the largest rotation of the vision frame from the first row's
  for (const MotionSample &s : motion)
    body_turn = std::max(body_turn, logSO3(motion.front().rotation().transpose() * s.rotation()).norm());
  const bool lever_matters = rig.cameraOffset().norm() >= kMinLever && (yaw_turns || body_turn >= kMinYawSpan);
  if (!yaw_matters && !lever_matters)
    return out;
  // As given, too few tracks may fit to be measured (a gross mistake): any alternative that fits wins.
  const Fit given = fit(camera, rig, input, options);
  const bool given_fits = given.measured && std::isfinite(given.f2);
  auto compare = [&](const std::string &what, const Fit &alt) {
    if (!alt.measured || !std::isfinite(alt.f2))
      return;
    if (!given_fits) {
      // Too few tracks fit as given to measure s0. A gross mistake only when the alternative fits at
      // the noise model's level and explains at least twice as many tracks: a small scene (under
      // min_tracks checkable tracks) has too few either way, and a clean one must never be doubted.
      if (alt.f2 <= kModelFitsS0 * kModelFitsS0 && used(alt) >= 2 * std::max(used(given), 1))
        out.push_back({what, HUGE_VAL, std::sqrt(alt.f2)});
      return;
    }
    // Judged on the tracks both models explain: the gates drop what a model cannot explain, so a
    // wrong model can fit what it keeps better (a wall beside the drive under a flipped yaw keeps
    // the short tracks, which any rotation fits, and loses the long ones).
    std::vector<bool> both(tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i)
      both[i] = given.tracks[i].dof >= 1 && alt.tracks[i].dof >= 1;
    double f2_given = 0, sigma_given = 0, f2_alt = 0, sigma_alt = 0;
    const int min_tracks = options.residual_check.min_tracks;
    if (varianceFactor(given.tracks, both, min_tracks, f2_given, sigma_given) < min_tracks ||
        varianceFactor(alt.tracks, both, min_tracks, f2_alt, sigma_alt) < min_tracks)
      return;
    // And an alternative that explains fewer tracks (more lost to the gates) must be decisively better.
    if (used(alt) < kMinTrackShare * used(given) && !(f2_alt * kDecisive < f2_given))
      return;
    if (f2_alt * kBetter < f2_given && f2_alt + kEvidence * std::hypot(sigma_alt, sigma_given) < f2_given)
      out.push_back({what, std::sqrt(f2_given), std::sqrt(f2_alt)});
  };
  if (lever_matters)
    compare("the lever arm's sign (the rig file's camera_offset, or camera_pose's translation)",
            fit(camera, leverNegated(rig), input, options));
  if (yaw_matters) {
    std::vector<MotionSample> negated = motion;
    for (MotionSample &s : negated)
      s.yaw = -s.yaw;
    compare("the yaw's sign (the motion log's yaw readings)", fit(camera, rig, input.withMotion(negated), options));
  }
  return out;
}

} // namespace pipeline_detail
} // namespace yawdepth
