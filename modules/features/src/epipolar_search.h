#pragma once
/*
  epipolar_search.h (private to the features module): KltTracker's guided search along a feature's
  epipolar segment (see klt_tracker.h, "Guided matching"): a rectified strip along the segment,
  scored by NCC against the feature's patch, the ambiguity check, then LK from the best position
  with the forward-backward check.
*/
#include <map>
#include <utility>
#include <vector>
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <yawdepth/features/klt_tracker.h>

namespace yawdepth {
namespace detail {

/*! \brief Cut the segment a-b to the rectangle [lo_u, hi_u] x [lo_v, hi_v]; false when nothing is left. */
bool clipSegment(Eigen::Vector2d &a, Eigen::Vector2d &b, double lo_u, double lo_v, double hi_u, double hi_v);

/*! \brief What the guided search did with one feature. */
enum class GuidedOutcome {
  NotSearched, //!< left to plain LK
  OffImage,  //!< no part of the segment is in the image
  Found,     //!< matched, refined and checked forward-backward
  Weak,      //!< no position on the segment correlates with the patch (best NCC under min_ncc)
  Ambiguous, //!< a second peak within the margin of the best, or a lobe longer than the window
  LostFlow,  //!< the LK refinement failed or moved more than a few pixels from the NCC match
  LostFb     //!< the forward-backward error of the refinement is above the threshold
};

/*! \brief One feature to search: its pixel in the previous image and its segment (already clipped to
    the image), and the segment's length (px) before that clipping: how far along the line the patch
    must have no copy in its own image (see searchSegment()). */
struct GuidedRequest {
  cv::Point2f point;
  Eigen::Vector2d near_px, far_px;
  double span_px = 0;
};

/*! \brief The NCC search's settings (from KltOptions). */
struct GuidedSettings {
  int window = 21;             //!< patch side (px, odd)
  double min_ncc = 0.7;        //!< weakest accepted best NCC
  double ambiguity_margin = 0.1;
  int levels = 1;              //!< pyramid levels of the LK refinement
  double forward_backward_px = 0.5;
};

/*! \brief The NCC profile's best position along a segment (before refinement). */
struct SegmentPeak {
  GuidedOutcome outcome = GuidedOutcome::Weak; //!< Found, Weak or Ambiguous
  double s = 0;                                //!< distance from the near end (px)
  double ncc = 0;                              //!< the best NCC
};

/*! \brief The NCC of the patch of `prev` around `point` at each pixel along near-far in `next`, and
    its best peak with the ambiguity check: no second peak within the margin in `next`'s profile, nor
    in `prev`'s own profile along the same line within `span_px` of the feature (a repeated texture
    whose other copies the image border hides in `next`). */
SegmentPeak searchSegment(const cv::Mat &prev, const cv::Mat &next, const cv::Point2f &point,
                          const Eigen::Vector2d &near_px, const Eigen::Vector2d &far_px, double span_px,
                          const GuidedSettings &settings);

/*! \brief Every request searched, then refined by LK (forward and backward) in two batched calls; the
    outcome of each and its refined pixel (meaningful when Found). The pyramids are the images' LK
    pyramids (cv::buildOpticalFlowPyramid with derivatives, window `settings.window`, at least
    `settings.levels` levels). */
std::vector<std::pair<GuidedOutcome, cv::Point2f>> guidedMatches(const cv::Mat &prev, const cv::Mat &next,
                                                                 const std::vector<GuidedRequest> &requests,
                                                                 const GuidedSettings &settings,
                                                                 const std::vector<cv::Mat> &prev_pyramid,
                                                                 const std::vector<cv::Mat> &next_pyramid);

/*! \brief The displacement (px) pyramidal LK follows reliably: a quarter of window x 2^levels (42 px by
    default). Beyond it plain LK loses its way (bench_wide_baseline); below it plain LK is as good as
    the guided search and cheaper. */
double lkReachPx(const KltOptions &options);

/*! \brief The guided search's results, one per feature. */
struct GuidedSearch {
  std::vector<GuidedOutcome> outcome; //!< NotSearched for a feature left to plain LK
  std::vector<cv::Point2f> position;  //!< the refined pixel where Found
};

/*!
  \brief The guided search (klt_tracker.h, "Guided matching") for the features `search` marks: each
  one's segment between min_depth and max_depth (or its depth hint +- 3 sigma, `hints` by id),
  cut to the image's interior [lo, hi_u] x [lo, hi_v], searched and refined (guidedMatches()).
*/
GuidedSearch guidedSearch(const KltTracker &tracker, const KltOptions &options, const cv::Mat &previous,
                          const std::vector<cv::Mat> &previous_pyramid, const cv::Mat &image,
                          const std::vector<cv::Mat> &pyramid, const std::vector<cv::Point2f> &points,
                          const std::vector<long> &ids,
                          const KltMotion &motion, const std::map<long, std::pair<double, double>> &hints,
                          double lo, double hi_u, double hi_v, const std::vector<char> &search);

} // namespace detail
} // namespace yawdepth
