#pragma once
/*!
  \file measuring_node.h
  \brief What a middleware node does around OnlineMeasurer, without the middleware: its settings
  (the ROS node's parameters, docs/ros.md), its start (the camera from camera_info, the mount, the
  pan joint's vision frame), the motion it pushes, its diagnostics and the servo depth requests. The
  ROS 1 node (modules/ros1) only converts messages to and from these calls; a ROS 2 node would be
  the same conversions against rclcpp.

  Frames: w the world, b the body (the motion's moving frame), v the vision frame (b itself, or with
  a pan joint panJointFrame(joint_axis, joint_origin): bMv), c the camera (an optical frame). The
  mount bMc at pan 0 is fixed (a static transform) or, when it moves with the pan (a pan link in the
  transform tree), the camera's own pose is the motion and the joint readings are not used.

  Times: images on the camera's clock (their header stamps), poses and joint readings on the motion
  clock; an image stamped t was exposed at motion time t - camera_latency.

  Thread-safe: the pushes from any thread, process() from one consumer thread, as OnlineMeasurer.
*/
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/bag/messages.h>
#include <yawdepth/online/frame_outputs.h>
#include <yawdepth/online/online_measurer.h>
#include <yawdepth/servo/depth_provider.h>

namespace yawdepth {

/*! \brief A measuring node's settings: the ROS node's parameters (docs/ros.md, "Parameters"). */
struct MeasuringNodeSettings {
  std::string motion = "tf";              //!< `tf` (world_frame -> body_frame from the transforms) or `odom` (an odometry topic).
  std::string world_frame = "odom";       //!< The world frame with motion `tf`.
  std::string body_frame = "base_link";   //!< The body frame with motion `tf`.
  std::string camera_frame;               //!< The camera frame; empty: the images' frame id.
  std::string joint;                      //!< The pan joint's name in the joint states; empty: no pan joint.
  Eigen::Vector3d joint_axis{0, 1, 0};    //!< The pan axis in the body frame (panJointFrame()).
  Eigen::Vector3d joint_origin{0, 0, 0};  //!< A point on the pan axis in the body frame (m).
  double camera_latency = 0.0;            //!< How long after its exposure an image is stamped (s).
  double interval_sigmas = 2.0;           //!< The depth intervals' half-width (frameCloud()), in sigmas (>= 0).
  double diagnostics_period = 1.0;        //!< How often diagnostics are published (s, > 0; wall clock).
  double service_wait = 0.2;              //!< How long a depth request waits for the motion around it (s, >= 0; wall clock).
  OnlineOptions online;                   //!< The measurer's options; its time_offset is -camera_latency (onlineOptions()).
  /*! \brief Throws yawdepth::Error "<parameter>: <why>" for an invalid setting. */
  void validate() const;
  /*! \brief `online` with `time_offset = -camera_latency`: what the measurer runs with (with a fixed
      pan mount, MeasuringNode also sets wait_for_joints). */
  OnlineOptions onlineOptions() const;
  /*! \brief The servo requests' DepthProvider: its own defaults (the noise model of control periods,
      the convergence rules) with the measurer's method, window and prior depth. */
  DepthProviderOptions providerOptions() const;
};

/*! \brief The transforms' answer about the camera's mount, body -> camera (see MeasuringNode::start()). */
struct MountLookup {
  std::optional<vpHomogeneousMatrix> fixed; //!< bMc from the static transforms alone, when they chain.
  bool moving = false;                      //!< Whether the chain exists only with the moving transforms.
  std::string why;                          //!< The transform library's reason when neither (for the log).
};

/*! \brief A node's health for the diagnostics topic. */
struct NodeDiagnostics {
  bool warn = false;                                      //!< WARN (else OK).
  std::string message;                                    //!< One line.
  std::vector<std::pair<std::string, std::string>> values; //!< Key-value pairs (docs/ros.md's keys).
};

/*! \brief A servo client's features in its image stamped `t` (camera clock): ids and observed pixels. */
struct ServoDepthRequest {
  double t = 0;               //!< The image's stamp (s).
  std::vector<long> ids;      //!< The client's ids.
  std::vector<double> u, v;   //!< Observed pixels (px), one per id.
};

/*! \brief The answer: DepthProvider's FeatureDepth per id, or the reason there is none. */
struct ServoDepthAnswer {
  std::vector<FeatureDepth> depths; //!< One per requested id, in order (empty with an error).
  std::string error;                //!< Empty, or why no depths were given.
};

/*! \brief OnlineMeasurer as a node runs it (see the file). */
class MeasuringNode {
public:
  /*! Throws yawdepth::Error for invalid settings. */
  explicit MeasuringNode(const MeasuringNodeSettings &settings);
  ~MeasuringNode();
  MeasuringNode(const MeasuringNode &) = delete;
  MeasuringNode &operator=(const MeasuringNode &) = delete;

