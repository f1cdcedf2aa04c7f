/*
  bench_klt: what natural-feature depth costs per frame at 640x480 with up to 300 tracks, against the
  tracking alone.

    bench_klt [--frames N] [--repeat R] [--max-features N] [--no-accuracy] [--no-cost] [--method fused|window|refine]

  Scene (klt_wall.h, shared with bench_tracker_errors): a textured wall 2 m in front of the first
  camera (smoothed uniform noise, seeded; each frame made photo-like: blur 0.8 px, vignetting 30 %,
  noise 2 gray levels, a gamma 2.2 response curve, JPEG at quality 85), the camera stepping 4 mm
  sideways per frame with a slow pan of +-1 degree; each image is the first warped by the wall's homography,
  rendered once before timing. One core: cv::setNumThreads(1), Eigen single-threaded by the build.

  Stages, each over the whole sequence R times after one warm-up pass (the median per frame printed;
  frames per second and the ratio from the tracking alone's median plus the stage's estimation):
  - tracking: yawdepth::KltTracker::track with the epipolar gate (pyramidal LK forward and
    backward, re-detection, the gate);
  - tracking + fused / + window: the same, and every frame's features into a
    yawdepth::StreamEstimator (the servo's and a live program's entry point).
  Targets (issues 14 and 35), checked (exit 1 when one is missed): tracking at 30 frames per second or more;
  tracking + fused within 1.2 x the tracking alone; tracking + window within 1.3 x the tracking
  alone (issue 35; bench_window checks window's own cost per frame).

  Then (unless --no-accuracy) the depths `measure --features klt` would report on the same sequence
  (trackSequence, then estimatePoints as `measure --features klt` by default: window, or --method; the
  residual check; --max-depth-sigma 0.05; the
  motion log exact, and modelled as exact) against the wall: each ok point's truth is
  where the ray of its last observed pixel meets the wall. Printed as bench_castle prints Castle-simu.
*/
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <yawdepth/error.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/pipeline/pipeline.h>
#include <yawdepth/window/stream_estimator.h>

#include "bench_common.h"
#include "klt_wall.h"

using namespace yawdepth;
using Clock = std::chrono::steady_clock;

