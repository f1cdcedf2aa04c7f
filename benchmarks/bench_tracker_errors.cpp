/*
  bench_tracker_errors: what the KLT tracker's errors are, to decide how the estimators model them
  (white noise, a random walk, a constant per-track bias, or AR(1): e_k = phi^gap e_{k-1} + innovation).

    bench_tracker_errors [--scene wall|castle|franka|all] [--wall-frames N] [--castle-frames N (2-40)]
                         [--max-features N] [--data DIR] [--franka DIR]

  The tracker is configured as `measure --features klt` by default (KltOptions' defaults, --max-features;
  trackSequence with the epipolar gate, the motion given as exact), as bench_klt and
  bench_castle run it. Scenes:
  (a) wall: bench_klt's photo-like textured wall (klt_wall.h; our render). Truth: the wall's
      homography. A track whose first pixel lies within kTextureMarginPx of the texture's mirrored
      border (BORDER_REFLECT) has no truth.
  (b) castle: Debian's visp-images-data mbt-depth/Castle-simu (someone else's renderer, castle_truth.h):
      the truth of a track is where the ray of its first pixel first meets that frame's depth map,
      moved by the poses; tracks without it (background, occluding edge) are skipped, as bench_castle.
  (c) franka: the real photos of tests/data/franka-eye-in-hand (a 9x6 chessboard; consecutive
      photos, wide baselines). Each pair is tracked by KltTracker (guided = auto, as bench_wide_baseline)
      with the motion from the board's pose in each photo (solvePnP on the chessboard corners); the truth
      is the board plane's homography between the two photos, from the 54 corners
      (findChessboardCorners + cornerSubPix); only features inside the board's outer corners count.
      Two photos give one step: no temporal correlation, only the error's size per pair.

  Per track (scenes a, b) the error sequence e_k (px, 2-vector) = the tracked position minus the true
  projection, in the frame k frames after detection, of the 3-D point where the ray of the track's
  FIRST observation meets the surface: e_0 = 0 by construction. A track whose error ever exceeds
  kGrossPx is a wrong lock (an outlier: the checks' business, not the noise model's), counted apart and
  left out of the statistics. Statistics, pooled over tracks and both axes:
  - std (about the pooled mean) and RMS of e_k against k: flat = white noise or a bias after
    detection, growing like sqrt(k) = a random walk (drift). Since e_0 = 0, E[e_k^2] = 2 gamma(k).
  - the increments d_k = e_k - e_{k-1} (consecutive frames): std, and their lag-1 correlation (0 for a
    random walk, -0.5 for white noise, -(1 - phi)/2 for AR(1)).
  - per-track bias: the RMS over tracks of each track's mean error (k >= 1) against the RMS of the
    spread within a track; white noise relative to the detection gives a ratio near 1 (its mean is
    minus the detection's own noise), a constant bias or a random walk gives more.
  - the lag-1, 2, 5 autocorrelation of each track's de-meaned error (k >= 1, tracks of 10+ steps),
    pooled: phi^h for AR(1) (minus about 1/length from the de-meaning).
  - the variogram gamma(h) = E[(e_{k+h} - e_k)^2] / 2, h = 1..20, over every pair of a track's frames
    h apart; it needs no truth of the detection's own error and ignores a per-track constant. Fitted
    by least squares on the relative residual, each lag weighted by its number of pairs: white:
    gamma = w^2; random walk + white: gamma = w^2 + q^2 h / 2 (e = r + w, r a random walk of step q);
    AR(1): gamma = s^2 (1 - phi^h) (stationary sigma s, phi per frame, on a grid up to 0.999, where
    AR(1) is a random walk over 20 frames); AR(1) + white: w^2 + s^2 (1 - phi^h). The best
    2-parameter model has the smallest RMS relative residual.
  - texture: tracks in quartiles of the Shi-Tomasi score (cv::cornerMinEigenVal, block 7, at the
    detection pixel in the track's first image): the increments' std, gamma(1) and gamma(10).
  - distance: the increments' std in bins of the true image motion of that step (px per frame), and
    the increments' and errors' std in bins of the true motion accumulated since detection.
*/
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <visp3/core/vpThetaUVector.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/pipeline/pipeline.h>

#include "bench_common.h"
#include "castle_truth.h"
#include "klt_wall.h"

using namespace yawdepth;

