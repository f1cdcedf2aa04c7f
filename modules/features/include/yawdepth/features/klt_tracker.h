#pragma once
/*!
  \file klt_tracker.h
  \brief Natural-feature tracks for any textured scene: corners tracked frame to frame by pyramidal
  Lucas-Kanade (OpenCV's calcOpticalFlowPyrLK, as ViSP's vpKltOpencv), cut when the known motion
  says they cannot be right.

  Each frame: every live feature is tracked from the previous image into the new one, then back
  (forward-backward check: a track whose backward track misses its start by more than
  `forward_backward_px` is cut); a track that leaves the image (minus `border_px`) ends; a track
  outside its **epipolar band** is cut. Where tracks have thinned out (fewer than
  `redetect_fraction` x `max_features` live), new corners (Shi-Tomasi, goodFeaturesToTrack) are
  detected at least `min_distance` px from every live feature and get new ids; ids are never
  reused, so a feature that is lost and found again is a new feature.

  The epipolar band. With the camera's motion from the previous frame known (cMp: the previous
  camera's pose in the current camera's frame), a point seen along the previous bearing
  \f$\mathbf b = (x_p, y_p, 1)\f$ at any depth \f$Z \ge Z_{\min}\f$ projects in the current image
  onto the segment between the image of \f$ {}^cR_p\,\mathbf b \f$ (infinitely far) and that of
  \f$ {}^cR_p\,\mathbf b\,Z_{\min} + {}^ct_p \f$ (as near as `min_depth`): the epipolar line, cut to
  the depths a real point can have. The track's new position must lie within
  \f[ w = k\,\sqrt{2\sigma_{px}^2 + (f\,\sigma_\theta)^2 + (f\,\sigma_t / Z_{\min})^2} \f]
  pixels of that segment (k = `gate_sigmas`; \f$\sigma_\theta, \sigma_t\f$ the rotation and
  translation uncertainty of the increment, f the focal length). A track that drifts along an edge
  or jumps to a repeated texture leaves this band and is cut rather than averaged into a depth.
  With a camera that does not translate the segment shrinks to a point: the gate is then the
  rotation's prediction.

  Guided matching (issue 35). Pyramidal LK follows a displacement of roughly half its window times
  \f$2^{levels}\f$ and no more; a wide step (disparities of 50-150 px) loses most tracks. With the
  motion known, the feature must be on its epipolar segment between the depths `min_depth` and
  `max_depth` (infinity by default: the rotation's prediction), or within depth +- 3 sigma of the
  feature's own depth estimate when one is given (setDepthHint()). The guided search samples that
  segment every pixel (a rectified strip along it), scores each position by the zero-mean normalised
  cross-correlation (NCC) of a `window` x `window` patch around the feature in the previous image,
  takes the best (sub-pixel by a parabola), refuses the match when it is weak (NCC under
  `guided_min_ncc`) or ambiguous (a second, separate peak within `ambiguity_margin` of the best: repeated
  texture; the best peak's lobe longer than the window: an edge along the line; or such a copy of
  the patch along the same line in its own image, as far as the segment reaches before the image
  cuts it: a repeated texture whose other copies the border hides), then refines it by LK started
  at that position (`guided_levels` pyramid levels) with the forward-backward check (backward LK
  started at the feature) and the epipolar band as for any track. `guided`:
  - `off`: never (plain pyramidal LK only);
  - `on`: for every feature; its refusals are final (`lost_ambiguous`, `lost_flow`, `lost_fb`);
  - `auto` (default): for a feature whose plain LK track failed a check or moved farther than LK's
    reach, \f$ 0.25 \cdot window \cdot 2^{levels}\f$ px (42 px by default); and for every feature of a
    frame where that is more than half of them (a wide step: plain LK's other tracks are suspect,
    locks onto a wrong corner or a copy of a repeated texture within its reach). Where the search
    finds one match, it wins; where it finds none or two, a track plain LK lost stays lost (for plain
    LK's reason) and a plain track it searched is cut (for the search's). A plain track that passed
    every check within LK's reach in a frame plain LK mostly follows is kept unsearched: the search
    costs next to nothing on such a sequence (Castle-simu: 15 searched steps in 40 frames), but such
    a frame's lock onto a wrong corner stays (Castle-simu frames k, k + 2: 1.6 % of the tracks more
    than 3 px off, as without the search; 0.4 % with `on`). Searching every plain track whose
    segment is long instead (min_depth = 0.1 m makes most long): Castle-simu's tracking 3.5x slower.
  Its cost: two NCC strips per searched feature (the segment in the new image, the line in the
  previous one): about 0.6 ms per feature whose segment crosses a 640x480 image, one core
  (bench_wide_baseline prints the time per pair).
  Two more checks that a track is still one static point (track_checks.h in the module's sources):
  - **appearance** (`min_ncc`): each feature's patch (the LK window) after the step against its patch
    at detection, by zero-mean NCC; a corner on an occlusion edge or a T-junction changes as its two
    sides move with different parallax, even when it stays inside the band. Below `min_ncc` the
    feature is cut and trackSequence() drops its whole track (lastAppearanceCuts()).
  - **jumps** (`jump_sigmas`, with a motion): a step whose position along the epipolar line says an
    inverse depth `jump_sigmas` sigmas from the one the feature's earlier steps say (a jump to a
    repeated texture, to the other side of a junction) splits the feature: the track so far ends,
    and the new position goes on as a new feature (new id).
*/
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>
#include <opencv2/core.hpp>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief When KltTracker searches the epipolar segment (see the file). */
enum class KltGuided {
  Off,  //!< plain pyramidal LK only
  Auto, //!< the guided search for long segments and for features plain LK lost
  On    //!< the guided search for every feature (with a motion)
};
/*! \brief "off", "auto", "on". */
const char *toString(KltGuided g);
/*! \brief From "off", "auto", "on"; throws yawdepth::Error otherwise. */
KltGuided kltGuidedFromString(const std::string &s);

