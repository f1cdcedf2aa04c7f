/*
  bench_two_planes: is any natural-feature point called `ok` far off the surface it lies on, when
  one textured plane stands in front of another (occlusion boundaries, T-junctions)? (Issue 35.)

    bench_two_planes [--frames N] [--draws D] [--worst K] [--max-features N] [--min-ncc X] [--jump-sigmas K]
                     [--sigma-odom M] [--sigma-rot R] [--sigma-px S]

  Data (our render, seeded, no file read): 640x480, f = 600 px, no distortion. A far wall 2.0 m in
  front of the first camera (smoothed uniform noise, blur 2 px) and, in front of it, a near plane at
  1.1 m (another texture, blur 1.5 px) covering the lower left of the first view (first-camera
  pixels u <= 330, v >= 150: a vertical and a horizontal occlusion edge, hence T-junctions where the
  near edge crosses the far texture). Each image is the two textures warped by their planes'
  homographies and composited by the near plane's (anti-aliased) mask, then made photo-like as in
  bench_klt (blur 0.8 px, vignetting 30 %, noise 2 gray levels, gamma 2.2, JPEG at quality 85). The
  camera steps 4 mm sideways per frame and pans 1.5 mrad per frame (60 frames: 0.24 m, 5 degrees;
  simulateScene's planar log with lateral_step and yaw_rate). Truth: for each ok point, the plane
  the ray of its last observed pixel hits (the near plane's mask back-projected), and that plane's
  depth along the ray.

  Tracking and estimation as `measure --features klt`: trackSequence (KltTracker with the epipolar
  gate and every track check), estimatePoints with the residual check and --max-depth-sigma 0.05,
  for each method fused, window, refine, the pixel noise model measure's default (0.3 px, --sigma-px);
  and
  (a) exact motion: the log is the truth, given as 0.1 mm and 0.1 mrad per pose (as bench_klt);
  (b) dead reckoning: each of D seeded draws (seeds 1..D, 40 by default: within a draw every point
      shares the odometry's error, so a draw is close to one sample of the coverage; 10 draws gave
      0.99 to 1.00 where 40 give 0.93 to 0.95) perturbs the log as odometry does
      (per increment 0.4 mm per axis, heading 0.3 mrad; each yaw reading 0.3 mrad; --sigma-odom,
      --sigma-rot) and the tracker
      and the estimator are told that noise model (the images are the truth's).
  (c) no target, a diagnostic: (a) with the noise model not re-estimated from the residuals
      (ResidualCheckOptions::reestimate_noise off), to show what the re-estimation does to the sigmas.
  Printed per method and motion: ok points (summed over the draws for (b)), the largest |depth
  error| / sigma_Z, how many beyond 5 sigma, the share within 2 sigma (pooled over the draws for
  (b)), the RMS relative depth error, the factor the residual check scaled the noise model by
  (mean over the draws), the tracks and the tracker's cuts (appearance) and splits (jumps); then
  the K worst ok points with where they sit (their distance to the occlusion edge in the last
  image, px, negative on the near plane) and their residual check (chi2 / dof, RMS px).

  Targets (exit 1 when one is missed): (a) no ok point more than 5 sigma off its plane, every
  method; (b) no ok point more than 5 sigma off, and 2-sigma coverage pooled over the draws in
  [0.90, 0.98], every method.
*/
#include <algorithm>
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
#include <yawdepth/simulation/scene.h>

#include "bench_common.h"
#include "photo_like.h"

using namespace yawdepth;

