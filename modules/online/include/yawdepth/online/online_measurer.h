#pragma once
/*!
  \file online_measurer.h
  \brief Measuring as a robot runs: images, poses and joint readings pushed as they arrive, each from
  its own thread and at its own rate; every image measured once the motion around its time is known.

  A robot gives three streams: images (e.g. 30 Hz, the camera's clock), the vision frame's pose in
  the world (odometry, forward kinematics: e.g. 100 Hz, the motion clock) and, for a pan head, the
  joint's yaw readings (e.g. 50 Hz, the motion clock). Each push is non-blocking: the measurer's
  mutex is held only to enqueue. process(), called from one consumer thread (a timer, a loop), measures
  every queued image whose motion time \f$ t + \text{time\_offset} \f$ (the image at camera time t was
  taken at motion time t + time_offset, as yawdepth/io/recording.h's alignment) lies between two
  poses, and between two joint readings when any were pushed: never extrapolated. The image's pose is
  interpolateMotion() of the two poses around it (geometry/rig.h: translation linear, rotation by slerp),
  its yaw interpolateMotion()'s yaw of the two joint readings around it (wrap-safe), or the poses' own
  yaw when no joint reading was pushed. Then KltTracker tracks the image's natural features, gated by
  the known motion since the previous measured image (kltMotion(), as trackSequence()), and a
  StreamEstimator (window by default, or fused) takes the frame; each measured image gives an
  OnlineFrame with its points' estimates. While the oldest queued image waits for its motion, a
  process() call that measured nothing does the part of its tracking that needs none
  (KltTracker::prepare(): the pyramid and plain Lucas-Kanade, the same numbers as without), so that
  only the gated rest is left when the motion comes.

  Bounded memory and latency. An image whose motion time is more than `max_image_age` behind the
  newest time any stream has pushed (on the motion clock: poses and joints as they are, images plus
  time_offset) is dropped (`dropped_stale`): a stalled pose stream does not hold images forever, and
  measuring resumes when poses return. An image before the first pose (or joint reading) kept, or
  between two poses (or joint readings) further apart than `max_pose_gap`, can never be measured and
  is dropped (`dropped_uncovered`). The queue holds at most `max_queued_images` images (the oldest
  dropped, `dropped_overflow`); poses and joint readings are kept from max_image_age behind the newest
  time on (what a queued image, or poseAt(), may still need). A timestamp not after its stream's previous one is counted and dropped (a
  live stream must not die on one glitch); a non-finite one is an Error.

  A pose stream may also come as odometry increments (pushOdometryIncrement()), composed onto the
  stream's last pose.
*/
#include <chrono>
#include <cstddef>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>
#include <opencv2/core.hpp>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/window/stream_estimator.h>