namespace {

constexpr double kGrossPx = 3.0;        // a track whose |e_k| ever exceeds this is a wrong lock
constexpr double kTextureMarginPx = 16; // wall: the LK window (21 px) and the blur clear of the mirrored border
constexpr int kMaxLag = 20;             // the variogram's lags the models are fitted to
constexpr int kLongLag = 40;            // the lags it is computed and predicted to (21..40: out of the fit)
constexpr int kMinBiasSteps = 10;       // tracks of this many steps after detection for the bias and autocorrelation

/* One track's errors (frames since detection, px). */
struct TrackErrors {
  std::vector<long> k;                // frames since the track's first observation
  std::vector<Eigen::Vector2d> e;     // tracked minus true position (px); e[0] = 0
  std::vector<Eigen::Vector2d> truth; // the true position (px)
  double score = 0;                   // Shi-Tomasi score (min eigenvalue) at the detection pixel
};

/* A scene's tracks with their errors. */
struct SceneErrors {
  std::string name;
  std::vector<TrackErrors> tracks;
  std::size_t all_tracks = 0, no_truth = 0, gross = 0;
  double largest_e0 = 0; // the largest |e_0| (px): 0 but for rounding, a check of the truth's arithmetic
};

/* The truth of a scene: `locate` the 3-D point (in whatever frame the scene uses) of a track's first
   observation, false without truth; `project` it into a frame (px). */
struct Truth {
  std::function<bool(const Observation &first, Eigen::Vector3d &X)> locate;
  std::function<Eigen::Vector2d(const Eigen::Vector3d &X, long frame)> project;
};

/* Pooled mean and std of 2-vectors (both axes, each about its own mean) and their RMS. */
struct Pooled {
  std::array<double, 2> n{}, sum{}, sq{};
  void add(const Eigen::Vector2d &x)
  {
    for (int a = 0; a < 2; ++a) {
      n[a] += 1;
      sum[a] += x[a];
      sq[a] += x[a] * x[a];
    }
  }
  double count() const { return n[0]; }
  double mean(int a) const { return n[a] > 0 ? sum[a] / n[a] : std::nan(""); }
  double std() const
  {
    if (n[0] < 2)
      return std::nan("");
    return std::sqrt((sq[0] - sum[0] * sum[0] / n[0] + sq[1] - sum[1] * sum[1] / n[1]) / (n[0] + n[1] - 2));
  }
  double rms() const { return n[0] > 0 ? std::sqrt((sq[0] + sq[1]) / (n[0] + n[1])) : std::nan(""); }
};

/* Shi-Tomasi scores of a frame's pixels, computed once per frame. */
class ScoreMaps {
public:
  explicit ScoreMaps(std::function<cv::Mat(long frame)> image) : image_(std::move(image)) {}
  double at(long frame, double u, double v)
  {
    auto it = maps_.find(frame);
    if (it == maps_.end()) {
      cv::Mat eig;
      cv::cornerMinEigenVal(image_(frame), eig, 7, 3); // block 7: KltOptions::block_size
      it = maps_.emplace(frame, eig).first;
    }
    const int iu = std::clamp(static_cast<int>(std::lround(u)), 0, it->second.cols - 1);
    const int iv = std::clamp(static_cast<int>(std::lround(v)), 0, it->second.rows - 1);
    return it->second.at<float>(iv, iu);
  }

private:
  std::function<cv::Mat(long)> image_;
  std::map<long, cv::Mat> maps_;
};

/* Every track of `tracks` against the truth: its errors, or counted as without truth or gross. */
SceneErrors collectErrors(const std::string &name, const std::vector<Track> &tracks, const Truth &truth,
                          ScoreMaps &scores)
{
  SceneErrors s;
  s.name = name;
  s.all_tracks = tracks.size();
  for (const Track &t : tracks) {
    const Observation &first = t.observations.front();
    Eigen::Vector3d X;
    if (!truth.locate(first, X)) {
      ++s.no_truth;
      continue;
    }
    TrackErrors te;
    bool gross = false;
    for (const Observation &o : t.observations) {
      const Eigen::Vector2d p = truth.project(X, o.frame);
      te.k.push_back(o.frame - first.frame);
      te.truth.push_back(p);
      te.e.push_back(Eigen::Vector2d(o.u, o.v) - p);
      gross = gross || !(te.e.back().norm() <= kGrossPx);
    }
    if (gross) {
      ++s.gross;
      continue;
    }
    s.largest_e0 = std::max(s.largest_e0, te.e.front().norm());
    te.score = scores.at(first.frame, first.u, first.v);
    s.tracks.push_back(std::move(te));
  }
  return s;
}

/* ---- statistics ---- */

/* The variogram gamma(h), h = 0..kLongLag (px^2, both axes pooled; gamma[0] unused), with its pair counts. */
struct Variogram {
  std::vector<double> gamma = std::vector<double>(kLongLag + 1, 0.0), pairs = std::vector<double>(kLongLag + 1, 0.0);
};

Variogram variogram(const std::vector<TrackErrors> &tracks)
{
  Variogram g;
  std::vector<double> sum(kLongLag + 1, 0.0);
  for (const TrackErrors &t : tracks)
    for (std::size_t i = 0; i < t.k.size(); ++i)
      for (std::size_t j = i + 1; j < t.k.size() && t.k[j] - t.k[i] <= kLongLag; ++j) {
        const auto h = static_cast<std::size_t>(t.k[j] - t.k[i]);
        sum[h] += (t.e[j] - t.e[i]).squaredNorm(); // both axes
        g.pairs[h] += 2;
      }
  for (std::size_t h = 1; h <= kLongLag; ++h)
    g.gamma[h] = g.pairs[h] > 0 ? 0.5 * sum[h] / g.pairs[h] : std::nan("");
  return g;
}

/* The increments d_k = e_k - e_{k-1} over consecutive frames: pooled std, and the lag-1 correlation of
   consecutive increments (pairs d_k, d_{k+1} of the same track). */
struct Increments {
  Pooled d;
  double lag1 = std::nan("");
};

Increments increments(const std::vector<TrackErrors> &tracks)
{
  Increments r;
  double sxy = 0, sxx = 0, syy = 0;
  for (const TrackErrors &t : tracks)
    for (std::size_t i = 1; i < t.k.size(); ++i) {
      if (t.k[i] - t.k[i - 1] != 1)
        continue;
      const Eigen::Vector2d d = t.e[i] - t.e[i - 1];
      r.d.add(d);
      if (i + 1 < t.k.size() && t.k[i + 1] - t.k[i] == 1) {
        const Eigen::Vector2d next = t.e[i + 1] - t.e[i];
        sxy += d.dot(next);
        sxx += d.squaredNorm();
        syy += next.squaredNorm();
      }
    }
  if (sxx > 0 && syy > 0)
    r.lag1 = sxy / std::sqrt(sxx * syy);
  return r;
}

/* A model of gamma(h): its name, parameters (printed), values (h = 0..kLongLag) and RMS relative residual over
   h = 1..kMaxLag. */
struct Fit {
  std::string name, params;
  std::vector<double> model;
  double residual = std::nan("");
  double phi = std::nan(""), sigma = std::nan(""); // AR(1): phi per frame, stationary sigma (px)
};

/* Least squares of gamma(h) ~ a f(h) + b g(h) on the relative residual (weights pairs(h) / gamma(h)^2), a, b >= 0
   (one of them 0 when the unconstrained optimum has a negative one); g = nullptr: b = 0. */
std::pair<double, double> fitTwo(const Variogram &v, const std::function<double(int)> &f,
                                 const std::function<double(int)> *g)
{
  double aa = 0, ab = 0, bb = 0, ay = 0, by = 0;
  for (int h = 1; h <= kMaxLag; ++h) {
    const double y = v.gamma[static_cast<std::size_t>(h)];
    if (!(y > 0))
      continue;
    const double fa = f(h) / y, fb = g ? (*g)(h) / y : 0.0; // divided by gamma: the relative residual
    const double n = v.pairs[static_cast<std::size_t>(h)]; // each lag weighted by its pairs
    aa += n * fa * fa;
    ab += n * fa * fb;
    bb += n * fb * fb;
    ay += n * fa;
    by += n * fb;
  }
  const double det = aa * bb - ab * ab;
  double a = aa > 0 ? ay / aa : 0, b = 0;
  if (g && det > 1e-12 * aa * bb) {
    a = (ay * bb - by * ab) / det;
    b = (by * aa - ay * ab) / det;
    if (a < 0 || b < 0) { // the better of a alone and b alone
      const double a_only = std::max(0.0, ay / aa), b_only = bb > 0 ? std::max(0.0, by / bb) : 0.0;
      const double cost_a = a_only * a_only * aa - 2 * a_only * ay, cost_b = b_only * b_only * bb - 2 * b_only * by;
      a = cost_a <= cost_b ? a_only : 0.0;
      b = cost_a <= cost_b ? 0.0 : b_only;
    }
  }
  return {a, b};
}

/* The RMS relative residual of `model` against the variogram. */
double relativeResidual(const Variogram &v, const std::vector<double> &model)
{
  double sum = 0, n = 0;
  for (int h = 1; h <= kMaxLag; ++h) {
    const double y = v.gamma[static_cast<std::size_t>(h)], pairs = v.pairs[static_cast<std::size_t>(h)];
    if (y > 0) {
      sum += pairs * std::pow((model[static_cast<std::size_t>(h)] - y) / y, 2);
      n += pairs;
    }
  }
  return n > 0 ? std::sqrt(sum / n) : std::nan("");
}

/* Fills a model's values from its function and its residual. */
Fit finish(Fit f, const Variogram &v, const std::function<double(int)> &gamma)
{
  f.model.assign(kLongLag + 1, 0.0);
  for (int h = 1; h <= kLongLag; ++h)
    f.model[static_cast<std::size_t>(h)] = gamma(h);
  f.residual = relativeResidual(v, f.model);
  return f;
}

/* AR(1) (with_white: plus white noise): phi on a grid of 0.001, the variances by fitTwo. */
Fit fitAr1(const Variogram &v, bool with_white)
{
  Fit best;
  const std::function<double(int)> one = [](int) { return 1.0; };
  for (int i = 0; i < 1000; ++i) {
    const double phi = 0.001 * i;
    const std::function<double(int)> ar = [phi](int h) { return 1.0 - std::pow(phi, h); };
    const auto [s2, w2] = fitTwo(v, ar, with_white ? &one : nullptr);
    char params[160];
    std::snprintf(params, sizeof params, with_white ? "phi %.3f, sigma %.3f px, white %.3f px" : "phi %.3f, sigma %.3f px",
                  phi, std::sqrt(s2), std::sqrt(w2));
    Fit f = finish({with_white ? "AR(1) + white" : "AR(1)", params, {}, 0, phi, std::sqrt(s2)}, v,
                   [&](int h) { return w2 + s2 * ar(h); });
    if (std::isnan(best.residual) || f.residual < best.residual)
      best = f;
  }
  return best;
}

/* The four models of the file, fitted to `v`. */
std::vector<Fit> fitModels(const Variogram &v)
{
  const std::function<double(int)> one = [](int) { return 1.0; }, half_h = [](int h) { return 0.5 * h; };
  const double w2 = fitTwo(v, one, nullptr).first;
  char params[160];
  std::snprintf(params, sizeof params, "w %.3f px", std::sqrt(w2));
  std::vector<Fit> fits{finish({"white", params, {}, 0}, v, [&](int) { return w2; })};
  const auto [c, q2] = fitTwo(v, one, &half_h);
  std::snprintf(params, sizeof params, "q %.4f px/sqrt(frame), w %.3f px", std::sqrt(q2), std::sqrt(c));
  fits.push_back(finish({"random walk + white", params, {}, 0}, v, [&](int h) { return c + q2 * 0.5 * h; }));
  fits.push_back(fitAr1(v, false));
  fits.push_back(fitAr1(v, true));
  return fits;
}

/* ---- tables ---- */

/* std and RMS of e_k against k, beside each model's prediction sqrt(2 gamma(k)) (e_0 = 0). */
void printErrorVsK(const SceneErrors &s, const std::vector<Fit> &fits)
{
  std::printf("\n%s: the error e_k against k, frames since detection (px; both axes pooled); a model's RMS is sqrt(2 "
              "gamma(k))\n| k | tracks | mean u | mean v | std | RMS | RW + white RMS | AR(1) RMS |\n"
              "|---|---|---|---|---|---|---|---|\n",
              s.name.c_str());
  for (long k : {1L, 2L, 5L, 10L, 20L, 40L}) {
    Pooled p;
    for (const TrackErrors &t : s.tracks)
      for (std::size_t i = 0; i < t.k.size(); ++i)
        if (t.k[i] == k)
          p.add(t.e[i]);
    if (p.count() < 2)
      continue;
    const auto model = [&](const Fit &f) {
      return k <= kLongLag ? std::sqrt(2 * f.model[static_cast<std::size_t>(k)]) : std::nan("");
    };
    std::printf("| %ld | %.0f | %+.3f | %+.3f | %.3f | %.3f | %.3f | %.3f |\n", k, p.count(), p.mean(0), p.mean(1), p.std(),
                p.rms(), model(fits[1]), model(fits[2]));
  }
}

/* Per-track bias and the pooled autocorrelation of the de-meaned errors (k >= 1, tracks of kMinBiasSteps+ steps). */
void printBiasAndAutocorrelation(const SceneErrors &s, double phi)
{
  double mean_sq = 0, within_sq = 0, tracks = 0;
  const std::array<int, 3> lags{1, 2, 5};
  std::array<double, 3> lagged{};
  std::array<double, 3> lagged_n{};
  double var = 0, var_n = 0;
  for (const TrackErrors &t : s.tracks) {
    if (t.k.size() < static_cast<std::size_t>(kMinBiasSteps) + 1)
      continue;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (std::size_t i = 1; i < t.k.size(); ++i)
      mean += t.e[i];
    mean /= static_cast<double>(t.k.size() - 1);
    double within = 0;
    for (std::size_t i = 1; i < t.k.size(); ++i) {
      within += (t.e[i] - mean).squaredNorm();
      for (std::size_t l = 0; l < lags.size(); ++l)
        for (std::size_t j = i + 1; j < t.k.size() && t.k[j] - t.k[i] <= lags[l]; ++j)
          if (t.k[j] - t.k[i] == lags[l]) {
            lagged[l] += (t.e[i] - mean).dot(t.e[j] - mean);
            lagged_n[l] += 2;
          }
    }
    var += within;
    var_n += 2.0 * static_cast<double>(t.k.size() - 1);
    mean_sq += mean.squaredNorm() / 2;
    within_sq += within / (2.0 * static_cast<double>(t.k.size() - 2));
    tracks += 1;
  }
  if (tracks < 1) {
    std::printf("%s: no track of %d+ steps for the bias and the autocorrelation\n", s.name.c_str(), kMinBiasSteps);
    return;
  }
  std::printf("\n%s: per-track bias and autocorrelation (k >= 1, %.0f tracks of %d+ steps; px)\n| RMS of a track's mean "
              "error | RMS spread within a track | ratio | autocorrelation lag 1 | lag 2 | lag 5 | AR(1) fit: phi, phi^2, "
              "phi^5 |\n|---|---|---|---|---|---|---|\n",
              s.name.c_str(), tracks, kMinBiasSteps);
  const double sd = var_n > 0 ? var / var_n : std::nan("");
  const auto r = [&](std::size_t l) { return lagged_n[l] > 0 ? lagged[l] / lagged_n[l] / sd : std::nan(""); };
  std::printf("| %.3f | %.3f | %.2f | %.3f | %.3f | %.3f | %.3f, %.3f, %.3f |\n", std::sqrt(mean_sq / tracks),
              std::sqrt(within_sq / tracks), std::sqrt(mean_sq / within_sq), r(0), r(1), r(2), phi, phi * phi,
              std::pow(phi, 5));
}

/* The increments and the variogram, with the models' fits; returns the fits. */
std::vector<Fit> printIncrementsAndVariogram(const SceneErrors &s, const Variogram &v)
{
  const Increments inc = increments(s.tracks);
  std::printf("\n%s: increments d_k = e_k - e_{k-1} (consecutive frames; px): %.0f increments, std %.3f px, lag-1 "
              "correlation %+.3f (random walk 0, white -0.5, AR(1) -(1 - phi)/2)\n",
              s.name.c_str(), inc.d.count(), inc.d.std(), inc.lag1);
  const std::vector<Fit> fits = fitModels(v);
  std::printf("\n%s: variogram gamma(h) = E[(e_{k+h} - e_k)^2] / 2 (px^2) and the fitted models\n| h | pairs | gamma |",
              s.name.c_str());
  for (const Fit &f : fits)
    std::printf(" %s |", f.name.c_str());
  std::printf("\n|---|---|---|---|---|---|---|\n");
  for (int h : {1, 2, 3, 5, 7, 10, 15, 20, 30, 40}) {
    const auto i = static_cast<std::size_t>(h);
    if (!(v.pairs[i] > 0))
      continue;
    std::printf("| %d%s | %.0f | %.4f |", h, h > kMaxLag ? " (not fitted)" : "", v.pairs[i], v.gamma[i]);
    for (const Fit &f : fits)
      std::printf(" %.4f |", f.model[i]);
    std::printf("\n");
  }
  std::printf("| model | parameters | RMS relative residual (h = 1..%d, weighted by pairs) |\n|---|---|---|\n", kMaxLag);
  for (const Fit &f : fits)
    std::printf("| %s | %s | %.3f |\n", f.name.c_str(), f.params.c_str(), f.residual);
  const Fit &best = fits[1].residual <= fits[2].residual ? fits[1] : fits[2];
  std::printf("%s: best 2-parameter model: %s (residual %.3f against %.3f); AR(1) per frame: phi %.3f, stationary "
              "sigma %.3f px%s\n",
              s.name.c_str(), best.name.c_str(), best.residual, (&best == &fits[1] ? fits[2] : fits[1]).residual,
              fits[2].phi, fits[2].sigma, fits[2].phi >= 0.999 ? " (phi at the grid's end: a random walk over these lags)" : "");
  return fits;
}

/* Texture: the increments' std, gamma(1) and gamma(10) per quartile of the Shi-Tomasi score. */
void printTexture(const SceneErrors &s)
{
  std::vector<double> scores;
  for (const TrackErrors &t : s.tracks)
    scores.push_back(t.score);
  std::printf("\n%s: by texture, quartiles of the Shi-Tomasi score at detection (min eigenvalue, block 7)\n| quartile | "
              "score | tracks | increment std (px) | gamma(1) | gamma(10) |\n|---|---|---|---|---|---|\n",
              s.name.c_str());
  for (int q = 0; q < 4; ++q) {
    const double lo = bench::quantile(scores, 0.25 * q), hi = bench::quantile(scores, 0.25 * (q + 1));
    std::vector<TrackErrors> part;
    for (const TrackErrors &t : s.tracks)
      if (t.score >= lo && (t.score < hi || (q == 3 && t.score <= hi)))
        part.push_back(t);
    const Variogram v = variogram(part);
    std::printf("| %d | %.3g-%.3g | %zu | %.3f | %.4f | %.4f |\n", q + 1, lo, hi, part.size(), increments(part).d.std(),
                v.gamma[1], v.gamma[10]);
  }
}

/* Distance: the increments' std in bins of the true motion of the step, and the increments' and the errors' std
   in bins of the true motion accumulated since detection. */
void printDistance(const SceneErrors &s)
{
  const std::vector<double> step_edges{0, 0.5, 1, 2, 4, 8, 16, 1e9}, total_edges{0, 5, 10, 20, 40, 80, 160, 1e9};
  std::vector<Pooled> by_step(step_edges.size() - 1), by_total(total_edges.size() - 1), e_by_total(total_edges.size() - 1);
  const auto bin = [](const std::vector<double> &edges, double x) {
    return static_cast<std::size_t>(std::upper_bound(edges.begin(), edges.end(), x) - edges.begin() - 1);
  };
  for (const TrackErrors &t : s.tracks)
    for (std::size_t i = 1; i < t.k.size(); ++i) {
      const std::size_t b = bin(total_edges, (t.truth[i] - t.truth[0]).norm());
      e_by_total[b].add(t.e[i]);
      if (t.k[i] - t.k[i - 1] != 1)
        continue;
      by_step[bin(step_edges, (t.truth[i] - t.truth[i - 1]).norm())].add(t.e[i] - t.e[i - 1]);
      by_total[b].add(t.e[i] - t.e[i - 1]);
    }
  std::printf("\n%s: by the distance tracked (true image motion, px)\n| motion per step (px/frame) | increments | "
              "increment std (px) |\n|---|---|---|\n",
              s.name.c_str());
  for (std::size_t b = 0; b < by_step.size(); ++b)
    if (by_step[b].count() >= 2)
      std::printf("| %g-%g | %.0f | %.3f |\n", step_edges[b], step_edges[b + 1], by_step[b].count(), by_step[b].std());
  std::printf("| motion since detection (px) | increments | increment std (px) | errors | error std (px) |\n"
              "|---|---|---|---|---|\n");
  for (std::size_t b = 0; b < by_total.size(); ++b)
    if (e_by_total[b].count() >= 2)
      std::printf("| %g-%g | %.0f | %.3f | %.0f | %.3f |\n", total_edges[b], total_edges[b + 1], by_total[b].count(),
                  by_total[b].std(), e_by_total[b].count(), e_by_total[b].std());
}

/* Every table of a sequence scene. */
void analyse(const SceneErrors &s)
{
  std::printf("\n## %s: %zu tracks over 2+ frames; %zu without truth; %zu gross (|e| > %.0f px in some frame, left out); "
              "%zu measured; largest |e_0| %.1e px\n",
              s.name.c_str(), s.all_tracks, s.no_truth, s.gross, kGrossPx, s.tracks.size(), s.largest_e0);
  if (s.tracks.empty())
    return;
  const Variogram v = variogram(s.tracks);
  const std::vector<Fit> fits = printIncrementsAndVariogram(s, v);
  printErrorVsK(s, fits);
  printBiasAndAutocorrelation(s, fits[2].phi);
  printTexture(s);
  printDistance(s);
}

/* ---- scenes ---- */

/* The gate's motion noise as bench_klt and bench_castle give it: the poses exact (per-pose noise 0). */
NoiseModel exactMotionNoise()
{
  NoiseModel noise;
  noise.motion_noise = MotionNoise::Absolute;
  noise.sigma_odom = 0;
  noise.sigma_rot = 0;
  noise.sigma_heading = 0;
  noise.sigma_yaw = 0;
  return noise;
}

/* (a) bench_klt's wall. X: the track's point in texture pixels (homogeneous). */
SceneErrors wallScene(int frames, const KltOptions &ko)
{
  using namespace bench::wall;
  const Sequence s = renderSequence(frames);
  const CameraModel camera = CameraModel::brown(kFocal, kFocal, kU0, kV0, {0, 0, 0, 0}, kWidth, kHeight);
  const SequenceTracks seq =
      trackSequence(camera, YawRig(), s.motion, [&](std::size_t i) { return s.images[i]; }, exactMotionNoise(), ko);
  std::vector<cv::Matx33d> H; // texture pixels -> frame k's pixels
  for (std::size_t k = 0; k < s.images.size(); ++k)
    H.push_back(wallHomography(cMc0(s, k)));
  Truth truth;
  truth.locate = [&](const Observation &o, Eigen::Vector3d &X) {
    const cv::Vec3d t = H[static_cast<std::size_t>(o.frame)].inv() * cv::Vec3d(o.u, o.v, 1.0);
    X = Eigen::Vector3d(t[0] / t[2], t[1] / t[2], 1.0);
    return X.x() >= kTextureMarginPx && X.x() <= kWidth - 1 - kTextureMarginPx && X.y() >= kTextureMarginPx &&
           X.y() <= kHeight - 1 - kTextureMarginPx;
  };
  truth.project = [&](const Eigen::Vector3d &X, long frame) {
    const cv::Vec3d p = H[static_cast<std::size_t>(frame)] * cv::Vec3d(X.x(), X.y(), 1.0);
    return Eigen::Vector2d(p[0] / p[2], p[1] / p[2]);
  };
  ScoreMaps scores([&](long frame) { return s.images[static_cast<std::size_t>(frame)]; });
  return collectErrors("wall (our render)", seq.tracks, truth, scores);
}

/* (b) Castle-simu, frames 1..frames. X: the track's point in the object's frame. */
SceneErrors castleScene(const std::string &data, int frames, const KltOptions &ko)
{
  using namespace bench::castle;
  const CameraModel camera = CameraModel::brown(kFocal, kFocal, kU0, kV0, {0, 0, 0, 0}, 640, 480);
  const Sequence q = readSequence(data, frames);
  const std::vector<MotionSample> &motion = q.motion;
  const std::vector<DepthMap> &depth = q.depth;
  std::vector<cv::Mat> images;
  for (const std::string &path : q.images)
    images.push_back(readGrayImage(path, camera));
  const SequenceTracks seq =
      trackSequence(camera, YawRig(), motion, [&](std::size_t i) { return images[i]; }, exactMotionNoise(), ko);
  const auto row = [](long frame) { return static_cast<std::size_t>(frame - 1); };
  Truth truth;
  truth.locate = [&](const Observation &o, Eigen::Vector3d &X) {
    const double z = rayTruth(depth[row(o.frame)], o.u, o.v);
    if (!std::isfinite(z))
      return false;
    const vpColVector w = wMc(YawRig(), motion[row(o.frame)]) *
                          vpColVector({(o.u - kU0) / kFocal * z, (o.v - kV0) / kFocal * z, z, 1.0});
    X = Eigen::Vector3d(w[0], w[1], w[2]);
    return true;
  };
  truth.project = [&](const Eigen::Vector3d &X, long frame) {
    const vpColVector c = wMc(YawRig(), motion[row(frame)]).inverse() * vpColVector({X.x(), X.y(), X.z(), 1.0});
    return Eigen::Vector2d(kFocal * c[0] / c[2] + kU0, kFocal * c[1] / c[2] + kV0);
  };
  ScoreMaps scores([&](long frame) { return images[row(frame)]; });
  return collectErrors("Castle-simu (visp-images-data, someone else's renderer)", seq.tracks, truth, scores);
}

/* ---- (c) the franka photos ---- */

/* A photo's chessboard: its 54 inner corners (sub-pixel) and the board's pose in the camera; found false when
   OpenCV does not find the board. */
struct Board {
  bool found = false;
  std::vector<cv::Point2f> corners;
  vpHomogeneousMatrix cMo;
};

/* The board's 54 corners in its own frame (m): row by row, OpenCV's order. */
std::vector<cv::Point3f> boardPoints()
{
  constexpr double kSquare = 0.0236; // m (chessboard-data.txt)
  std::vector<cv::Point3f> object;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 9; ++c)
      object.emplace_back(static_cast<float>(c * kSquare), static_cast<float>(r * kSquare), 0.0f);
  return object;
}