  /*! \brief The settings. */
  const MeasuringNodeSettings &settings() const { return settings_; }

  /*! @name Start */
  ///@{
  /*!
    \brief A camera_info: the first is the camera (cameraFromCameraInfo(): throws yawdepth::Error
    naming `topic` for a bad one, which is not kept); a later one is compared with it.
    \return false when a later one gives another calibration (the first is kept: warn).
  */
  bool setCameraInfo(const CameraInfoMessage &info, const std::string &topic);
  /*!
    \brief The odometry's frames (motion `odom`): the first message's are kept; throws yawdepth::Error
    naming `topic` when a later message gives others.
  */
  void setOdometryFrames(const std::string &world, const std::string &body, const std::string &topic);
  /*! \brief The body frame: body_frame (motion `tf`), the odometry's child frame, or empty before it. */
  std::string bodyFrame() const;
  /*! \brief The world frame: world_frame (motion `tf`), the odometry's frame, or empty before it. */
  std::string worldFrame() const;
  /*!
    \brief Start measuring once the camera, the body and the mount are known: with the first image's
    frame id (unless camera_frame is set) and `mount`, the transforms' answer for bodyFrame() ->
    the camera frame (called only when the two differ).
    \return empty when measuring (now or before), else what it waits for (one line, for the log).
    Throws yawdepth::Error when the images have no frame id and camera_frame is not set.
  */
  std::string start(const std::string &image_frame, const std::function<MountLookup(const std::string &body,
                                                                                    const std::string &camera)> &mount);
  /*! \brief Whether start() succeeded. */
  bool started() const { return started_.load(); }
  /*! \brief The camera frame (after start()). */
  const std::string &cameraFrame() const { return camera_frame_; }
  /*! \brief Whether the mount moves (after start()): the camera's own pose is the motion. */
  bool movingMount() const { return moving_mount_; }
  /*! \brief The frame whose pose in the world is the motion (after start()): the body's, or the camera's
      with a moving mount. */
  const std::string &motionFrame() const { return moving_mount_ ? camera_frame_ : body_frame_; }
  /*! \brief The pan joint's vision frame in the body, bMv (identity without a joint or with a moving mount). */
  const vpHomogeneousMatrix &bMv() const { return bMv_; }
  ///@}

