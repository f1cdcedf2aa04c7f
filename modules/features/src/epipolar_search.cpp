#include "epipolar_search.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace yawdepth {
namespace detail {

namespace {
/* The LK refinement may move the NCC match by this much (px) at most: farther, it found another
   structure than the one the NCC matched. */
constexpr double kMaxRefinementPx = 3.0;

} // namespace

bool clipSegment(Eigen::Vector2d &a, Eigen::Vector2d &b, double lo_u, double lo_v, double hi_u, double hi_v)
{
  // Liang-Barsky: the part of a + s (b - a), s in [0, 1], inside the rectangle.
  const Eigen::Vector2d d = b - a;
  double s0 = 0, s1 = 1;
  const double p[4] = {-d.x(), d.x(), -d.y(), d.y()};
  const double q[4] = {a.x() - lo_u, hi_u - a.x(), a.y() - lo_v, hi_v - a.y()};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0)
        return false;
      continue;
    }
    const double r = q[i] / p[i];
    if (p[i] < 0)
      s0 = std::max(s0, r);
    else
      s1 = std::min(s1, r);
  }
  if (s0 > s1)
    return false;
  const Eigen::Vector2d a0 = a;
  a = a0 + s0 * d;
  b = a0 + s1 * d;
  return true;
}

namespace {

/* Whether the NCC profile r[0..n) has one peak at `best` above `floor`: no other position as high
   outside the best's lobe (the positions next to it above `floor`), and a lobe no longer than `max_width`. */
bool onePeak(const float *r, int n, int best, double floor, int max_width)
{
  int lo = best, hi = best;
  while (lo > 0 && r[lo - 1] >= floor)
    --lo;
  while (hi + 1 < n && r[hi + 1] >= floor)
    ++hi;
  if (hi - lo > max_width) // an edge along the line: no one position
    return false;
  for (int k = 0; k < n; ++k)
    if ((k < lo || k > hi) && r[k] >= floor) // a separate peak as good: repeated texture
      return false;
  return true;
}

/* The NCC of `patch` (side x side, CV_32F) at each of n positions 1 px apart along `along` from
   `start` in `image` (bilinear, on the grid of `along` and `across`); score: 1 x n. */
void nccAlong(const cv::Mat &image, const cv::Mat &patch, const Eigen::Vector2d &start, const Eigen::Vector2d &along,
              const Eigen::Vector2d &across, int n, cv::Mat &score)
{
  const int side = patch.cols, h = side / 2;
  cv::Mat sx(side, n + side - 1, CV_32F), sy(side, n + side - 1, CV_32F), strip, strip_f;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < n + side - 1; ++j) {
      const Eigen::Vector2d o = start + (j - h) * along + (i - h) * across;
      sx.at<float>(i, j) = static_cast<float>(o.x());
      sy.at<float>(i, j) = static_cast<float>(o.y());
    }
  cv::remap(image, strip, sx, sy, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  strip.convertTo(strip_f, CV_32F);
  cv::matchTemplate(strip_f, patch, score, cv::TM_CCOEFF_NORMED);
}

} // namespace