/*! \brief Options of KltTracker. */
struct KltOptions {
  int max_features = 300;            //!< most features alive at once
  double min_distance = 10;          //!< px between features (detection)
  double quality = 0.01;             //!< Shi-Tomasi quality level (fraction of the best corner)
  int block_size = 7;                //!< corner detection block (px)
  int window = 21;                   //!< Lucas-Kanade window (px, odd, >= 5)
  int pyramid_levels = 3;            //!< pyramid levels above the image (0: none)
  double forward_backward_px = 0.5;  //!< largest forward-backward error of a kept track (px)
  double redetect_fraction = 0.8;    //!< detect new corners when fewer than this x max_features are alive
  double border_px = 8;              //!< a feature closer to the image border ends
  double gate_sigmas = 4;            //!< k: half-width of the epipolar band in sigmas
  double sigma_px = 0.5;             //!< tracker noise per point (px)
  double min_depth = 0.1;            //!< Z_min: the nearest a tracked point can be (m)
  /*! Z_max: the farthest a tracked point can be (m, > min_depth); infinity (default): the far end of the
      guided search is the rotation's prediction. Used by the guided search only; the band keeps
      [min_depth, infinity). */
  double max_depth = std::numeric_limits<double>::infinity();
  KltGuided guided = KltGuided::Auto; //!< when to search the epipolar segment (see the file)
  double guided_min_ncc = 0.7;        //!< guided: the best NCC of an accepted match
  double ambiguity_margin = 0.1;      //!< guided: refuse when a separate peak is within this NCC of the best
  int guided_levels = 1;              //!< guided: pyramid levels of the LK refinement from the NCC match
  /*! Appearance check (track_checks.h): a feature whose `window` x `window` patch, after the
      Lucas-Kanade alignment, has a zero-mean normalised cross-correlation with its patch at
      detection below this is cut, and trackSequence() drops its whole track (a corner on an
      occlusion boundary or a T-junction changes as its two sides move with different parallax, and
      slid in its earlier frames too). 0 (or less): no appearance check. */
  double min_ncc = 0.95;
  /*! Jump check (track_checks.h, with a motion): a step whose position along the epipolar line is
      further than `jump_sigmas` sigmas from what the feature's own earlier steps say (its inverse
      depth) splits the feature: the track so far ends, the new position starts a new feature (new
      id). 0: no jump check. */
  double jump_sigmas = 4.0;
  /*! \brief Throws yawdepth::Error for invalid options. */
  void validate() const;
};

/*! \brief The camera's motion since the previous frame, for the epipolar gate. */
struct KltMotion {
  vpHomogeneousMatrix cMp;  //!< the previous camera's pose in the current camera's frame
  double sigma_rot = 0;     //!< 1-sigma of its rotation (rad)
  double sigma_trans = 0;   //!< 1-sigma of its translation (m, per axis)
};