/* The board's pose in the camera of photo `n` (1..8) from the arm: cMo = (rMe eMc)^-1 rMo, rMe from
   franka_pose_rPe_N.yaml, eMc and rMo as ViSP's hand-eye tutorial publishes them (the data's README). */
vpHomogeneousMatrix kinematicPose(const std::string &dir, int n)
{
  const std::string path = dir + "/franka_pose_rPe_" + std::to_string(n) + ".yaml";
  std::ifstream in(path);
  std::string line;
  std::vector<double> p;
  while (std::getline(in, line)) {
    const std::size_t open = line.find("- [");
    if (open != std::string::npos)
      p.push_back(std::atof(line.c_str() + open + 3));
  }
  if (p.size() != 6)
    throw Error(path + ": expected 6 values (a vpPoseVector)");
  const vpHomogeneousMatrix rMe(p[0], p[1], p[2], p[3], p[4], p[5]);
  const vpHomogeneousMatrix eMc(0.0577148, -0.0339261, -0.0422745, 0.00178253, 0.00917657, 1.58178);
  const vpHomogeneousMatrix rMo(0.5364858483, 0.123945742, 0.09155742609, 2.22636085, -2.213916548, 0.02071766945);
  return (rMe * eMc).inverse() * rMo;
}

/* The corners, and the board's pose by solvePnP, of a photo; the grid's order (a 9x6 grid read from
   its other end is the same grid) is the one that agrees with the arm's pose `cMo_arm`, so that corner
   i is the same physical corner in every photo. */