SegmentPeak searchSegment(const cv::Mat &prev, const cv::Mat &next, const cv::Point2f &point,
                          const Eigen::Vector2d &near_px, const Eigen::Vector2d &far_px, double span_px,
                          const GuidedSettings &settings)
{
  SegmentPeak peak;
  const int h = settings.window / 2, side = 2 * h + 1;
  const double length = (far_px - near_px).norm();
  const int n = static_cast<int>(std::floor(length)) + 1; // candidates 1 px apart, from the near end
  // The strip's axes: along the segment and across it (the image's own axes for a point-like segment).
  const Eigen::Vector2d along = length > 1e-9 ? Eigen::Vector2d((far_px - near_px) / length) : Eigen::Vector2d(1, 0);
  const Eigen::Vector2d across(-along.y(), along.x());
  // The patch around the feature in the previous image and the strip along the segment in the new
  // one, both sampled on the same rotated grid (bilinear), so that matchTemplate compares like with like.
  cv::Mat tx(side, side, CV_32F), ty(side, side, CV_32F), patch, patch_f, score;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const Eigen::Vector2d o = (j - h) * along + (i - h) * across;
      tx.at<float>(i, j) = static_cast<float>(point.x + o.x());
      ty.at<float>(i, j) = static_cast<float>(point.y + o.y());
    }
  cv::remap(prev, patch, tx, ty, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  patch.convertTo(patch_f, CV_32F);
  nccAlong(next, patch_f, near_px, along, across, n, score);
  const float *r = score.ptr<float>(0);
  const int best = static_cast<int>(std::max_element(r, r + n) - r);
  peak.ncc = r[best];
  if (!(peak.ncc >= settings.min_ncc))
    return peak; // Weak (NaN too: a flat patch)
  const double floor_ncc = peak.ncc - settings.ambiguity_margin;
  bool unique = onePeak(r, n, best, floor_ncc, settings.window);
  // The patch along the same line in its own image, as far each way as the segment was long before
  // the image cut it (at most the image's diagonal): a texture that repeats along the line has copies
  // there too, even when the image border leaves only one of its copies on the segment in the new image.
  // Only the part of that line in the image (beyond it, the strip would be made up by the border; the
  // patches of its ends are, in part, as the feature's own patch can be).
  const double diagonal = std::hypot(prev.cols, prev.rows);
  const double m = std::ceil(std::min(std::max(span_px, length), diagonal));
  const Eigen::Vector2d p(point.x, point.y);
  Eigen::Vector2d lo = p - m * along, hi = p + m * along;
  if (unique && m >= 1 && clipSegment(lo, hi, 0, 0, prev.cols - 1.0, prev.rows - 1.0)) {
    const int before = static_cast<int>(std::floor((p - lo).norm())); // positions before the feature
    const int count = before + 1 + static_cast<int>(std::floor((hi - p).norm()));
    cv::Mat self;
    nccAlong(prev, patch_f, p - before * along, along, across, count, self);
    unique = onePeak(self.ptr<float>(0), count, before, floor_ncc, settings.window);
  }
  if (!unique) {
    peak.outcome = GuidedOutcome::Ambiguous;
    return peak;
  }
  double offset = 0; // sub-pixel: the parabola through the best and its neighbours
  if (best > 0 && best + 1 < n) {
    const double den = r[best - 1] - 2.0 * r[best] + r[best + 1];
    if (den < 0)
      offset = std::clamp(0.5 * (r[best - 1] - r[best + 1]) / den, -0.5, 0.5);
  }
  peak.s = best + offset;
  peak.outcome = GuidedOutcome::Found;
  return peak;
}