/*!
  \brief The motion trackSequence() gates the step from row `prev` to row `cur` with: cMp the previous
  camera's pose in the current camera's frame (wMc of each row through the rig), its translation
  sigma incrementTranslationSigma() of the step's length, its rotation sigma the heading's
  (sigma_heading, planar rows) or sigma_rot (6-DoF rows) with two yaw readings' noise added in variance.
*/
KltMotion kltMotion(const YawRig &rig, const MotionSample &prev, const MotionSample &cur, const NoiseModel &noise);

/*! \brief What one KltTracker::track() call did. */
struct KltStats {
  int tracked = 0;          //!< tracks continued into this frame
  int lost_flow = 0;        //!< ended: Lucas-Kanade found no match
  int lost_fb = 0;          //!< cut: forward-backward error above the threshold
  int lost_border = 0;      //!< ended: left the image (minus the border)
  int lost_epipolar = 0;    //!< cut: outside the epipolar band
  int detected = 0;         //!< new features
  int guided = 0;           //!< of `tracked`: continued by the guided search (epipolar segment + NCC + LK)
  int lost_ambiguous = 0;   //!< cut: the guided search found two matches (repeated texture) or an edge
  int lost_appearance = 0;  //!< cut: its patch no longer matches its patch at detection (min_ncc); whole track dropped
  int split_jump = 0;       //!< split: a step inconsistent with its own earlier steps (jump_sigmas); new id
};

/*! \brief Per-feature state of the track checks (appearance, jumps; see track_checks.h in the
    module's sources). Internal to KltTracker. */
struct KltFeatureState {
  cv::Mat reference;        //!< the feature's patch at detection (32-bit float, `window` x `window`)
  double rho_weight = 0;    //!< sum of 1 / sigma^2 of its steps' inverse depths (0: no step yet)
  double rho_weighted = 0;  //!< sum of rho / sigma^2 of its steps' inverse depths
};

/*!
  \brief Pyramidal Lucas-Kanade tracks with stable ids, forward-backward check, re-detection and the
  epipolar gate (see the file).
*/
class KltTracker {
public:
  /*! \param camera The camera (its image size is required; images must have it).
      \param options Tracking options. */
  explicit KltTracker(const CameraModel &camera, const KltOptions &options = KltOptions());

  /*!
    \brief Track the live features into `image` and detect new ones where tracks thinned out.
    \param image The next frame, 8-bit gray, the camera's size (else yawdepth::Error); a view into a
    larger buffer (an ROI) is tracked as its own pixels (copied: the pixels around it never count).
    \param motion The camera's motion since the previous image, for the epipolar gate; nullptr: no gate.
    \return The features in this image: id and observed (distorted) pixel.
  */
  std::vector<FeatureObservation> track(const cv::Mat &image, const KltMotion *motion = nullptr);
  /*!
    \brief The part of track() that needs no motion, done ahead of it: `image`'s LK pyramid and plain
    Lucas-Kanade of the live features into it, forward and backward. For a caller whose image waits
    for its motion (OnlineMeasurer): the next track() call with this image (the same cv::Mat, or one
    sharing its data, unchanged meanwhile) takes this work and returns exactly what it returns
    without it; a track() call with another image discards it. The same checks of `image` as track().
  */
  void prepare(const cv::Mat &image);
  /*! \brief Whether prepare() was called for `image` (its data) since the last track(). */
  bool prepared(const cv::Mat &image) const;
  /*! \brief What the last track() call did. */
  const KltStats &lastStats() const { return stats_; }
  /*! \brief The features the last track() call cut for their appearance (KltOptions::min_ncc): their
      whole tracks are not one point (trackSequence() drops them). */
  const std::vector<long> &lastAppearanceCuts() const { return appearance_cuts_; }
  /*!
    \brief Distance (px) of `uv` from the epipolar segment of `uv_prev` (see the file); NaN when the
    segment is not defined (a point that would be behind the camera at every depth).
    \param uv_prev The feature in the previous image (observed pixel). \param uv In the current image.
    \param cMp The previous camera's pose in the current camera's frame.
  */
  double epipolarDistance(const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv, const vpHomogeneousMatrix &cMp) const;
  /*! \brief Half-width of the epipolar band (px) for a motion's uncertainty (see the file). */
  double bandHalfWidth(const KltMotion &motion) const;
  /*!
    \brief The epipolar segment of `uv_prev` in the current image: the images (observed pixels) of the
    previous bearing at depth `z_near` and at depth `z_far` (infinity: the rotation's prediction),
    depths along the previous camera's Z. The near end is moved to where the ray comes in front of the
    current camera when it would be behind it. False when no part of the segment is in front.
  */
  bool epipolarSegment(const Eigen::Vector2d &uv_prev, const vpHomogeneousMatrix &cMp, double z_near, double z_far,
                       Eigen::Vector2d &near_px, Eigen::Vector2d &far_px) const;
  /*!
    \brief The depth of feature `id` in the camera of its last image (m), to narrow its guided search to
    depth +- 3 sigma (within [min_depth, max_depth]). Optional; kept while the feature lives, replaced
    by the next call; `sigma` <= 0 or a non-finite depth removes it. Ignored for an id not alive.
  */
  void setDepthHint(long id, double depth, double sigma);

private:
  // prepare()'s work for one image, taken by the next track() call with that image.
  struct Ahead {
    cv::Mat image;                                  // its header: holds the data (and so its address)
    std::vector<cv::Mat> pyramid;                   // the LK pyramid, with derivatives
    std::vector<cv::Point2f> next, back;            // plain LK of points_: forward, and back from next
    std::vector<unsigned char> status, status_back; // their LK status
  };
  void checkImage(const cv::Mat &image) const;
  Ahead ahead(const cv::Mat &image) const;