  /*! @name Streams (before start(), ignored) */
  ///@{
  /*! \brief An image (8-bit gray) stamped `t`. */
  void pushImage(double t, const cv::Mat &gray);
  /*!
    \brief The motion frame's pose in the world at `t` (motionFrame()), pushed as wMv = wMb bMv; with a
    moving mount and an odometry, `bMc_t` is the mount at `t`, chained on.
  */
  void pushMotion(double t, const vpHomogeneousMatrix &wMb, const vpHomogeneousMatrix &bMc_t = vpHomogeneousMatrix());
  /*!
    \brief The transform a queued motion sample waits for (queueMotion()), at its time `t` (s) and
    with the `tag` it was queued with (the middleware's exact stamp, e.g. in ns); none when the
    transforms do not give it yet.
  */
  using TransformAt = std::function<std::optional<vpHomogeneousMatrix>(double t, std::uint64_t tag)>;
  /*!
    \brief A motion sample whose transform may come later: with motion `tf`, a stamp of the
    transforms (`wMb` empty; the transform is the chain world -> motionFrame() at it); with an
    odometry and a moving mount, the odometry's pose `wMb` (the transform is the mount body -> camera
    at its time). Queued in time order, pushed by resolveMotion() once its transform is known: a
    chain with a slower link, or a moving mount's link published after the odometry, loses no pose.
    Kept in time order (a stamp ahead of the others waits while the earlier ones go through); a time
    already queued, or not after the last one pushed, is ignored; samples more than max_image_age
    behind the newest queued are dropped (counted: "motion dropped (no transform)" in the diagnostics).
  */
  void queueMotion(double t, std::uint64_t tag, const std::optional<vpHomogeneousMatrix> &wMb = std::nullopt);
  /*!
    \brief Push the queued samples whose transform `transform_at` gives, in time order (pushMotion());
    one it does not give while a later one it does is dropped and counted (before a link's first
    reading: never given).
    \return How many were pushed.
  */
  std::size_t resolveMotion(const TransformAt &transform_at);
  /*!
    \brief A joint state: the pan joint's position, when `names` has it (not used with a moving mount).
    \return false when `names` has no pan joint. Throws yawdepth::Error naming `topic` when it has no
    position for it.
  */
  bool pushJointState(double t, const std::vector<std::string> &names, const std::vector<double> &positions,
                      const std::string &topic);
  /*! \brief A bad message was dropped (counted in the diagnostics). */
  void noteBadMessage() { ++bad_messages_; }
  /*!
    \brief After the clock jumped back (a bag played again): a new measurer and servo provider with
    the same camera, mount and settings, every stream starting afresh (the old estimates, tracks and
    buffered motion dropped). No-op before start(). Frames of the old measurer still being published
    keep their clouds.
  */
  void restart();
  ///@}

  /*! @name Outputs */
  ///@{
  /*! \brief OnlineMeasurer::process() (none before start()); each frame counted for the diagnostics. */
  std::vector<OnlineFrame> process();
  /*! \brief frameCloud() of a frame with the settings' interval (its size is the diagnostics' points published). */
  std::vector<CloudPoint> cloud(const OnlineFrame &frame);
  /*! \brief The diagnostics since the previous call (see docs/ros.md's keys). */
  NodeDiagnostics diagnostics();
  /*!
    \brief A servo client's control period: the motion at the request's time (OnlineMeasurer::poseAt,
    waiting up to service_wait for it), then one DepthProvider::update. Errors are answered, not thrown.
  */
  ServoDepthAnswer depths(const ServoDepthRequest &request);
  ///@}

private:
  MeasuringNodeSettings settings_;
  mutable std::mutex mutex_; // the start's state (before started_), the odometry frames, the diagnostics' counters
  std::optional<CameraInfoMessage> info_;
  std::string info_topic_, odom_world_, odom_body_;
  std::string waiting_; // what start() waits for
  std::atomic<bool> started_{false};
  // Set once by start(), before started_; read-only after.
  std::string camera_frame_, body_frame_, world_frame_;
  bool moving_mount_ = false;
  vpHomogeneousMatrix bMv_;
  std::unique_ptr<YawRig> rig_;
  std::unique_ptr<CameraModel> camera_;
  OnlineOptions online_;
  // Replaced by restart(): read through measurer() (an atomic load of the shared pointer).
  std::shared_ptr<OnlineMeasurer> measurer_;
  std::shared_ptr<OnlineMeasurer> measurer() const { return std::atomic_load(&measurer_); }
  // The motion waiting for its transforms (queueMotion()), in time order.
  struct PendingMotion {
    double t = 0;
    std::uint64_t tag = 0;
    std::optional<vpHomogeneousMatrix> wMb;
  };
  std::mutex motion_mutex_; // the queue, and the order of its pushes
  std::deque<PendingMotion> pending_motion_;
  double last_pushed_t_ = -std::numeric_limits<double>::infinity();
  std::atomic<std::size_t> unresolved_motion_{0};
  std::mutex provider_mutex_;
  std::unique_ptr<DepthProvider> provider_;
  // Diagnostics (under mutex_).
  std::atomic<std::size_t> bad_messages_{0};
  std::size_t frames_ = 0, last_dropped_ = 0, last_cloud_ = 0, last_bad_ = 0, restarts_ = 0;
  std::vector<double> latencies_ms_;
  std::vector<std::pair<Status, std::size_t>> last_counts_;
  std::chrono::steady_clock::time_point last_diagnostics_{};
};

} // namespace yawdepth