std::vector<std::pair<GuidedOutcome, cv::Point2f>> guidedMatches(const cv::Mat &prev, const cv::Mat &next,
                                                                 const std::vector<GuidedRequest> &requests,
                                                                 const GuidedSettings &settings,
                                                                 const std::vector<cv::Mat> &prev_pyramid,
                                                                 const std::vector<cv::Mat> &next_pyramid)
{
  std::vector<std::pair<GuidedOutcome, cv::Point2f>> out(requests.size());
  std::vector<cv::Point2f> from, guess;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const GuidedRequest &q = requests[i];
    const SegmentPeak p = searchSegment(prev, next, q.point, q.near_px, q.far_px, q.span_px, settings);
    out[i].first = p.outcome;
    if (p.outcome != GuidedOutcome::Found)
      continue;
    const double length = (q.far_px - q.near_px).norm();
    const Eigen::Vector2d at = length > 1e-9 ? Eigen::Vector2d(q.near_px + (q.far_px - q.near_px) * (p.s / length))
                                             : q.near_px;
    out[i].second = cv::Point2f(static_cast<float>(at.x()), static_cast<float>(at.y()));
    from.push_back(q.point);
    guess.push_back(out[i].second);
    index.push_back(i);
  }
  if (index.empty())
    return out;
  // LK from the NCC match (a few levels: the match is within a pixel or two), then back from there
  // to the feature (started at the feature: the prediction back).
  const cv::Size win(settings.window, settings.window);
  const cv::TermCriteria term(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  std::vector<cv::Point2f> fwd = guess, back = from;
  std::vector<unsigned char> st, st_back;
  std::vector<float> err, err_back;
  cv::calcOpticalFlowPyrLK(prev_pyramid, next_pyramid, from, fwd, st, err, win, settings.levels, term,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  cv::calcOpticalFlowPyrLK(next_pyramid, prev_pyramid, fwd, back, st_back, err_back, win, settings.levels, term,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  for (std::size_t k = 0; k < index.size(); ++k) {
    std::pair<GuidedOutcome, cv::Point2f> &o = out[index[k]];
    if (!st[k] || !st_back[k] || !std::isfinite(fwd[k].x) || !std::isfinite(fwd[k].y) ||
        std::hypot(fwd[k].x - guess[k].x, fwd[k].y - guess[k].y) > kMaxRefinementPx) {
      o.first = GuidedOutcome::LostFlow;
      continue;
    }
    if (std::hypot(back[k].x - from[k].x, back[k].y - from[k].y) > settings.forward_backward_px) {
      o.first = GuidedOutcome::LostFb;
      continue;
    }
    o.second = fwd[k];
  }
  return out;
}

double lkReachPx(const KltOptions &options)
{
  return 0.25 * options.window * static_cast<double>(1 << options.pyramid_levels);
}

GuidedSearch guidedSearch(const KltTracker &tracker, const KltOptions &options, const cv::Mat &previous,
                          const std::vector<cv::Mat> &previous_pyramid, const cv::Mat &image,
                          const std::vector<cv::Mat> &pyramid, const std::vector<cv::Point2f> &points,
                          const std::vector<long> &ids,
                          const KltMotion &motion, const std::map<long, std::pair<double, double>> &hints,
                          double lo, double hi_u, double hi_v, const std::vector<char> &search)
{
  GuidedSearch out;
  out.outcome.assign(points.size(), GuidedOutcome::NotSearched);
  out.position.resize(points.size());
  std::vector<GuidedRequest> requests;
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!search[i])
      continue;
    double z_near = options.min_depth, z_far = options.max_depth;
    const auto hint = hints.find(ids[i]);
    if (hint != hints.end()) { // depth +- 3 sigma, within [min_depth, max_depth]
      z_near = std::clamp(hint->second.first - 3 * hint->second.second, options.min_depth, options.max_depth);
      z_far = std::clamp(hint->second.first + 3 * hint->second.second, z_near, options.max_depth);
    }
    Eigen::Vector2d a, b;
    bool seen = tracker.epipolarSegment(Eigen::Vector2d(points[i].x, points[i].y), motion.cMp, z_near, z_far, a, b);
    const double span = seen ? (b - a).norm() : 0.0; // before the image cuts it: the self-check's reach
    seen = seen && clipSegment(a, b, lo, lo, hi_u, hi_v);
    if (!seen) {
      out.outcome[i] = GuidedOutcome::OffImage;
      continue;
    }
    requests.push_back({points[i], a, b, span});
    index.push_back(i);
  }
  GuidedSettings gs;
  gs.window = options.window;
  gs.min_ncc = options.guided_min_ncc;
  gs.ambiguity_margin = options.ambiguity_margin;
  gs.levels = options.guided_levels;
  gs.forward_backward_px = options.forward_backward_px;
  const auto found = guidedMatches(previous, image, requests, gs, previous_pyramid, pyramid);
  for (std::size_t k = 0; k < index.size(); ++k) {
    out.outcome[index[k]] = found[k].first;
    out.position[index[k]] = found[k].second;
  }
  return out;
}

} // namespace detail
} // namespace yawdepth
