#include <yawdepth/features/klt_tracker.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <set>
#include <string>
#include <yawdepth/error.h>

#include "epipolar_search.h"
#include "track_checks.h"

namespace yawdepth {

const char *toString(KltGuided g)
{
  switch (g) {
  case KltGuided::Off:
    return "off";
  case KltGuided::On:
    return "on";
  case KltGuided::Auto:
    break;
  }
  return "auto";
}

KltGuided kltGuidedFromString(const std::string &s)
{
  if (s == "off")
    return KltGuided::Off;
  if (s == "auto")
    return KltGuided::Auto;
  if (s == "on")
    return KltGuided::On;
  throw Error("klt: guided must be off, auto or on, not '" + s + "'");
}

void KltOptions::validate() const
{
  if (max_features < 1 || max_features > 100000)
    throw Error("klt: max_features must be in [1, 100000]");
  if (!(std::isfinite(min_distance) && min_distance >= 1))
    throw Error("klt: min_distance must be at least 1 px");
  if (!(std::isfinite(quality) && quality > 0 && quality < 1))
    throw Error("klt: quality must be in (0, 1)");
  if (block_size < 3 || block_size > 31)
    throw Error("klt: block_size must be in [3, 31]");
  if (window < 5 || window > 101 || window % 2 == 0)
    throw Error("klt: window must be odd and in [5, 101]");
  if (pyramid_levels < 0 || pyramid_levels > 8)
    throw Error("klt: pyramid_levels must be in [0, 8]");
  if (!(std::isfinite(forward_backward_px) && forward_backward_px > 0))
    throw Error("klt: forward_backward_px must be finite and positive");
  if (!(std::isfinite(redetect_fraction) && redetect_fraction >= 0 && redetect_fraction <= 1))
    throw Error("klt: redetect_fraction must be in [0, 1]");
  if (!(std::isfinite(border_px) && border_px >= 0))
    throw Error("klt: border_px must be finite and non-negative");
  if (!(std::isfinite(gate_sigmas) && gate_sigmas > 0))
    throw Error("klt: gate_sigmas must be finite and positive");
  if (!(std::isfinite(sigma_px) && sigma_px > 0))
    throw Error("klt: sigma_px must be finite and positive");
  if (!(std::isfinite(min_depth) && min_depth > 0))
    throw Error("klt: min_depth must be finite and positive");
  if (!(max_depth > min_depth)) // infinity allowed: the point at infinity
    throw Error("klt: max_depth must be greater than min_depth");
  if (!(std::isfinite(guided_min_ncc) && guided_min_ncc > -1 && guided_min_ncc < 1))
    throw Error("klt: guided_min_ncc must be in (-1, 1)");
  if (!(std::isfinite(ambiguity_margin) && ambiguity_margin >= 0 && ambiguity_margin < 2))
    throw Error("klt: ambiguity_margin must be in [0, 2)");
  if (guided_levels < 0 || guided_levels > 8)
    throw Error("klt: guided_levels must be in [0, 8]");
  if (!(std::isfinite(min_ncc) && min_ncc < 1))
    throw Error("klt: min_ncc must be finite and under 1 (0 or less: no appearance check)");
  if (!(std::isfinite(jump_sigmas) && jump_sigmas >= 0))
    throw Error("klt: jump_sigmas must be finite and non-negative (0: no jump check)");
}

KltTracker::KltTracker(const CameraModel &camera, const KltOptions &options) : camera_(camera), options_(options)
{
  options_.validate();
  if (camera_.width() == 0 || camera_.height() == 0)
    throw Error("klt: the camera needs an image size");
}

bool KltTracker::epipolarSegment(const Eigen::Vector2d &uv_prev, const vpHomogeneousMatrix &cMp, double z_near,
                                 double z_far, Eigen::Vector2d &near_px, Eigen::Vector2d &far_px) const
{
  Eigen::Vector2d mp;
  if (!camera_.undistort(uv_prev, mp) || !(z_near > 0) || !(z_far >= z_near))
    return false;
  const Eigen::Isometry3d M = toIsometry(cMp);
  const Eigen::Vector3d t = M.translation();
  const Eigen::Vector3d dir = M.linear() * Eigen::Vector3d(mp.x(), mp.y(), 1.0);
  constexpr double kFront = 1e-9;
  // The far end: the point at infinity (the bearing rotated) or the point at z_far.
  const Eigen::Vector3d pf = std::isinf(z_far) ? dir : Eigen::Vector3d(dir * z_far + t);
  if (pf.z() <= kFront)
    return false;
  double zn = z_near;
  if (t.z() + dir.z() * zn <= kFront) // the near end behind the camera: start where the ray comes in front
    zn = (kFront - t.z()) / dir.z() * 1.001; // dir.z() > 0 here: the far end is in front
  const Eigen::Vector3d pn = dir * zn + t;
  Eigen::Vector2d a(pn.x() / pn.z(), pn.y() / pn.z()), b(pf.x() / pf.z(), pf.y() / pf.z());
  // Cut in normalised coordinates (where the path is straight) to a box around the view, so that the
  // distortion model is never asked about points far outside the image.
  const double w = camera_.width(), h = camera_.height();
  double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
  for (const Eigen::Vector2d &c : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0), Eigen::Vector2d(0, h),
                                   Eigen::Vector2d(w, h), Eigen::Vector2d(w / 2, 0), Eigen::Vector2d(w / 2, h),
                                   Eigen::Vector2d(0, h / 2), Eigen::Vector2d(w, h / 2)}) {
    Eigen::Vector2d m;
    if (!camera_.undistort(c, m))
      continue;
    lo_x = std::min(lo_x, m.x());
    hi_x = std::max(hi_x, m.x());
    lo_y = std::min(lo_y, m.y());
    hi_y = std::max(hi_y, m.y());
  }
  const double mx = 0.1 * (hi_x - lo_x), my = 0.1 * (hi_y - lo_y);
  if (!(lo_x < hi_x) || !detail::clipSegment(a, b, lo_x - mx, lo_y - my, hi_x + mx, hi_y + my))
    return false;
  near_px = camera_.project(a);
  far_px = camera_.project(b);
  return near_px.allFinite() && far_px.allFinite();
}

