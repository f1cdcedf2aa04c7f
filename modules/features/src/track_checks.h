#pragma once
/*!
  \file track_checks.h
  \brief KltTracker's checks that a track is still one static point of the scene, after the
  Lucas-Kanade step and the epipolar gate (private to the features module).

  - **Appearance** (KltOptions::min_ncc). A corner on a surface keeps its look from frame to frame
    (up to gain, offset and slow perspective change, to which a zero-mean NCC is blind or nearly
    so). A corner on an occlusion boundary or a T-junction (two surfaces at different depths) does
    not: its two sides move with different parallax, so the texture on one side slides under the
    other. Each feature's `window` x `window` patch at detection is its reference; after each
    step, the patch at the new (sub-pixel) position is compared with it by zero-mean NCC, and a
    feature below `min_ncc` is cut. Its earlier observations slid too (the drop was gradual), so
    the whole track is reported (KltTracker::lastAppearanceCuts()) and trackSequence() drops it.
  - **Jumps** (KltOptions::jump_sigmas, with a motion). A step to a repeated texture or to the
    other side of a junction can stay inside the epipolar band (the band spans every depth from
    `min_depth` to infinity) yet contradict the feature's own history. With the previous camera's
    pose cMp = [R | t] and the previous normalised bearing b, the point at inverse depth rho
    projects at pi(R b + rho t); linearised about the feature's inverse depth so far rho_0 (its
    steps' weighted mean), a step's position gives
    \f[ \rho = \rho_0 + \frac{J^\top (u - \pi(R b + \rho_0 t))}{J^\top J}, \qquad
        \sigma_\rho = \frac{\sqrt{2\sigma_{px}^2 + (f\sigma_\theta)^2 + (f\sigma_t\rho_0)^2}}{|J|} \f]
    (J the image's derivative in pixels with respect to rho). A step with
    \f$ |\rho - \bar\rho| > k \sqrt{\sigma_\rho^2 + 1/\sum w} \f$ (k = `jump_sigmas`, w the earlier
    steps' 1/sigma^2) is a jump: the feature is split, the new position starting a new feature (new
    id, new reference), rather than averaged into one depth. A motion without translation across
    the bearing (|J| under 1e-3 px per unit of inverse depth) says nothing about depth: no test.
*/
#include <limits>
#include <map>
#include <vector>
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/klt_tracker.h>

namespace yawdepth {
namespace track_checks {

/*! \brief The `size` x `size` patch of an 8-bit gray image centred at `p` (sub-pixel, bilinear), as
    32-bit float. */
cv::Mat patchAt(const cv::Mat &image, const cv::Point2f &p, int size);

/*! \brief Zero-mean normalised cross-correlation of two patches of the same size (32-bit float);
    NaN when either is flat (standard deviation under 0.5 gray level) or the sizes differ. */
double zeroMeanNcc(const cv::Mat &a, const cv::Mat &b);

/*! \brief One step's inverse depth along its epipolar line (see the file). */
struct EpipolarStep {
  bool valid = false;                                    //!< false: no depth information (no translation across the bearing, or the point cannot be undistorted)
  double rho = std::numeric_limits<double>::quiet_NaN();   //!< inverse depth in the previous camera (1/m)
  double sigma = std::numeric_limits<double>::quiet_NaN(); //!< its 1-sigma (1/m)
};

/*!
  \brief The inverse depth a step from `uv_prev` to `uv` (observed pixels) says, linearised about
  `rho0` (see the file).
  \param camera The camera. \param uv_prev, uv The feature in the previous and the current image.
  \param motion The motion since the previous image. \param sigma_px Tracker noise per point (px).
  \param rho0 The feature's inverse depth so far (0: none known).
*/
EpipolarStep epipolarStep(const CameraModel &camera, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv,
                          const KltMotion &motion, double sigma_px, double rho0);

/*! \brief Whether `step` contradicts the feature's earlier steps in `state` by more than `k` sigmas
    (false when either has no information). */
bool isJump(const KltFeatureState &state, const EpipolarStep &step, double k);

/*! \brief Add a step to the feature's inverse-depth history. */
void addStep(KltFeatureState &state, const EpipolarStep &step);

/*!
  \brief The checks on the features that followed into `image` (see the file): features cut for
  their appearance are removed from `points` / `ids` (counted in stats.lost_appearance, their ids in
  `cut`); those that jumped get a new id from `next_id` (stats.split_jump) and a fresh state.
  \param camera The camera. \param options The tracker's options. \param image The new image.
  \param motion The motion since the previous image (nullptr: no jump check).
  \param previous Each live feature's pixel in the previous image, by id.
  \param points, ids The features followed into `image`; changed in place.
  \param state Per-feature state, by id; updated (new references for split features).
  \param next_id The next unused id. \param stats Counters. \param cut Receives the ids cut.
*/
void checkTracks(const CameraModel &camera, const KltOptions &options, const cv::Mat &image, const KltMotion *motion,
                 const std::map<long, cv::Point2f> &previous, std::vector<cv::Point2f> &points, std::vector<long> &ids,
                 std::map<long, KltFeatureState> &state, long &next_id, KltStats &stats, std::vector<long> &cut);

} // namespace track_checks
} // namespace yawdepth
