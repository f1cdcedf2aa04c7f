/*!
  \file time_offset.cpp
  \brief The time offset by its profile likelihood (yawdepth/calibration/time_offset.h).
*/
#include <yawdepth/calibration/time_offset.h>

#include "text.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <yawdepth/error.h>
#include <yawdepth/io/recording.h>

namespace yawdepth {

namespace {

std::string ms(double seconds)
{
  std::ostringstream s;
  s.precision(4);
  s << seconds * 1e3 << " ms";
  return s.str();
}

/* The cost at each offset, each solved once. */
class Profile {
public:
  explicit Profile(const std::function<ProfileCost(double)> &cost) : cost_(cost) {}
  double operator()(double offset)
  {
    const auto it = cache_.find(offset);
    if (it != cache_.end())
      return it->second.sum_squares;
    ProfileCost c;
    c.sum_squares = std::numeric_limits<double>::infinity();
    try {
      c = cost_(offset);
      if (!std::isfinite(c.sum_squares))
        c.sum_squares = std::numeric_limits<double>::infinity();
    } catch (const Error &) {
      c.sum_squares = std::numeric_limits<double>::infinity();
    }
    ++evaluations;
    cache_[offset] = c;
    return c.sum_squares;
  }
  const ProfileCost &at(double offset) const { return cache_.at(offset); }
  int evaluations = 0;

private:
  std::function<ProfileCost(double)> cost_;
  std::map<double, ProfileCost> cache_;
};

/* Golden-section search of the minimum of f on [a, b] to `tolerance`; `fx` receives f there. */
double goldenMinimum(const std::function<double(double)> &f, double a, double b, double tolerance, double &fx)
{
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = f(x1), f2 = f(x2);
  while (b - a > tolerance) {
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = f(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = f(x2);
    }
  }
  fx = std::min(f1, f2);
  return f1 < f2 ? x1 : x2;
}

} // namespace

void TimeOffsetSearch::validate() const
{
  if (!std::isfinite(min) || !std::isfinite(max) || !(min < max))
    throw Error("time offset search: the range [" + ms(min) + ", " + ms(max) + "] is empty or not finite");
  if (!std::isfinite(step) || !std::isfinite(tolerance) || !(tolerance > 0) || !(step >= tolerance))
    throw Error("time offset search: step " + ms(step) + " and tolerance " + ms(tolerance) +
                " must be finite with 0 < tolerance <= step");
}

TimeOffsetEstimate estimateTimeOffset(const std::function<ProfileCost(double)> &cost, const TimeOffsetSearch &search)
{
  search.validate();
  Profile S(cost);
  // The grid.
  const int n = std::max(2, static_cast<int>(std::ceil((search.max - search.min) / search.step)));
  const double h = (search.max - search.min) / n;
  int best = -1;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i) {
    const double c = S(search.min + i * h);
    if (c < best_cost) {
      best_cost = c;
      best = i;
    }
  }
  if (best < 0)
    throw Error("time offset: the calibration failed at every offset from " + ms(search.min) + " to " + ms(search.max));
  if (best == 0 || best == n)
    throw Error("time offset: the best offset is at the end of the search range [" + ms(search.min) + ", " +
                ms(search.max) + "]: widen it");
  // Golden-section search in the grid cell pair around the best node.
  double fx = 0;
  const double x = goldenMinimum([&](double t) { return S(t); }, search.min + (best - 1) * h, search.min + (best + 1) * h,
                                 search.tolerance, fx);
  // The curvature from a parabola through the cost half a grid step either side (wide enough that
  // the resampled noise's wiggles do not make it).
  const double d = 0.5 * h;
  const double fm = S(x - d), fp = S(x + d);
  const double curvature = (fp - 2 * fx + fm) / (d * d);
  const ProfileCost &c = S.at(x);
  const double dof = c.residuals - c.parameters - 1;
  if (!std::isfinite(fm) || !std::isfinite(fp) || !(curvature > 0) || !(dof > 0))
    throw Error("time offset: the cost does not change with the offset (the motion must change speed: a pan sweeping "
                "back and forth, a robot accelerating)");
  const double variance = fx / dof;
  // Determined only when the cost rises clearly on both sides within the range: by more than
  // kMinRise residual variances (the offset's 5-sigma interval inside it) and by more than the cost
  // itself (it at least doubles). A motion that cannot tell the offset gives a flat profile whose
  // wiggles are the motion log's noise resampled at each offset (measured: +-20 % of the cost at a
  // constant yaw rate), and a minimum among them with a curvature that means nothing.
  constexpr double kMinRise = 25.0;
  double left = 0, right = 0;
  for (int i = 0; i <= n; ++i) {
    const double t = search.min + i * h, ci = S(t);
    if (t < x)
      left = std::max(left, ci - fx);
    else
      right = std::max(right, ci - fx);
  }
  const double rise = std::max(kMinRise * variance, fx);
  if (!(left > rise) || !(right > rise))
    throw Error("time offset: not determined by the images (the reprojection cost changes by only " +
                std::to_string(std::min(left, right) / fx) + " times its minimum over the range searched): the "
                "motion must change speed while the board is seen (a pan sweeping back and forth, an arm accelerating)");
  TimeOffsetEstimate e;
  e.offset = x;
  e.sigma = std::sqrt(2.0 * variance / curvature);
  e.sum_squares = fx;
  e.evaluations = S.evaluations;
  // A flat profile: the offset's 1-sigma is as wide as the range searched.
  if (!(e.sigma < 0.5 * (search.max - search.min)))
    throw Error("time offset: not determined by the images (1-sigma " + ms(e.sigma) + " over a range of " +
                ms(search.max - search.min) + "): the motion must change speed while the board is seen (a pan "
                "sweeping back and forth, an arm accelerating)");
  return e;
}