void KltTracker::setDepthHint(long id, double depth, double sigma)
{
  if (!(std::isfinite(depth) && depth > 0 && std::isfinite(sigma) && sigma > 0)) {
    hints_.erase(id);
    return;
  }
  if (std::find(ids_.begin(), ids_.end(), id) != ids_.end())
    hints_[id] = {depth, sigma};
}

double KltTracker::bandHalfWidth(const KltMotion &motion) const
{
  const double f = std::max(camera_.kx(), camera_.ky());
  const double s = options_.sigma_px, r = f * motion.sigma_rot, t = f * motion.sigma_trans / options_.min_depth;
  return options_.gate_sigmas * std::sqrt(2 * s * s + r * r + t * t);
}

double KltTracker::epipolarDistance(const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv,
                                    const vpHomogeneousMatrix &cMp) const
{
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector2d mp, mc;
  if (!camera_.undistort(uv_prev, mp) || !camera_.undistort(uv, mc))
    return kNaN;
  const Eigen::Isometry3d M = toIsometry(cMp);
  const Eigen::Vector3d t = M.translation();
  const Eigen::Vector3d dir = M.linear() * Eigen::Vector3d(mp.x(), mp.y(), 1.0);
  // Depths Z in [Z_min, inf): P(Z) = dir Z + t, a segment in the image from the near end to the
  // point at infinity (dir). Keep the part in front of the camera.
  constexpr double kFront = 1e-9;
  double z_near = options_.min_depth;
  if (dir.z() <= kFront) // the bearing turned away from the camera: no far end in view
    return kNaN;
  if (t.z() + dir.z() * z_near <= kFront) // the near end behind the camera: start where it comes in front
    z_near = (kFront - t.z()) / dir.z() * 1.001;
  const Eigen::Vector3d pn = dir * z_near + t;
  const Eigen::Vector2d a(pn.x() / pn.z(), pn.y() / pn.z()), b(dir.x() / dir.z(), dir.y() / dir.z());
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0 ? std::clamp((mc - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  const Eigen::Vector2d d = mc - (a + s * ab);
  return std::hypot(d.x() * camera_.kx(), d.y() * camera_.ky());
}

namespace {

/*! \brief The part of the image a feature may be in: `border` px from the edges. */
struct ImageInterior {
  double lo, hi_u, hi_v;
  ImageInterior(const cv::Mat &image, double border)
      : lo(border), hi_u(image.cols - 1 - border), hi_v(image.rows - 1 - border) {}
  bool contains(const cv::Point2f &p) const { return p.x >= lo && p.y >= lo && p.x <= hi_u && p.y <= hi_v; }
};

/*! \brief Live features: pixels and their ids. */
struct LiveFeatures {
  std::vector<cv::Point2f> points;
  std::vector<long> ids;
};

/*!
  \brief The features at `points` (ids `ids`) of `previous` followed into `image`: plain LK's
  forward and backward pass (`next_in`, `back` and their status, KltTracker::ahead()'s) and, with a
  `motion`, the guided search; those lost (no flow, forward-backward error, border, outside the
  epipolar band when `motion` is given) are counted in `stats` and left out. The pyramids are the
  images' LK pyramids (KltTracker::ahead()).
*/
LiveFeatures followFeatures(const KltTracker &tracker, const KltOptions &options, const cv::Mat &previous,
                            const std::vector<cv::Mat> &previous_pyramid, const cv::Mat &image,
                            const std::vector<cv::Mat> &pyramid, const std::vector<cv::Point2f> &points,
                            const std::vector<long> &ids, const KltMotion *motion,
                            const std::map<long, std::pair<double, double>> &hints, const ImageInterior &interior,
                            const std::vector<cv::Point2f> &next_in, const std::vector<cv::Point2f> &back,
                            const std::vector<unsigned char> &status, const std::vector<unsigned char> &status_back,
                            KltStats &stats)
{
  std::vector<cv::Point2f> next = next_in;
  const double band = motion ? tracker.bandHalfWidth(*motion) : 0.0;
  const auto in_band = [&](std::size_t i, const cv::Point2f &p) {
    const double d = tracker.epipolarDistance(Eigen::Vector2d(points[i].x, points[i].y), Eigen::Vector2d(p.x, p.y),
                                              motion->cMp);
    return d <= band; // NaN: no depth in front of both cameras explains the match
  };
  const auto plain_lost = [&](std::size_t i) {
    return !status[i] || !status_back[i] || !std::isfinite(next[i].x) || !std::isfinite(next[i].y);
  };
  const auto plain_fb = [&](std::size_t i) {
    return std::hypot(back[i].x - points[i].x, back[i].y - points[i].y) > options.forward_backward_px;
  };
  std::vector<char> plain_ok(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    plain_ok[i] = !plain_lost(i) && !plain_fb(i) && interior.contains(next[i]) && (!motion || in_band(i, next[i]));
  // auto searches where plain LK failed a check or moved farther than it follows reliably; where that
  // is most of the features, the step is wide and plain LK's other tracks are suspect too (locks onto
  // a wrong corner within its reach): every feature is searched.
  const double reach = detail::lkReachPx(options);
  const auto moved = [&](std::size_t i) { return std::hypot(next[i].x - points[i].x, next[i].y - points[i].y); };
  std::size_t doubtful = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    doubtful += !plain_ok[i] || moved(i) > reach ? 1 : 0;
  const bool wide_step = 2 * doubtful > points.size();
  std::vector<char> search(points.size(), 0);
  if (motion && options.guided != KltGuided::Off)
    for (std::size_t i = 0; i < points.size(); ++i)
      search[i] = options.guided == KltGuided::On || wide_step || !plain_ok[i] || moved(i) > reach;
  const detail::GuidedSearch guided =
      motion ? detail::guidedSearch(tracker, options, previous, previous_pyramid, image, pyramid, points, ids, *motion,
                                    hints, interior.lo, interior.hi_u, interior.hi_v, search)
             : detail::GuidedSearch{std::vector<detail::GuidedOutcome>(points.size()), {}};
  LiveFeatures kept;
  for (std::size_t i = 0; i < points.size(); ++i) {
    using detail::GuidedOutcome;
    GuidedOutcome outcome = guided.outcome[i];
    // auto: where the search finds no one match (none, or two: repeated texture, an edge along the
    // line) for a track plain LK lost, it is lost for plain LK's reason, as without the search; a
    // plain track it searched (beyond LK's reach, or in a wide step) is cut for the search's reason.
    if (outcome != GuidedOutcome::Found && options.guided == KltGuided::Auto && !plain_ok[i])
      outcome = GuidedOutcome::NotSearched;
    const bool by_guided = outcome != GuidedOutcome::NotSearched;
    if (by_guided) {
      switch (outcome) {
      case GuidedOutcome::OffImage:
        ++stats.lost_border;
        continue;
      case GuidedOutcome::Ambiguous:
        ++stats.lost_ambiguous;
        continue;
      case GuidedOutcome::LostFb:
        ++stats.lost_fb;
        continue;
      case GuidedOutcome::Weak:
      case GuidedOutcome::LostFlow:
        ++stats.lost_flow;
        continue;
      case GuidedOutcome::NotSearched:
      case GuidedOutcome::Found:
        next[i] = guided.position[i];
        break;
      }
    } else if (plain_lost(i)) {
      ++stats.lost_flow;
      continue;
    } else if (plain_fb(i)) {
      ++stats.lost_fb;
      continue;
    }
    if (!interior.contains(next[i])) {
      ++stats.lost_border;
      continue;
    }
    if (motion && !in_band(i, next[i])) {
      ++stats.lost_epipolar;
      continue;
    }
    kept.points.push_back(next[i]);
    kept.ids.push_back(ids[i]);
    stats.guided += by_guided ? 1 : 0;
  }
  stats.tracked = static_cast<int>(kept.points.size());
  return kept;
}

/*!
  \brief Up to `wanted` new corners (Shi-Tomasi, then cornerSubPix) in the interior of `image`, at
  least min_distance from the `kept` features.
*/
std::vector<cv::Point2f> detectCorners(const cv::Mat &image, const KltOptions &options,
                                       const std::vector<cv::Point2f> &kept, int wanted)
{
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  const int b = static_cast<int>(std::ceil(options.border_px));
  if (image.cols > 2 * b && image.rows > 2 * b)
    mask(cv::Rect(b, b, image.cols - 2 * b, image.rows - 2 * b)).setTo(255);
  const int r = static_cast<int>(std::ceil(options.min_distance));
  for (const cv::Point2f &p : kept)
    cv::circle(mask, cv::Point(cvRound(p.x), cvRound(p.y)), r, cv::Scalar(0), cv::FILLED);
  std::vector<cv::Point2f> corners;
  if (wanted > 0)
    cv::goodFeaturesToTrack(image, corners, wanted, options.quality, options.min_distance, mask, options.block_size);
  if (!corners.empty()) {
    const cv::Size half(std::max(2, options.window / 4), std::max(2, options.window / 4));
    cv::cornerSubPix(image, corners, half, cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.01));
  }
  return corners;
}

} // namespace

void KltTracker::checkImage(const cv::Mat &image) const
{
  if (image.empty() || image.type() != CV_8UC1)
    throw Error("klt: the image must be 8-bit gray");
  if (image.cols != static_cast<int>(camera_.width()) || image.rows != static_cast<int>(camera_.height()))
    throw Error("klt: the image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                " but the camera is " + std::to_string(camera_.width()) + "x" + std::to_string(camera_.height()));
}

// The motion-free work of track(image): the pyramid, and plain LK of the live features forward and
// back. calcOpticalFlowPyrLK given the pyramids computes what it computes from the images (it builds
// the same pyramids itself), each built once instead of once per pass.
KltTracker::Ahead KltTracker::ahead(const cv::Mat &image) const
{
  Ahead a;
  a.image = image;
  const cv::Size win(options_.window, options_.window);
  // Its own copy (no reuse of a larger buffer around an ROI image): the borders LK would make itself,
  // and nothing the caller may overwrite kept as the next step's previous image.
  cv::buildOpticalFlowPyramid(image, a.pyramid, win, std::max(options_.pyramid_levels, options_.guided_levels), true,
                              cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
  if (points_.empty() || previous_.empty())
    return a;
  const cv::TermCriteria term(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  std::vector<float> err, err_back;
  cv::calcOpticalFlowPyrLK(previous_pyramid_, a.pyramid, points_, a.next, a.status, err, win, options_.pyramid_levels,
                           term);
  cv::calcOpticalFlowPyrLK(a.pyramid, previous_pyramid_, a.next, a.back, a.status_back, err_back, win,
                           options_.pyramid_levels, term);
  return a;
}

bool KltTracker::prepared(const cv::Mat &image) const
{
  return !ahead_.image.empty() && ahead_.image.data == image.data && ahead_.image.size == image.size &&
         ahead_.image.step == image.step && ahead_.image.type() == image.type();
}

namespace {
/* The pixels of `image` alone: a view into a larger buffer (an ROI) copied, so that no filter reads
   the pixels around it and nothing kept refers to the caller's memory. */
cv::Mat ownPixels(const cv::Mat &image) { return image.isSubmatrix() ? image.clone() : image; }
} // namespace

void KltTracker::prepare(const cv::Mat &image)
{
  checkImage(image);
  if (prepared(image))
    return;
  ahead_ = ahead(ownPixels(image));
  ahead_.image = image; // the caller's: what track() recognises
}

std::vector<FeatureObservation> KltTracker::track(const cv::Mat &image, const KltMotion *motion)
{
  checkImage(image);
  const cv::Mat own = ownPixels(image);
  Ahead work = prepared(image) ? std::move(ahead_) : ahead(own);
  ahead_ = Ahead();
  stats_ = KltStats();
  const ImageInterior interior(own, options_.border_px);

  LiveFeatures kept;
  if (!points_.empty() && !previous_.empty())
    kept = followFeatures(*this, options_, previous_, previous_pyramid_, own, work.pyramid, points_, ids_, motion,
                          hints_, interior, work.next, work.back, work.status, work.status_back, stats_);
  // Still one static point? Appearance and jumps (track_checks.h).
  appearance_cuts_.clear();
  {
    std::map<long, cv::Point2f> previous;
    for (std::size_t i = 0; i < ids_.size(); ++i)
      previous.emplace(ids_[i], points_[i]);
    track_checks::checkTracks(camera_, options_, own, motion, previous, kept.points, kept.ids, state_, next_id_,
                              stats_, appearance_cuts_);
    stats_.tracked = static_cast<int>(kept.points.size());
  }

  // New corners where the tracks thinned out, away from the live ones.
  const int alive = static_cast<int>(kept.points.size());
  if (alive < options_.redetect_fraction * options_.max_features || alive == 0) {
    const std::vector<cv::Point2f> corners = detectCorners(own, options_, kept.points, options_.max_features - alive);
    // Sub-pixel refinement can pull two detections onto one corner: keep the spacing.
    const double min_d2 = options_.min_distance * options_.min_distance;
    const auto crowded = [&](const cv::Point2f &c) {
      return std::any_of(kept.points.begin(), kept.points.end(), [&](const cv::Point2f &p) {
        const double du = p.x - c.x, dv = p.y - c.y;
        return du * du + dv * dv < min_d2;
      });
    };
    for (const cv::Point2f &c : corners) {
      if (!interior.contains(c) || !std::isfinite(c.x) || !std::isfinite(c.y) || crowded(c))
        continue;
      kept.points.push_back(c);
      kept.ids.push_back(next_id_);
      if (options_.min_ncc > 0) // the appearance check's reference
        state_[next_id_].reference = track_checks::patchAt(own, c, options_.window);
      ++next_id_;
      ++stats_.detected;
    }
  }
  points_ = std::move(kept.points);
  ids_ = std::move(kept.ids);
  for (auto h = hints_.begin(); h != hints_.end();) // a hint lives as long as its feature
    h = std::binary_search(ids_.begin(), ids_.end(), h->first) ? std::next(h) : hints_.erase(h);
  if (!state_.empty()) { // forget the features that ended
    std::vector<long> live = ids_;
    std::sort(live.begin(), live.end());
    for (auto it = state_.begin(); it != state_.end();)
      it = std::binary_search(live.begin(), live.end(), it->first) ? std::next(it) : state_.erase(it);
  }
  previous_ = own.data == image.data ? own.clone() : own; // own pixels, kept
  previous_pyramid_ = std::move(work.pyramid);
  std::vector<FeatureObservation> out;
  out.reserve(points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i)
    out.push_back(FeatureObservation{ids_[i], points_[i].x, points_[i].y});
  return out;
}

int grayLevelAt(const cv::Mat &image, double u, double v)
{
  if (image.type() != CV_8UC1 || !(u >= 0 && v >= 0 && u <= image.cols - 1 && v <= image.rows - 1))
    return -1;
  const int u0 = std::min(static_cast<int>(u), std::max(0, image.cols - 2));
  const int v0 = std::min(static_cast<int>(v), std::max(0, image.rows - 2));
  const int u1 = std::min(u0 + 1, image.cols - 1), v1 = std::min(v0 + 1, image.rows - 1);
  const double a = u - u0, b = v - v0;
  const double g = (1 - a) * (1 - b) * image.at<unsigned char>(v0, u0) + a * (1 - b) * image.at<unsigned char>(v0, u1) +
                   (1 - a) * b * image.at<unsigned char>(v1, u0) + a * b * image.at<unsigned char>(v1, u1);
  return static_cast<int>(std::lround(std::clamp(g, 0.0, 255.0)));
}

SequenceTracks trackSequence(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &samples,
                             const std::vector<std::string> &images, const NoiseModel &noise, const KltOptions &options,
                             bool gate, const std::function<void(std::size_t, std::size_t)> &progress)
{
  if (images.size() != samples.size())
    throw Error("klt: " + std::to_string(images.size()) + " images for " + std::to_string(samples.size()) +
                " motion rows");
  const FrameSource files = [&](std::size_t i) {
    if (images[i].empty())
      throw Error("frame " + std::to_string(samples[i].frame) + ": no image (KLT tracking needs every frame's image)");
    return readGrayImage(images[i], camera); // the camera has a size: KltTracker requires one
  };
  return trackSequence(camera, rig, samples, files, noise, options, gate, progress);
}

KltMotion kltMotion(const YawRig &rig, const MotionSample &prev, const MotionSample &cur, const NoiseModel &noise)
{
  KltMotion m;
  m.cMp = wMc(rig, cur).inverse() * wMc(rig, prev);
  const double dist = std::sqrt((cur.x - prev.x) * (cur.x - prev.x) + (cur.y - prev.y) * (cur.y - prev.y) +
                                (cur.z - prev.z) * (cur.z - prev.z));
  m.sigma_trans = incrementTranslationSigma(noise, dist);
  const double turn = cur.six_dof ? noise.sigma_rot : noise.sigma_heading;
  m.sigma_rot = std::sqrt(turn * turn + 2 * noise.sigma_yaw * noise.sigma_yaw);
  return m;
}

SequenceTracks trackSequence(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &samples,
                             const FrameSource &frames, const NoiseModel &noise, const KltOptions &options, bool gate,
                             const std::function<void(std::size_t, std::size_t)> &progress)
{
  KltTracker tracker(camera, options);
  const std::size_t n = samples.size();
  SequenceTracks out;
  std::vector<FrameDetection> detections;
  detections.reserve(n);
  std::set<long> dropped; // cut for their appearance: the whole track is not one point
  for (std::size_t i = 0; i < n; ++i) {
    const MotionSample &s = samples[i];
    const cv::Mat image = frames(i);
    if (image.cols != static_cast<int>(camera.width()) || image.rows != static_cast<int>(camera.height()))
      throw Error("frame " + std::to_string(s.frame) + ": the image is " + std::to_string(image.cols) + "x" +
                  std::to_string(image.rows) + " but the camera is " + std::to_string(camera.width()) + "x" +
                  std::to_string(camera.height()));
    FrameDetection d;
    d.frame = s.frame;
    if (i > 0 && gate) {
      const KltMotion m = kltMotion(rig, samples[i - 1], s, noise);
      d.features = tracker.track(image, &m);
    } else {
      d.features = tracker.track(image, nullptr);
    }
    for (const FeatureObservation &f : d.features)
      out.gray[{s.frame, f.id}] = grayLevelAt(image, f.u, f.v);
    const KltStats &st = tracker.lastStats();
    out.totals.tracked += st.tracked;
    out.totals.lost_flow += st.lost_flow;
    out.totals.lost_fb += st.lost_fb;
    out.totals.lost_border += st.lost_border;
    out.totals.lost_epipolar += st.lost_epipolar;
    out.totals.detected += st.detected;
    out.totals.guided += st.guided;
    out.totals.lost_ambiguous += st.lost_ambiguous;
    out.totals.lost_appearance += st.lost_appearance;
    out.totals.split_jump += st.split_jump;
    dropped.insert(tracker.lastAppearanceCuts().begin(), tracker.lastAppearanceCuts().end());
    d.found = !d.features.empty();
    detections.push_back(std::move(d));
    if (i + 1 == n)
      out.last_image = image;
    if (progress)
      progress(i + 1, n);
  }
  for (Track &t : PatternDetector::toTracks(detections))
    if (t.observations.size() >= 2 && dropped.count(t.id) == 0) // a feature seen once measures nothing
      out.tracks.push_back(std::move(t));
  return out;
}

} // namespace yawdepth