namespace {

constexpr double kFocal = 600, kU0 = 320, kV0 = 240;
constexpr double kFarDepth = 2.0, kNearDepth = 1.1;
// The near plane in first-camera pixels (its texture's extent beyond the view is irrelevant).
constexpr double kNearRight = 330, kNearTop = 150;
// The textures' canvas: first-camera pixel (u, v) at canvas (u + kPadU, v + kPadV).
constexpr int kPadU = 480, kPadV = 360, kCanvasW = 640 + 2 * kPadU, kCanvasH = 480 + 2 * kPadV;
constexpr double kSigmaLimit = 5, kCoverLo = 0.90, kCoverHi = 0.98;

/* The homography of the fronto-parallel plane Z = depth (first camera) from the first camera's
   pixels to those of the camera at `cMc0`. */
cv::Matx33d planeHomography(const vpHomogeneousMatrix &cMc0, double depth)
{
  return bench::planeHomography(cMc0, depth, kFocal, kU0, kV0);
}

cv::Mat texture(std::uint64_t seed, double blur)
{
  cv::Mat noise(kCanvasH, kCanvasW, CV_32F), smooth, out;
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(noise, smooth, cv::Size(0, 0), blur);
  cv::normalize(smooth, smooth, 20, 235, cv::NORM_MINMAX);
  smooth.convertTo(out, CV_8U);
  return out;
}

struct Scene2 {
  std::vector<MotionSample> truth;
  std::vector<cv::Mat> images;
};

vpHomogeneousMatrix cMc0Of(const std::vector<MotionSample> &log, std::size_t k)
{
  return wMc(YawRig(), log[k]).inverse() * wMc(YawRig(), log.front());
}

SceneOptions motionOptions(int frames)
{
  SceneOptions o;
  o.frames = frames;
  o.step = 0;
  o.lateral_step = 0.004;
  o.yaw_rate = -0.0015;
  o.points = 1;
  return o;
}

Scene2 renderScene(const CameraModel &camera, int frames)
{
  Scene2 s;
  s.truth = simulateScene(camera, YawRig(), motionOptions(frames)).truth;
  const cv::Mat far = texture(11, 2.0), near = texture(23, 1.5);
  cv::Mat mask(kCanvasH, kCanvasW, CV_32F, cv::Scalar(0));
  mask(cv::Rect(0, static_cast<int>(kNearTop) + kPadV, static_cast<int>(kNearRight) + kPadU + 1,
                kCanvasH - static_cast<int>(kNearTop) - kPadV))
      .setTo(1.0);
  const cv::Matx33d canvas_to_first(1, 0, -kPadU, 0, 1, -kPadV, 0, 0, 1);
  cv::Mat vignetting(480, 640, CV_32F);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u)
      vignetting.at<float>(v, u) =
          static_cast<float>(1.0 - 0.3 * ((u - kU0) * (u - kU0) + (v - kV0) * (v - kV0)) / (kU0 * kU0 + kV0 * kV0));
  cv::RNG rng(5);
  for (std::size_t k = 0; k < s.truth.size(); ++k) {
    const vpHomogeneousMatrix cMc0 = cMc0Of(s.truth, k);
    const cv::Mat Hf(planeHomography(cMc0, kFarDepth) * canvas_to_first),
        Hn(planeHomography(cMc0, kNearDepth) * canvas_to_first);
    cv::Mat wf, wn, wm;
    cv::warpPerspective(far, wf, Hf, cv::Size(640, 480), cv::INTER_CUBIC, cv::BORDER_REFLECT);
    cv::warpPerspective(near, wn, Hn, cv::Size(640, 480), cv::INTER_CUBIC, cv::BORDER_REFLECT);
    cv::warpPerspective(mask, wm, Hn, cv::Size(640, 480), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::Mat ff, fn;
    wf.convertTo(ff, CV_32F);
    wn.convertTo(fn, CV_32F);
    cv::Mat composed = fn.mul(wm) + ff.mul(1.0 - wm), blurred, frame_noise(480, 640, CV_32F);
    cv::GaussianBlur(composed, blurred, cv::Size(0, 0), 0.8);
    rng.fill(frame_noise, cv::RNG::NORMAL, 0.0, 2.0);
    s.images.push_back(bench::photoFinish(blurred.mul(vignetting) + frame_noise));
  }
  return s;
}

/* The truth at pixel (u, v) of row k: the depth (camera k's Z) of the plane its ray hits, and the
   signed distance (px, first camera; about the same in camera k) to the near plane's edge, negative
   on the near plane. */
struct Truth {
  double depth = std::nan(""), edge_px = std::nan("");
  bool near = false;
};

Truth truthAt(const std::vector<MotionSample> &truth, std::size_t k, double u, double v)
{
  const vpHomogeneousMatrix c0Mc = cMc0Of(truth, k).inverse();
  const vpColVector o = c0Mc.getTranslationVector();
  const vpColVector d = vpColVector(c0Mc.getRotationMatrix() * vpColVector({(u - kU0) / kFocal, (v - kV0) / kFocal, 1.0}));
  Truth t;
  // The ray against the near plane: inside its mask?
  const double tn = (kNearDepth - o[2]) / d[2];
  const double un = kU0 + kFocal * (o[0] + tn * d[0]) / kNearDepth, vn = kV0 + kFocal * (o[1] + tn * d[1]) / kNearDepth;
  const double out_u = un - kNearRight, out_v = kNearTop - vn; // > 0: outside past that edge
  t.near = out_u <= 0 && out_v <= 0;
  t.edge_px = t.near ? std::max(out_u, out_v) : std::hypot(std::max(out_u, 0.0), std::max(out_v, 0.0));
  t.depth = t.near ? tn : (kFarDepth - o[2]) / d[2];
  return t;
}

struct Scored {
  std::size_t track;
  long id;
  double est, truth, sigma, ratio, edge_px;
  bool near;
  int frames;
  double chi2, dof, rms_px;
};

struct Summary {
  int ok = 0, beyond = 0, within2 = 0;
  double largest = 0, sq_rel = 0;
  std::vector<Scored> all;
};

void score(const Scene2 &s, const SequenceTracks &seq, const PipelineResult &r, Summary &sum)
{
  for (std::size_t i = 0; i < seq.tracks.size(); ++i) {
    const PointEstimate &e = r.points[i];
    if (!e.ok())
      continue;
    const long row = rowOfFrame(s.truth, e.frame);
    const Observation &last = seq.tracks[i].observations.back();
    const Truth t = truthAt(s.truth, static_cast<std::size_t>(row), last.u, last.v);
    if (!std::isfinite(t.depth))
      continue;
    const double err = e.c_P.z() - t.depth, ratio = std::abs(err) / e.sigmaZ();
    ++sum.ok;
    sum.beyond += ratio > kSigmaLimit ? 1 : 0;
    sum.within2 += ratio <= 2 ? 1 : 0;
    sum.largest = std::max(sum.largest, ratio);
    sum.sq_rel += (err / t.depth) * (err / t.depth);
    const TrackResidual tr = i < r.residuals.tracks.size() ? r.residuals.tracks[i] : TrackResidual();
    sum.all.push_back({i, seq.tracks[i].id, e.c_P.z(), t.depth, e.sigmaZ(), ratio, t.edge_px, t.near,
                       static_cast<int>(seq.tracks[i].observations.size()), tr.chi2, static_cast<double>(tr.dof),
                       tr.rms_px});
  }
}

PipelineOptions pipelineOptions(Method m, const NoiseModel &noise, bool reestimate)
{
  PipelineOptions po;
  po.method = m;
  po.noise = noise;
  po.residual_check.enabled = true;
  po.max_depth_sigma = 0.05;
  po.residual_check.reestimate_noise = reestimate;
  return po;
}

} // namespace