std::vector<std::size_t> imagesPosedOverRange(const MotionLog &motion, const std::vector<double> &image_times,
                                              const std::vector<bool> &usable, const TimeOffsetSearch &search,
                                              double max_pose_gap)
{
  search.validate();
  if (image_times.size() != usable.size())
    throw Error("time offset: " + std::to_string(image_times.size()) + " image times for " +
                std::to_string(usable.size()) + " detections");
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < image_times.size(); ++i) {
    if (!usable[i])
      continue;
    bool covered = true;
    for (double offset : {search.min, search.max}) {
      ImageList one;
      one.times = {image_times[i]};
      one.paths = {std::string()};
      TimeAlignmentOptions o;
      o.time_offset = offset;
      o.max_pose_gap = max_pose_gap;
      try {
        covered = covered && alignMotionToImages(motion, one, o, "motion", "image").matched == 1;
      } catch (const Error &) {
        covered = false;
      }
    }
    if (covered)
      index.push_back(i);
  }
  return index;
}

std::vector<MotionSample> imageSamplesAt(const MotionLog &motion, const std::vector<double> &image_times,
                                         const std::vector<std::size_t> &images, double offset, double max_pose_gap)
{
  ImageList list;
  for (std::size_t i : images) {
    list.times.push_back(image_times.at(i));
    list.paths.emplace_back();
  }
  TimeAlignmentOptions o;
  o.time_offset = offset;
  o.max_pose_gap = max_pose_gap;
  const TimeAlignment a = alignMotionToImages(motion, list, o, "motion", "images");
  if (a.matched != images.size())
    throw Error("time offset: an image lost its pose");
  std::vector<MotionSample> samples = a.log.samples;
  for (std::size_t k = 0; k < samples.size(); ++k)
    samples[k].frame = static_cast<long>(k);
  return samples;
}