namespace yawdepth {

/*! \brief Options of OnlineMeasurer: the estimator's, the tracker's, and the streams' limits. */
struct OnlineOptions {
  StreamMethod method = StreamMethod::Window; //!< `window` (the default) or `fused`.
  NoiseModel noise;                           //!< The one noise model: pixels, motion, yaw readings (tracker gate and estimator).
  int window = StreamOptions().window;        //!< window: frames kept in the window (>= 2).
  double prior_depth = StreamOptions().prior_depth; //!< The prior depth of a new feature (m), as StreamOptions.
  KltOptions klt;                             //!< Tracking options.
  double time_offset = 0.0;   //!< The image at camera time t was taken at motion time t + time_offset (s).
  double max_pose_gap = 0.2;  //!< An image between two poses (or joint readings) further apart is dropped (s, > 0).
  double max_image_age = 0.5; //!< An image this far behind the newest time of any stream is dropped (s, > 0).
  int max_queued_images = 16; //!< Most images queued; a push beyond drops the oldest (>= 1).
  /*! A pan rig whose joint readings will come: every image waits for joint readings around it from
      the start (else, before the first reading, the poses' own yaw is used: never for a pan rig). */
  bool wait_for_joints = false;
  /*! \brief Throws yawdepth::Error (one line naming the field) for an invalid option. */
  void validate() const;
};

/*! \brief One tracked feature of a measured image and its estimate. */
struct OnlinePoint {
  long id = 0;             //!< Feature id (KltTracker's: never reused).
  double u = 0;            //!< Observed pixel: column (px).
  double v = 0;            //!< Observed pixel: row (px).
  PointEstimate estimate;  //!< StreamEstimator::estimate(): c_P in this image's camera when ok (frame == this frame).
};

/*! \brief One measured image. */
struct OnlineFrame {
  double t = 0;            //!< The image's time, camera clock (s), as pushed.
  double t_motion = 0;     //!< Its motion-clock time, t + time_offset (s).
  long frame = 0;          //!< Frame number: the measured images before it (0, 1, ...: consecutive, the estimator's frames).
  MotionSample pose;       //!< The motion-log row used: the pose (and yaw) interpolated at t_motion; `frame` set.
  cv::Mat image;           //!< The measured image (8-bit gray; shares the copy pushImage() made).
  std::vector<OnlinePoint> points; //!< The features tracked in this image.
  double latency_ms = 0;   //!< Wall time from pushImage() to this frame's result (ms).
  double wait_ms = 0;      //!< Of it: from pushImage() until process() took the image (waiting for its motion) (ms).
  /*! Of the wait: the tracking done while the image waited for its motion (KltTracker::prepare(): its
      pyramid and plain LK; 0 when the motion was there first) (ms). */
  double ahead_ms = 0;
  double track_ms = 0;     //!< Of it: KltTracker::track, the rest of the tracking once the motion is known (ms).
  double estimate_ms = 0;  //!< Of it: StreamEstimator::addFrame and the estimates (ms).
};

/*! \brief Counters of an OnlineMeasurer (stats()). */
struct OnlineStats {
  std::size_t images_pushed = 0;      //!< Images accepted by pushImage().
  std::size_t images_measured = 0;    //!< Images measured (an OnlineFrame each).
  std::size_t dropped_stale = 0;      //!< Dropped: more than max_image_age behind the newest stream time.
  std::size_t dropped_uncovered = 0;  //!< Dropped: before the first pose/joint kept, or in a gap over max_pose_gap.
  std::size_t dropped_overflow = 0;   //!< Dropped: the queue was full (max_queued_images).
  std::size_t out_of_order_images = 0; //!< Image pushes whose time was not after the previous one (dropped).
  std::size_t out_of_order_poses = 0;  //!< Pose pushes whose time was not after the previous one (dropped).
  std::size_t out_of_order_joints = 0; //!< Joint pushes whose time was not after the previous one (dropped).
  std::size_t queued_images = 0;      //!< Images waiting now.
  std::size_t buffered_poses = 0;     //!< Poses kept now.
  std::size_t buffered_joints = 0;    //!< Joint readings kept now.
  double last_latency_ms = 0;         //!< The last measured image's OnlineFrame::latency_ms.
  /*! The last image's motion time minus the newest pose's time when it was pushed (s; NaN before an
      image and a pose): about the pose period when the clocks agree; far positive when the image
      stamps run ahead of the motion, far negative when behind (a wrong time_offset, another clock). */
  double image_ahead_of_poses = std::numeric_limits<double>::quiet_NaN();
  std::size_t joint_readings = 0;     //!< Joint readings accepted.
  /*! With joint readings (a pan rig): the vision frame's turn so far (geometry/rig.h's TurnAxis over
      the poses pushed). `turns_off_pan_axis` when it clearly turns about another axis than its +Y,
      the pan axis: on a robot driving on a floor, the sign of a wrong pan axis (or mount). */
  double turned = 0;                  //!< Total angle the vision frame turned (rad).
  Eigen::Vector3d turn_axis = Eigen::Vector3d::Zero(); //!< Its summed rotation vector, in the vision frame (rad).
  bool turns_off_pan_axis = false;    //!< TurnAxis::offPanAxis(), with joint readings only.
};

/*!
  \brief Images, poses and joint readings in, from any threads; measured frames out (see the file).
*/
class OnlineMeasurer {
public:
  /*!
    \param camera Camera model, with its image size (images must have it).
    \param rig Camera mount and yaw joint.
    \param options Options; throws yawdepth::Error for invalid ones.
  */
  OnlineMeasurer(const CameraModel &camera, const YawRig &rig, const OnlineOptions &options = OnlineOptions());
  ~OnlineMeasurer();
  OnlineMeasurer(const OnlineMeasurer &) = delete;
  OnlineMeasurer &operator=(const OnlineMeasurer &) = delete;

