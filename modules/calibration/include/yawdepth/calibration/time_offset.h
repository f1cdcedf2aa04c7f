#pragma once
/*!
  \file time_offset.h
  \brief The time offset between the camera's clock and the motion log's, estimated with the rig:
  the image at camera time t was taken at motion time t + offset (yawdepth/io/recording.h).

  Method: the offset's profile likelihood. For each candidate offset the images' poses are
  interpolated at their times and the calibration is solved for every other unknown; the offset
  minimising the reprojection cost \f$ S(\delta) \f$ is the joint least-squares estimate. It is found
  by a grid over the search range, then golden-section search to `tolerance`; its 1-sigma is
  \f$ \sqrt{2 \hat\sigma^2 / S''(\hat\delta)} \f$, with \f$ \hat\sigma^2 = S / (n - p) \f$ the residual
  variance and \f$ S'' \f$ from a parabola through the cost around the minimum.

  What makes it observable: the camera's motion must change speed (a pan sweeping back and forth, a
  robot accelerating). At a constant yaw rate an offset is the same as a yaw offset, and a constant
  velocity the same as a shifted start: the cost is then flat, and the estimate is refused.
*/
#include <cstddef>
#include <functional>
#include <vector>
#include <yawdepth/calibration/rig_calibration.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

/*! \brief Where and how finely the offset is searched (s). */
struct TimeOffsetSearch {
  double min = -0.1;        //!< smallest offset tried (s)
  double max = 0.1;         //!< largest offset tried (s)
  double step = 0.005;      //!< grid step before the golden-section search (s)
  double tolerance = 1e-5;  //!< the search stops when the bracket is this narrow (s)
  /*! \brief Throws yawdepth::Error unless min < max, 0 < tolerance <= step, all finite. */
  void validate() const;
};

/*! \brief The cost of a calibration at one offset: its sum of squared residuals and its size. */
struct ProfileCost {
  double sum_squares = 0; //!< sum of squared reprojection residuals (px^2)
  double residuals = 0;   //!< number of residual components
  double parameters = 0;  //!< number of parameters estimated beside the offset
};

/*! \brief The estimated offset. */
struct TimeOffsetEstimate {
  double offset = 0;      //!< the image at camera time t was taken at motion time t + offset (s)
  double sigma = 0;       //!< its 1-sigma (s)
  double sum_squares = 0; //!< the cost at the offset (px^2)
  int evaluations = 0;    //!< calibrations solved
};

/*!
  \brief Minimise `cost` over the offset (see the file). `cost` may throw yawdepth::Error for an
  offset where the calibration fails: that offset counts as infinitely bad.
  \throws yawdepth::Error when every offset fails, when the minimum is at an end of the range (widen
  it), or when the cost is flat (the motion does not tell the offset).
*/
TimeOffsetEstimate estimateTimeOffset(const std::function<ProfileCost(double)> &cost, const TimeOffsetSearch &search);

/*!
  \brief A calibration's cost from the images' poses at one offset: `samples[k]` is the motion log
  interpolated at image `images[k]`'s time plus the offset (an index into the image list; frames
  numbered 0, 1, ...). It may throw yawdepth::Error when the calibration cannot be solved.
*/
using TimedImagesCost =
    std::function<ProfileCost(const std::vector<MotionSample> &samples, const std::vector<std::size_t> &images)>;

/*! \brief The offset found over timed images (estimateTimeOffsetOverImages()). */
struct TimedImagesOffset {
  TimeOffsetEstimate estimate;       //!< the offset; its sigma the larger of the curvature's and the jackknife's
  std::vector<std::size_t> images;   //!< the images used (indices into the list): a pose over the whole range
  std::vector<MotionSample> samples; //!< their motion samples at the offset found
};

/*!
  \brief The images, among the `usable` ones, that have a pose (alignMotionToImages()) at both ends
  of the search range: the same views at every offset tried.
*/
std::vector<std::size_t> imagesPosedOverRange(const MotionLog &motion, const std::vector<double> &image_times,
                                              const std::vector<bool> &usable, const TimeOffsetSearch &search,
                                              double max_pose_gap);

/*! \brief The motion samples of `images` (indices into `image_times`) at `offset`, frames 0, 1, ...;
    throws yawdepth::Error when one has no pose. */
std::vector<MotionSample> imageSamplesAt(const MotionLog &motion, const std::vector<double> &image_times,
                                         const std::vector<std::size_t> &images, double offset, double max_pose_gap);

/*!
  \brief The time offset of any calibration from timed images and a timestamped log: the profile
  (estimateTimeOffset()) of `cost` over the images with a pose over the whole range (at least 3),
  and with 20 images or more a delete-a-group jackknife over ten blocks of consecutive images (each
  block left out, the offset searched again within two grid steps): the motion log's errors are
  shared by an image's residuals and by neighbouring images, which the curvature does not see; the
  larger sigma is kept. Used by calibrateRigWithTimeOffset() and calibrateHandEyeWithTimeOffset().
  \param motion A timestamped log. \param image_times Camera-clock times (s).
  \param usable Per image, whether it has the board. \param cost The calibration at one offset.
  \param search The offsets tried. \param max_pose_gap As TimeAlignmentOptions.
  \throws yawdepth::Error as estimateTimeOffset(), with fewer than 3 images posed over the range, or
  when the calibration cannot be solved without a tenth of the images in more than half the cases.
*/
TimedImagesOffset estimateTimeOffsetOverImages(const MotionLog &motion, const std::vector<double> &image_times,
                                               const std::vector<bool> &usable, const TimedImagesCost &cost,
                                               const TimeOffsetSearch &search, double max_pose_gap);

/*! \brief The yaw rig's calibration with the time offset (calibrateRigWithTimeOffset()). */
struct TimedRigCalibration {
  RigCalibration rig;            //!< the rig at the estimated offset
  TimeOffsetEstimate time_offset; //!< the offset
  int images_used = 0;           //!< images whose pose is known over the whole search range
};

/*!
  \brief The yaw rig and the time offset together, from a board seen while the pan moves.
  \param camera, board As calibrateRig(). \param motion A timestamped log (readMotionFile()) with
  the yaw readings. \param image_times Each image's camera-clock time (s).
  \param features Each image's detected board features (empty when not found).
  \param options As calibrateRig() (its max_rms_px applies to the final fit).
  \param search The offsets tried. \param max_pose_gap As TimeAlignmentOptions.
  Only images with a pose over the whole search range are used.
*/
TimedRigCalibration calibrateRigWithTimeOffset(const CameraModel &camera, const BoardLayout &board,
                                               const MotionLog &motion, const std::vector<double> &image_times,
                                               const std::vector<std::vector<FeatureObservation>> &features,
                                               const RigCalibrationOptions &options, const TimeOffsetSearch &search,
                                               double max_pose_gap = 0.2);

} // namespace yawdepth