TimedImagesOffset estimateTimeOffsetOverImages(const MotionLog &motion, const std::vector<double> &image_times,
                                               const std::vector<bool> &usable, const TimedImagesCost &cost,
                                               const TimeOffsetSearch &search, double max_pose_gap)
{
  TimedImagesOffset out;
  // The images with a pose whatever the offset in the range: the same views at every offset.
  out.images = imagesPosedOverRange(motion, image_times, usable, search, max_pose_gap);
  const std::vector<std::size_t> &images = out.images;
  if (images.size() < 3)
    throw Error("time offset: only " + std::to_string(images.size()) +
                " images with the board have a pose over the whole search range [" + ms(search.min) + ", " +
                ms(search.max) + "]");
  out.estimate = estimateTimeOffset(
      [&](double offset) { return cost(imageSamplesAt(motion, image_times, images, offset, max_pose_gap), images); },
      search);
  // The curvature's sigma takes every corner's residual as independent; the motion log's errors are
  // shared by the corners of an image and by neighbouring images (the readings interpolated), so
  // that sigma is too small when they dominate (measured on the yaw rig: 8 to 50 times,
  // bench_time_offset). A delete-a-group jackknife over kGroups blocks of consecutive images
  // measures the spread itself; the larger of the two is reported.
  constexpr std::size_t kGroups = 10;
  if (images.size() >= 2 * kGroups) {
    const double h = search.step;
    std::vector<double> estimates;
    for (std::size_t g = 0; g < kGroups; ++g) {
      const std::size_t from = g * images.size() / kGroups, to = (g + 1) * images.size() / kGroups;
      std::vector<std::size_t> kept_images, kept_positions;
      for (std::size_t k = 0; k < images.size(); ++k)
        if (k < from || k >= to) {
          kept_images.push_back(images[k]);
          kept_positions.push_back(k);
        }
      const auto cost_without = [&](double offset) {
        const std::vector<MotionSample> all = imageSamplesAt(motion, image_times, images, offset, max_pose_gap);
        std::vector<MotionSample> kept;
        kept.reserve(kept_positions.size());
        for (std::size_t k : kept_positions)
          kept.push_back(all[k]);
        try {
          return cost(kept, kept_images).sum_squares;
        } catch (const Error &) {
          return std::numeric_limits<double>::infinity();
        }
      };
      double f = 0;
      const double e = goldenMinimum(cost_without, out.estimate.offset - 2 * h, out.estimate.offset + 2 * h,
                                     search.tolerance, f);
      if (std::isfinite(f)) // without some images the calibration may not be solvable (the yaw span too small)
        estimates.push_back(e);
    }
    constexpr std::size_t kMinGroups = 5;
    if (estimates.size() < kMinGroups)
      throw Error("time offset: the calibration cannot be solved without any tenth of the images in " +
                  std::to_string(kGroups - estimates.size()) + " of " + std::to_string(kGroups) +
                  " cases: too few views to tell the offset's uncertainty (move wider and longer)");
    out.estimate.sigma = std::max(out.estimate.sigma, calibration_detail::jackknifeSigma(estimates));
  }
  out.samples = imageSamplesAt(motion, image_times, images, out.estimate.offset, max_pose_gap);
  return out;
}

TimedRigCalibration calibrateRigWithTimeOffset(const CameraModel &camera, const BoardLayout &board,
                                               const MotionLog &motion, const std::vector<double> &image_times,
                                               const std::vector<std::vector<FeatureObservation>> &features,
                                               const RigCalibrationOptions &options, const TimeOffsetSearch &search,
                                               double max_pose_gap)
{
  if (image_times.size() != features.size())
    throw Error("time offset: " + std::to_string(image_times.size()) + " image times for " +
                std::to_string(features.size()) + " detections");
  std::vector<bool> usable(features.size());
  for (std::size_t i = 0; i < features.size(); ++i)
    usable[i] = !features[i].empty();
  const auto viewsOf = [&](const std::vector<MotionSample> &samples, const std::vector<std::size_t> &images) {
    std::vector<RigView> views(samples.size());
    for (std::size_t k = 0; k < views.size(); ++k) {
      views[k].sample = samples[k];
      views[k].features = features[images[k]];
    }
    return views;
  };
  RigCalibrationOptions profile_options = options;
  profile_options.max_rms_px = std::numeric_limits<double>::max(); // a wrong offset fits badly: that is its cost
  profile_options.max_offset_sigma = std::numeric_limits<double>::max();
  profile_options.check_board_scale = false; // once, at the offset found
  const auto cost = [&](const std::vector<MotionSample> &samples, const std::vector<std::size_t> &images) {
    const RigCalibration r = calibrateRig(camera, board, viewsOf(samples, images), profile_options);
    ProfileCost c;
    c.sum_squares = r.rms_px * r.rms_px * r.points; // rms_px: per coordinate pair
    c.residuals = 2.0 * r.points;
    c.parameters = 6 + 2 + (options.estimate_axis ? 2 : 0) + (r.yaw_zero == YawZeroSource::Fixed ? 0 : 1); // the board pose, t0 (x, z), the axis, the yaw zero
    return c;
  };
  const TimedImagesOffset found = estimateTimeOffsetOverImages(motion, image_times, usable, cost, search, max_pose_gap);
  TimedRigCalibration out;
  out.time_offset = found.estimate;
  out.rig = calibrateRig(camera, board, viewsOf(found.samples, found.images), options);
  out.images_used = static_cast<int>(found.images.size());
  return out;
}

} // namespace yawdepth