namespace {

using bench::wall::kFocal;
using bench::wall::kU0;
using bench::wall::kV0;
using bench::wall::kWallDepth;
using bench::wall::renderSequence;
using bench::wall::Sequence;

/* One pass over the sequence: tracking, and the estimator when `method` is fused or window. Returns
   the per-frame milliseconds of tracking and of estimation (summed over the frames), and the mean
   live features per frame. */
struct Pass {
  double track_ms = 0, estimate_ms = 0, features = 0;
};

Pass runPass(const Sequence &s, const CameraModel &camera, const KltOptions &ko, const StreamMethod *method)
{
  const YawRig rig;
  NoiseModel noise;
  noise.sigma_px = 0.5;
  KltTracker tracker(camera, ko);
  std::unique_ptr<StreamEstimator> estimator;
  if (method) {
    StreamOptions so;
    so.method = *method;
    so.noise = noise;
    estimator = std::make_unique<StreamEstimator>(camera, rig, so);
  }
  Pass p;
  for (std::size_t k = 0; k < s.images.size(); ++k) {
    KltMotion m;
    const bool gate = k > 0;
    if (gate) {
      m.cMp = wMc(rig, s.motion[k]).inverse() * wMc(rig, s.motion[k - 1]);
      m.sigma_trans = noise.sigma_odom;
      m.sigma_rot = noise.sigma_heading;
    }
    const auto t0 = Clock::now();
    const std::vector<FeatureObservation> obs = tracker.track(s.images[k], gate ? &m : nullptr);
    const auto t1 = Clock::now();
    if (estimator)
      estimator->addFrame(s.motion[k], obs);
    const auto t2 = Clock::now();
    p.track_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
    p.estimate_ms += std::chrono::duration<double, std::milli>(t2 - t1).count();
    p.features += static_cast<double>(obs.size());
  }
  const double n = static_cast<double>(s.images.size());
  p.track_ms /= n;
  p.estimate_ms /= n;
  p.features /= n;
  return p;
}

/* The depth (camera Z at `sample`) where the ray of pixel (u, v) meets the wall (Z = kWallDepth in the
   first camera). */
double wallDepth(const CameraModel &camera, const MotionSample &first, const MotionSample &sample, double u, double v)
{
  Eigen::Vector2d m;
  if (!camera.undistort(Eigen::Vector2d(u, v), m))
    return std::nan("");
  const vpHomogeneousMatrix c0Mc = wMc(YawRig(), first).inverse() * wMc(YawRig(), sample);
  const vpColVector o = c0Mc.getTranslationVector();
  const vpColVector d = vpColVector(c0Mc.getRotationMatrix() * vpColVector({m.x(), m.y(), 1.0}));
  const double t = (kWallDepth - o[2]) / d[2]; // along the ray from the camera, in units of its depth there
  return t > 0 ? t : std::nan("");
}

/* The accuracy table: every ok point with its wall truth, then those whose own sigma is under 1 %. */
void accuracyTable(const Sequence &s, const CameraModel &camera, const KltOptions &ko, Method method)
{
  PipelineOptions po = naturalFeatureOptions(); // measure --features klt's defaults, but the method
  po.method = method;
  po.noise.motion_noise = MotionNoise::Absolute;
  po.noise.sigma_odom = 0; // the render's poses are exact: the model says so
  po.noise.sigma_heading = 0;
  po.noise.sigma_yaw = 0;
  const SequenceTracks seq =
      trackSequence(camera, YawRig(), s.motion, [&](std::size_t i) { return s.images[i]; }, po.noise, ko);
  const PipelineResult r = estimatePoints(camera, YawRig(), s.motion, seq.tracks, po);
  std::printf("\nDepth against the wall (measure --features klt's defaults, method %s: the residual check, "
              "--max-depth-sigma 0.05): %zu tracks; residual check: noise model scaled by %.3f from the residuals, "
              "correlation %.2f, %d inconsistent\n",
              toString(method), seq.tracks.size(), r.residuals.noise_scale, r.residuals.correlation,
              r.residuals.inconsistent);
  const TrackerErrorModel &em = r.residuals.error_model;
  if (em.variance > 0)
    std::printf("tracker's errors (restricted maximum likelihood over the tracks): %.3f px per axis, %.0f %% white, the "
                "rest correlated %.3f from one image to the next; the bound: each depth's sigma under that model with "
                "the poses known\n",
                std::sqrt(em.variance), 100 * em.white, em.phi);
  std::printf("| points | count | median rel. error | 95th pct | within 2 sigma | median error / sigma (0.67 when "
              "honest) | largest | RMSE / bound (points with one) |\n|---|---|---|---|---|---|---|---|\n");
  for (int subset = 0; subset < 2; ++subset) {
    std::vector<double> rel, ratio;
    int within = 0, bounded = 0;
    double sum_sq = 0;
    for (std::size_t i = 0; i < seq.tracks.size(); ++i) {
      const PointEstimate &e = r.points[i];
      if (!e.ok() || (subset == 1 && !(e.sigmaZ() < 0.01 * e.c_P.z())))
        continue;
      const long row = rowOfFrame(s.motion, e.frame);
      const Observation &last = seq.tracks[i].observations.back();
      const double z = wallDepth(camera, s.motion.front(), s.motion[static_cast<std::size_t>(row)], last.u, last.v);
      if (!std::isfinite(z))
        continue;
      rel.push_back(std::abs(e.c_P.z() - z) / z);
      ratio.push_back(std::abs(e.c_P.z() - z) / e.sigmaZ());
      within += std::abs(e.c_P.z() - z) <= 2 * e.sigmaZ() ? 1 : 0;
      const double bound = r.residuals.tracks[i].sigma_z_bound; // the tracker's error model, poses known
      if (std::isfinite(bound) && bound > 0) {
        sum_sq += std::pow((e.c_P.z() - z) / bound, 2);
        ++bounded;
      }
    }
    const double largest = rel.empty() ? 0.0 : *std::max_element(rel.begin(), rel.end());
    std::printf("| %s | %zu | %.3f %% | %.3f %% | %.3f | %.2f | %.2f %% | %.2f (%d) |\n",
                subset == 0 ? "every ok point" : "own sigma under 1 %", rel.size(), 100 * bench::quantile(rel, 0.5), 100 * bench::quantile(rel, 0.95),
                rel.empty() ? 0.0 : static_cast<double>(within) / static_cast<double>(rel.size()),
                bench::median(ratio), 100 * largest, bounded > 0 ? std::sqrt(sum_sq / bounded) : std::nan(""), bounded);
  }
}

/* The cost table: each stage's median per frame over `repeat` passes after a warm-up; prints the
   targets and whether they are met (false when one is missed). */
bool costTable(const Sequence &s, const CameraModel &camera, const KltOptions &ko, int repeat)
{
  constexpr double kMinFps = 30.0, kMaxFusedRatio = 1.2, kMaxWindowRatio = 1.3;
  const StreamMethod fused = StreamMethod::Fused, window = StreamMethod::Window;
  const struct {
    const char *name;
    const StreamMethod *method;
  } stages[] = {{"tracking alone", nullptr}, {"tracking + fused", &fused}, {"tracking + window", &window}};
  std::printf("| stage | features per frame | tracking ms | estimation ms | frames per second | (tracking + "
              "estimation) / tracking |\n|---|---|---|---|---|---|\n");
  runPass(s, camera, ko, nullptr); // warm-up: allocations, OpenCV's first calls
  double alone = 0, fused_ratio = 0, window_ratio = 0;
  for (const auto &stage : stages) {
    std::vector<double> track_ms, est_ms;
    double features = 0;
    for (int r = 0; r < repeat; ++r) {
      const Pass p = runPass(s, camera, ko, stage.method);
      track_ms.push_back(p.track_ms);
      est_ms.push_back(p.estimate_ms);
      features = p.features;
    }
    const double t = bench::median(track_ms), e = stage.method ? bench::median(est_ms) : 0.0;
    if (!stage.method)
      alone = t;
    if (stage.method == &fused)
      fused_ratio = (alone + e) / alone;
    if (stage.method == &window)
      window_ratio = (alone + e) / alone;
    // The ratio against the tracking alone's median: every stage tracks the same images the same way.
    std::printf("| %s | %.0f | %.2f | %.2f | %.0f | %.3f |\n", stage.name, features, t, e, 1000.0 / (alone + e),
                (alone + e) / alone);
  }
  const bool fps_ok = 1000.0 / alone >= kMinFps, ratio_ok = fused_ratio <= kMaxFusedRatio,
             window_ok = window_ratio <= kMaxWindowRatio;
  std::printf("target: tracking at %.0f frames per second or more (%.0f): %s\n", kMinFps, 1000.0 / alone,
              fps_ok ? "met" : "MISSED");
  std::printf("target: tracking + fused within %.1f x the tracking alone (%.3f): %s\n", kMaxFusedRatio, fused_ratio,
              ratio_ok ? "met" : "MISSED");
  std::printf("target: tracking + window within %.1f x the tracking alone (%.3f): %s\n", kMaxWindowRatio,
              window_ratio, window_ok ? "met" : "MISSED");
  return fps_ok && ratio_ok && window_ok;
}

} // namespace