Board detectBoard(const cv::Mat &image, const CameraModel &camera, const vpHomogeneousMatrix &cMo_arm)
{
  Board b;
  b.found = cv::findChessboardCorners(image, cv::Size(9, 6), b.corners,
                                      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (!b.found)
    return b;
  cv::cornerSubPix(image, b.corners, cv::Size(11, 11), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
  const std::vector<cv::Point3f> object = boardPoints();
  double as_is = 0, reversed = 0;
  for (std::size_t i = 0; i < object.size(); ++i) {
    const vpColVector c = cMo_arm * vpColVector({object[i].x, object[i].y, 0.0, 1.0});
    const cv::Point2f q(static_cast<float>(camera.kx() * c[0] / c[2] + camera.u0()),
                        static_cast<float>(camera.ky() * c[1] / c[2] + camera.v0()));
    as_is += cv::norm(q - b.corners[i]);
    reversed += cv::norm(q - b.corners[object.size() - 1 - i]);
  }
  if (reversed < as_is)
    std::reverse(b.corners.begin(), b.corners.end());
  const cv::Matx33d K(camera.kx(), 0, camera.u0(), 0, camera.ky(), camera.v0(), 0, 0, 1);
  cv::Vec3d rvec, tvec;
  cv::solvePnP(object, b.corners, K, cv::noArray(), rvec, tvec);
  cv::Matx33d R;
  cv::Rodrigues(rvec, R);
  for (unsigned i = 0; i < 3; ++i) {
    for (unsigned j = 0; j < 3; ++j)
      b.cMo[i][j] = R(static_cast<int>(i), static_cast<int>(j));
    b.cMo[i][3] = tvec[static_cast<int>(i)];
  }
  return b;
}

/* One pair's errors: the board's features tracked from photo a to photo b against the board's homography. */
struct PairErrors {
  int in_board = 0, tracked = 0;
  KltStats stats; // the second image's tracking (every feature, in the board or not)
  std::vector<double> err;
  double h_rms = 0, motion = 0; // the homography's RMS residual on the corners; the corners' median motion (px)
  double turn = 0;              // the camera's rotation between the photos (degrees, from the boards' poses)
};

PairErrors measurePair(const cv::Mat &a, const cv::Mat &b, const Board &ba, const Board &bb, const CameraModel &camera,
                       const KltOptions &ko)
{
  PairErrors r;
  const cv::Mat H = cv::findHomography(ba.corners, bb.corners, 0);
  std::vector<cv::Point2f> mapped;
  cv::perspectiveTransform(ba.corners, mapped, H);
  for (std::size_t i = 0; i < mapped.size(); ++i)
    r.h_rms += std::pow(cv::norm(mapped[i] - bb.corners[i]), 2) / static_cast<double>(mapped.size());
  r.h_rms = std::sqrt(r.h_rms);
  std::vector<double> motion;
  for (std::size_t i = 0; i < ba.corners.size(); ++i)
    motion.push_back(cv::norm(bb.corners[i] - ba.corners[i]));
  r.motion = bench::median(motion);
  r.turn = vpThetaUVector((bb.cMo * ba.cMo.inverse()).getRotationMatrix()).getTheta() * 180.0 / M_PI;
  // The board's area: the quadrilateral of its outer inner corners.
  const std::vector<cv::Point2f> quad{ba.corners[0], ba.corners[8], ba.corners[53], ba.corners[45]};
  KltTracker tracker(camera, ko);
  std::map<long, cv::Point2f> first;
  for (const FeatureObservation &f : tracker.track(a)) {
    const cv::Point2f p(static_cast<float>(f.u), static_cast<float>(f.v));
    if (cv::pointPolygonTest(quad, p, false) > 0)
      first[f.id] = p;
  }
  r.in_board = static_cast<int>(first.size());
  KltMotion m;
  m.cMp = bb.cMo * ba.cMo.inverse();
  m.sigma_rot = 2e-3; // the boards' poses from solvePnP: about 2 mrad and 2 mm
  m.sigma_trans = 2e-3;
  for (const FeatureObservation &f : tracker.track(b, &m)) {
    const auto it = first.find(f.id);
    if (it == first.end())
      continue;
    std::vector<cv::Point2f> t;
    cv::perspectiveTransform(std::vector<cv::Point2f>{it->second}, t, H);
    r.err.push_back(std::hypot(f.u - t[0].x, f.v - t[0].y));
    ++r.tracked;
  }
  r.stats = tracker.lastStats();
  return r;
}

/* The consecutive pairs of the franka photos: each pair's error table, then the pooled errors. */
void frankaScene(const std::string &dir, const KltOptions &ko)
{
  std::printf("\n## real photos, franka eye-in-hand (%s): consecutive pairs, KltTracker (guided auto), truth the "
              "board plane's homography from the chessboard corners; features inside the board only\n",
              dir.c_str());
  const CameraModel camera = loadCameraFile(dir + "/franka_camera.xml");
  std::vector<cv::Mat> images;
  std::vector<Board> boards;
  for (int i = 1; i <= 8; ++i) {
    images.push_back(readGrayImage(dir + "/franka_image-" + std::to_string(i) + ".png", camera));
    boards.push_back(detectBoard(images.back(), camera, kinematicPose(dir, i)));
  }
  std::printf("| pair | corners' motion (median px) | camera turn (deg) | board features | tracked | median error (px) | "
              "95th pct (px) | homography RMS on the corners (px) | whole image: guided, lost flow, fb, epipolar, "
              "ambiguous, appearance |\n|---|---|---|---|---|---|---|---|---|\n");
  std::vector<double> good;
  std::size_t tracked = 0, gross = 0;
  double least_turn = 180, most_turn = 0;
  for (std::size_t i = 0; i + 1 < images.size(); ++i) {
    if (!boards[i].found || !boards[i + 1].found) {
      std::printf("| %zu-%zu | board not found | | | | | | | |\n", i + 1, i + 2);
      continue;
    }
    const PairErrors r = measurePair(images[i], images[i + 1], boards[i], boards[i + 1], camera, ko);
    for (double e : r.err)
      (e > kGrossPx ? gross : tracked) += 1;
    for (double e : r.err)
      if (e <= kGrossPx)
        good.push_back(e);
    least_turn = std::min(least_turn, r.turn);
    most_turn = std::max(most_turn, r.turn);
    const KltStats &st = r.stats;
    std::printf("| %zu-%zu | %.0f | %.1f | %d | %d | %.3f | %.3f | %.3f | %d, %d, %d, %d, %d, %d |\n", i + 1, i + 2,
                r.motion, r.turn, r.in_board, r.tracked, bench::median(r.err), bench::quantile(r.err, 0.95), r.h_rms,
                st.guided, st.lost_flow, st.lost_fb, st.lost_epipolar, st.lost_ambiguous, st.lost_appearance);
  }
  std::printf("all pairs: %zu board features tracked within %.0f px of the truth (median %.3f px, 95th pct %.3f px), %zu "
              "gross (more than %.0f px off)\n",
              tracked, kGrossPx, bench::median(good), bench::quantile(good, 0.95), gross, kGrossPx);
  std::printf("real pairs: one step each, so no temporal correlation (bias, drift, AR(1)) can be measured on them; the "
              "truth is a homography fitted to the detected corners, no better than its RMS column; the camera turns "
              "%.0f to %.0f degrees between these photos, beyond what translational LK and the appearance check (NCC "
              ">= %.2f against the detection's patch) follow: too few tracks to model anything\n",
              least_turn, most_turn, ko.min_ncc);
}

/* The command line's values. */
struct Args {
  std::string scene = "all";
  int wall_frames = 60, castle_frames = 40, max_features = 300;
  std::string data = "/usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu";
  std::string franka = YAWDEPTH_SOURCE_DIR "/tests/data/franka-eye-in-hand";
};

} // namespace

int main(int argc, char **argv)
{
  Args a;
  bench::CommandLine cli("[--scene wall|castle|franka|all] [--wall-frames N] [--castle-frames N (2-40)] "
                         "[--max-features N] [--data DIR] [--franka DIR]");
  cli.option("--scene", a.scene).option("--wall-frames", a.wall_frames).option("--castle-frames", a.castle_frames);
  cli.option("--max-features", a.max_features).option("--data", a.data).option("--franka", a.franka);
  if (!cli.parse(argc, argv))
    return 2;
  const bool all = a.scene == "all";
  if ((!all && a.scene != "wall" && a.scene != "castle" && a.scene != "franka") || a.wall_frames < 2 ||
      a.castle_frames < 2 || a.castle_frames > 40 || a.max_features < 1) {
    std::fprintf(stderr, "bench_tracker_errors: --scene wall|castle|franka|all, --wall-frames >= 2, --castle-frames in "
                         "[2, 40], --max-features >= 1\n");
    return 2;
  }
  try {
    const auto missing = [](const std::string &path) { return !std::ifstream(path).good(); };
    const bool wall = all || a.scene == "wall", castle = all || a.scene == "castle", franka = all || a.scene == "franka";
    a.franka = std::filesystem::weakly_canonical(a.franka).string();
    if (castle && missing(a.data + "/CameraPose/Camera_001.txt"))
      throw Error(a.data + ": no Castle-simu here (Debian's visp-images-data, or --data DIR)");
    if (franka && missing(a.franka + "/franka_camera.xml"))
      throw Error(a.franka + ": no franka eye-in-hand photos here (--franka DIR)");
    cv::setNumThreads(1);
    KltOptions ko; // measure --features klt's defaults
    ko.max_features = a.max_features;
    ko.validate();
    std::printf("bench_tracker_errors: the KLT tracker's errors against the truth (measure --features klt's tracker); "
                "data: a textured wall (our render), visp-images-data Castle-simu (someone else's renderer), real "
                "photos, franka eye-in-hand\n");
    std::printf("Reproduce: build/benchmarks/bench_tracker_errors --scene %s --wall-frames %d --castle-frames %d "
                "--max-features %d --data %s --franka %s\n",
                a.scene.c_str(), a.wall_frames, a.castle_frames, a.max_features, a.data.c_str(), a.franka.c_str());
    if (wall)
      analyse(wallScene(a.wall_frames, ko));
    if (castle)
      analyse(castleScene(a.data, a.castle_frames, ko));
    if (franka)
      frankaScene(a.franka, ko);
    return 0;
  } catch (const Error &e) {
    std::fprintf(stderr, "bench_tracker_errors: %s\n", e.what());
    return 1;
  }
}