  /*!
    \brief Queue an image (copied). Thread-safe, non-blocking.
    \param t Its time, camera clock (s): finite (else Error), after the previous image's (else counted, dropped).
    \param gray 8-bit single channel, the camera's size (else yawdepth::Error).
  */
  void pushImage(double t, const cv::Mat &gray);
  /*!
    \brief Add a pose: a motion-log row, the vision frame's pose in the world (planar or 6-DoF, the
    same form for every push, else Error). Its `frame` is ignored; its `yaw` too once joint readings
    are pushed. Thread-safe, non-blocking.
    \param t Its time, motion clock (s): finite (else Error), after the previous pose's (else counted, dropped).
    \param row The pose; every value finite (else Error).
  */
  void pushPose(double t, const MotionSample &row);
  /*!
    \brief Add a pose as an odometry increment: the vision frame's pose at `t` in its pose at the
    previous pose pushed (\f$ {}^{v,prev}M_{v,cur} \f$), composed onto that pose:
    \f$ {}^wM_{v,cur} = {}^wM_{v,prev}\, {}^{v,prev}M_{v,cur} \f$, and queued as pushPose() would
    (the same stream, its yaw the previous pose's). A planar stream stays planar: its increments
    must turn about +Y only (else Error); a 6-DoF stream takes any. Needs a first pose from
    pushPose() (else Error). Thread-safe, non-blocking.
    \param t Its time, motion clock (s): finite (else Error), after the previous pose's (else counted, dropped).
    \param vprevMvcur The increment; every value finite (else Error).
  */
  void pushOdometryIncrement(double t, const vpHomogeneousMatrix &vprevMvcur);
  /*!
    \brief Add a joint reading: the camera's yaw relative to the vision frame (rad). Once one is
    pushed, every image needs joint readings around its time. Thread-safe, non-blocking.
    \param t Its time, motion clock (s): finite (else Error), after the previous reading's (else counted, dropped).
    \param yaw The yaw (rad), finite (else Error).
  */
  void pushJoint(double t, double yaw);

  /*!
    \brief Measure every queued image whose motion is known now, in time order; drop the stale and
    uncovered ones. Call from one consumer thread (calls are serialised); pushes go on meanwhile.
    \return One OnlineFrame per image measured by this call (none when no image is ready).
  */
  std::vector<OnlineFrame> process();

  /*!
    \brief The latest estimates of features `ids` carried to the newest pose (StreamEstimator::estimateAt()
    at currentPose()), for a servo loop: `too_few_frames` for an unknown id or before any pose.
    Waits for a process() call under way.
  */
  std::vector<PointEstimate> depths(const std::vector<long> &ids) const;
  /*! \brief Whether the motion at a time is known (poseAt()). */
  enum class Coverage {
    Covered, //!< Known: interpolated.
    NotYet,  //!< After the newest pose (or joint reading): it may come.
    Never    //!< Before the buffers' start (max_image_age behind the newest time), or in a gap over max_pose_gap.
  };
  /*!
    \brief The motion-log row at motion time `t_motion`, interpolated as an image's is (the poses and,
    once pushed or with wait_for_joints, the joint readings around it; never extrapolated), e.g. for
    a servo client's image at camera time t: poseAt(t + time_offset). `pose` is set when Covered.
    Throws yawdepth::Error for a non-finite time.
  */
  Coverage poseAt(double t_motion, MotionSample &pose) const;
  /*! \brief The newest pose pushed, its yaw the newest joint reading when joint readings are pushed;
      false before any pose. */
  bool currentPose(MotionSample &pose) const;
  /*! \brief The counters (a snapshot). */
  OnlineStats stats() const;
  /*! \brief The options. */
  const OnlineOptions &options() const { return options_; }

private:
  using Clock = std::chrono::steady_clock;
  struct QueuedImage {
    double t = 0;
    cv::Mat gray;
    Clock::time_point pushed;
  };
  struct Job;
  /* The row at motion time tm: 0 covered (pose set), 1 not yet (wait), -1 never (before the first
     kept, or in a gap over max_pose_gap). Under queue_mutex_. */
  int motionAtLocked(double tm, MotionSample &pose) const;
  bool nextJob(Job &job);
  void noteTime(double t_motion);
  void appendPoseLocked(double t, const MotionSample &row);
  void trimBuffers();

  CameraModel camera_;
  YawRig rig_;
  OnlineOptions options_;

  // Guarded by queue_mutex_: the streams and the counters.
  mutable std::mutex queue_mutex_;
  std::deque<QueuedImage> images_;
  std::deque<std::pair<double, MotionSample>> poses_;
  std::deque<std::pair<double, double>> joints_;
  bool have_pose_form_ = false;
  bool six_dof_ = false;
  bool joints_pushed_ = false;
  TurnAxis turn_; // over the poses pushed
  double last_image_t_, last_pose_t_, last_joint_t_, newest_t_;
  OnlineStats stats_;

  // Guarded by work_mutex_: the tracker and the estimator (process(), depths()).
  mutable std::mutex work_mutex_;
  KltTracker tracker_;
  StreamEstimator estimator_;
  long next_frame_ = 0;
  bool have_previous_ = false;
  MotionSample previous_;
  std::vector<std::pair<long, long>> last_seen_; // (id, frame) of the features the estimator may hold
  double ahead_ms_ = 0; // the last KltTracker::prepare() call's time (for the image it prepared)
};

} // namespace yawdepth