  CameraModel camera_;
  KltOptions options_;
  cv::Mat previous_;
  std::vector<cv::Mat> previous_pyramid_; // previous_'s LK pyramid (built once, used by both passes)
  Ahead ahead_;                           // prepare()'s, until the next track()
  std::vector<cv::Point2f> points_;
  std::vector<long> ids_;
  long next_id_ = 0;
  KltStats stats_;
  std::map<long, std::pair<double, double>> hints_; // id -> (depth, sigma)
  std::map<long, KltFeatureState> state_; // per live feature, for the track checks
  std::vector<long> appearance_cuts_;
};

/*! \brief Gray level (0-255) at a sub-pixel position of an 8-bit gray image, bilinear; -1 outside
    the image or for an image of another type. */
int grayLevelAt(const cv::Mat &image, double u, double v);

/*! \brief What trackSequence() found. */
struct SequenceTracks {
  std::vector<Track> tracks;                   //!< every feature seen in 2 frames or more, by id
  KltStats totals;                             //!< the per-frame KltStats summed
  std::map<std::pair<long, long>, int> gray;   //!< gray level (0-255) at each feature, keyed (frame, id)
  cv::Mat last_image;                          //!< the last image tracked (8-bit gray)
};

/*!
  \brief The images of a sequence, one per motion-log row: called with the row's index (0, 1, ... in
  order, each once), it returns that row's image, 8-bit gray, or throws yawdepth::Error (a missing or
  unreadable image, a video that ended). See VideoFrames (video_frames.h) for a video or camera.
*/
using FrameSource = std::function<cv::Mat(std::size_t row)>;

/*!
  \brief KLT tracks through a sequence of images with known motion: KltTracker on each image in turn,
  each step gated by the motion's increment, its uncertainty from `noise` (the increment's
  translation, incrementTranslationSigma(); its rotation, sigma_heading or sigma_rot with two yaw
  readings), unless `gate` is false. A feature the tracker cut for its appearance
  (KltOptions::min_ncc, KltTracker::lastAppearanceCuts()) is left out whole: its earlier frames slid
  too. A feature split at a jump is two tracks (two ids).
  \param camera The camera (with its image size). \param rig The rig. \param samples The motion, one row per image.
  \param images The image files (8-bit gray, or converted), one per row.
  \param noise The motion's noise model. \param options Tracking options. \param gate Use the epipolar gate.
  \param progress Called after each image with (images done, total), when set.
  Throws yawdepth::Error for a missing or unreadable image, or one of another size than the camera's.
*/
SequenceTracks trackSequence(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &samples,
                             const std::vector<std::string> &images, const NoiseModel &noise,
                             const KltOptions &options = KltOptions(), bool gate = true,
                             const std::function<void(std::size_t, std::size_t)> &progress = {});

/*!
  \brief The same, each row's image from `frames` (FrameSource) instead of a file; an image of another
  size than the camera's is an error that names the row's frame.
*/
SequenceTracks trackSequence(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &samples,
                             const FrameSource &frames, const NoiseModel &noise, const KltOptions &options = KltOptions(),
                             bool gate = true, const std::function<void(std::size_t, std::size_t)> &progress = {});

} // namespace yawdepth