int main(int argc, char **argv)
{
  int frames = 60, repeat = 5, max_features = 300;
  bool no_accuracy = false, no_cost = false;
  std::string method = "window";
  bench::CommandLine cli("[--frames N (>= 2)] [--repeat R] [--max-features N] [--no-accuracy] [--no-cost] [--method M]");
  cli.option("--frames", frames).option("--repeat", repeat).option("--max-features", max_features);
  cli.flag("--no-accuracy", no_accuracy).flag("--no-cost", no_cost).option("--method", method);
  if (!cli.parse(argc, argv))
    return 2;
  if (frames < 2 || repeat < 1 || max_features < 1) {
    std::fprintf(stderr, "bench_klt: --frames >= 2, --repeat >= 1, --max-features >= 1\n");
    return 2;
  }
  try {
    cv::setNumThreads(1);
    const CameraModel camera = CameraModel::brown(kFocal, kFocal, kU0, kV0, {0, 0, 0, 0}, 640, 480);
    const Sequence s = renderSequence(frames);
    KltOptions ko;
    ko.max_features = max_features;
    std::printf("bench_klt: KLT tracking and depth per frame, 640x480, a textured wall 2 m away (our render), "
                "one core\n");
    std::printf("Reproduce: build/benchmarks/bench_klt --frames %d --repeat %d --max-features %d --method %s%s%s\n",
                frames, repeat, max_features, method.c_str(), no_cost ? " --no-cost" : "",
                no_accuracy ? " --no-accuracy" : "");
    bool met = true;
    if (!no_cost)
      met = costTable(s, camera, ko, repeat);
    if (!no_accuracy)
      accuracyTable(s, camera, ko, methodFromString(method));
    return met ? 0 : 1;
  } catch (const Error &e) {
    std::fprintf(stderr, "bench_klt: %s\n", e.what());
    return 1;
  }
}