int main(int argc, char **argv)
{
  int frames = 60, draws = 40, worst = 3, max_features = 300;
  double min_ncc = KltOptions().min_ncc, jump_sigmas = KltOptions().jump_sigmas;
  double sigma_odom = 4e-4, sigma_rot = 3e-4, sigma_px = NoiseModel().sigma_px;
  bench::CommandLine cli("[--frames N (>= 3)] [--draws D] [--worst K] [--max-features N] [--min-ncc X] [--jump-sigmas K] [--sigma-odom M] [--sigma-rot R] [--sigma-px S]");
  cli.option("--frames", frames).option("--draws", draws).option("--worst", worst).option("--max-features", max_features);
  cli.option("--min-ncc", min_ncc).option("--jump-sigmas", jump_sigmas);
  cli.option("--sigma-odom", sigma_odom).option("--sigma-rot", sigma_rot).option("--sigma-px", sigma_px);
  if (!cli.parse(argc, argv))
    return 2;
  if (frames < 3 || draws < 1 || worst < 0 || max_features < 1) {
    std::fprintf(stderr, "bench_two_planes: --frames >= 3, --draws >= 1, --worst >= 0, --max-features >= 1\n");
    return 2;
  }
  try {
    cv::setNumThreads(1);
    const CameraModel camera = CameraModel::brown(kFocal, kFocal, kU0, kV0, {0, 0, 0, 0}, 640, 480);
    const Scene2 s = renderScene(camera, frames);
    KltOptions ko;
    ko.max_features = max_features;
    ko.min_ncc = min_ncc;
    ko.jump_sigmas = jump_sigmas;
    std::printf("bench_two_planes: natural features on two textured planes (1.1 m in front of 2.0 m; our render, "
                "photo-like), 640x480, %d frames, 4 mm sideways and 1.5 mrad pan per frame\n",
                frames);
    std::printf("Reproduce: build/benchmarks/bench_two_planes --frames %d --draws %d --worst %d --max-features %d "
                "--min-ncc %g --jump-sigmas %g --sigma-odom %g --sigma-rot %g --sigma-px %g\n",
                frames, draws, worst, max_features, min_ncc, jump_sigmas, sigma_odom, sigma_rot, sigma_px);

    NoiseModel exact;
    exact.motion_noise = MotionNoise::Absolute;
    exact.sigma_odom = 1e-4;
    exact.sigma_heading = 1e-4;
    exact.sigma_yaw = 0;
    exact.sigma_px = sigma_px;
    NoiseModel dr;
    dr.motion_noise = MotionNoise::Increment;
    dr.sigma_odom = sigma_odom;
    dr.sigma_heading = sigma_rot;
    dr.sigma_yaw = sigma_rot;
    dr.sigma_px = sigma_px;

    const Method methods[] = {Method::Fused, Method::Window, Method::Refine};
    std::printf("| motion | method | ok points | largest error / sigma | beyond %.0f sigma | within 2 sigma | RMS rel. "
                "error | noise model scaled by | tracks | cut: appearance | split: jump |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|\n",
                kSigmaLimit);
    const char *const run_names[] = {"exact", "dead reckoning", "exact, model as given"};
    bool met = true;
    std::vector<std::pair<std::string, Summary>> worst_lists;
    // Runs: exact motion, dead reckoning (targets); exact motion with the noise model not re-estimated
    // from the residuals (no target: what the re-estimation does to the sigmas).
    for (int motion = 0; motion < 3; ++motion) {
      const int n_draws = motion == 1 ? draws : 1;
      std::vector<double> scale(3, 0.0);
      std::vector<Summary> sums(3);
      std::size_t n_tracks = 0;
      KltStats totals;
      for (int d = 0; d < n_draws; ++d) {
        std::vector<MotionSample> log = s.truth;
        const NoiseModel &noise = motion == 1 ? dr : exact;
        if (motion == 1) {
          SceneOptions o = motionOptions(frames);
          o.noise = dr;
          o.seed = static_cast<std::uint64_t>(d + 1);
          log = simulateScene(camera, YawRig(), o).measured;
        }
        const SequenceTracks seq = trackSequence(camera, YawRig(), log, [&](std::size_t i) { return s.images[i]; },
                                                 noise, ko);
        n_tracks += seq.tracks.size();
        totals.lost_appearance += seq.totals.lost_appearance;
        totals.split_jump += seq.totals.split_jump;
        for (int m = 0; m < 3; ++m) {
          const PipelineResult r =
              estimatePoints(camera, YawRig(), log, seq.tracks, pipelineOptions(methods[m], noise, motion != 2));
          score(s, seq, r, sums[static_cast<std::size_t>(m)]);
          scale[static_cast<std::size_t>(m)] += r.residuals.noise_scale / n_draws;
        }
      }
      for (int m = 0; m < 3; ++m) {
        Summary &sum = sums[static_cast<std::size_t>(m)];
        const double cover = sum.ok ? static_cast<double>(sum.within2) / sum.ok : 0.0;
        const bool ok = sum.beyond == 0 && (motion != 1 || (cover >= kCoverLo && cover <= kCoverHi));
        if (motion != 2)
          met = met && ok;
        std::printf("| %s | %s | %d | %.1f | %d | %.3f | %.2f %% | %.3f | %zu | %d | %d |\n", run_names[motion],
                    toString(methods[m]), sum.ok, sum.largest, sum.beyond, cover,
                    sum.ok ? 100 * std::sqrt(sum.sq_rel / sum.ok) : 0.0, scale[static_cast<std::size_t>(m)], n_tracks,
                    totals.lost_appearance, totals.split_jump);
        worst_lists.emplace_back(std::string(run_names[motion]) + ", " + toString(methods[m]), std::move(sum));
      }
    }
    if (draws > 1)
      std::printf("(dead reckoning: %d draws, seeds 1..%d, pooled; tracks and cuts summed over the draws)\n", draws,
                  draws);
    std::printf("target: exact motion, no ok point beyond %.0f sigma; dead reckoning, none beyond %.0f sigma and "
                "2-sigma coverage in [%.2f, %.2f]: %s\n",
                kSigmaLimit, kSigmaLimit, kCoverLo, kCoverHi, met ? "met" : "MISSED");
    if (worst > 0) {
      std::printf("\nWorst ok points (edge: distance to the occlusion edge in the last image, px, negative on the near "
                  "plane; chi2/dof of the residual check)\n");
      std::printf("| run | id | frames | plane | edge px | depth | truth | sigma | error / sigma | chi2/dof | rms px "
                  "|\n|---|---|---|---|---|---|---|---|---|---|---|\n");
      for (auto &[name, sum] : worst_lists) {
        std::sort(sum.all.begin(), sum.all.end(), [](const Scored &a, const Scored &b) { return a.ratio > b.ratio; });
        for (std::size_t k = 0; k < sum.all.size() && k < static_cast<std::size_t>(worst); ++k) {
          const Scored &p = sum.all[k];
          std::printf("| %s | %ld | %d | %s | %.1f | %.3f | %.3f | %.4f | %.1f | %.2f | %.2f |\n", name.c_str(), p.id,
                      p.frames, p.near ? "near" : "far", p.edge_px, p.est, p.truth, p.sigma, p.ratio,
                      p.dof > 0 ? p.chi2 / p.dof : std::nan(""), p.rms_px);
        }
      }
    }
    return met ? 0 : 1;
  } catch (const Error &e) {
    std::fprintf(stderr, "bench_two_planes: %s\n", e.what());
    return 1;
  }
}
