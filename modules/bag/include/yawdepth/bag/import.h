#pragma once
/*
  bag/import.h, for the build tree only (not installed: the command line's `import-bag`; the
  CMakeLists.txt of yawdepth::bag).

  A bag turned into the files every command reads (`yawdepth import-bag`,
  `measure --bag`): the images, each image's pose (the motion source interpolated at its time on
  SE(3), as alignMotionToImages() does for recordings), the pan joint at each image time, the
  camera from `camera_info` and the camera's mount from `/tf_static`.

  Frames: `world` (the motion source's fixed frame: the odometry's `header.frame_id`, the pose's,
  or WORLD of `--tf WORLD:BODY`), `body` (the odometry's `child_frame_id`, the pose's subject, or
  BODY; the motion log's vision frame), the camera frame (`--camera-frame`, default the images'
  `frame_id`, usually an optical frame: z forward, x right, y down, as yawdepth's camera). wMb is
  the body's pose in the world, bMc the camera's pose in the body (the rig's `camera_pose`).
*/
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace yawdepth {

/* What `import-bag` reads and where it writes (the options of docs/formats.md, "import-bag"). */
struct BagImportOptions {
  std::string bag;                // the bag file or ROS 2 bag folder
  std::string out_dir;            // created; see BagImportResult for what is written there
  std::string image_topic;        // sensor_msgs/Image or sensor_msgs/CompressedImage (required)
  std::string camera_info_topic;  // empty: the image topic's sibling `camera_info`
  /* The motion, exactly one of: */
  std::string odom_topic;         // nav_msgs/Odometry
  std::string pose_topic;         // geometry_msgs/PoseStamped or PoseWithCovarianceStamped
  std::string tf_world;           // `--tf WORLD:BODY`'s WORLD: BODY's pose in WORLD from `/tf` (+ `/tf_static`)
  std::string tf_body;            // `--tf WORLD:BODY`'s BODY
  std::string camera_frame;       // empty: the images' `frame_id`
  std::string joint_topic;        // sensor_msgs/JointState with the pan joint, or empty
  std::string joint;              // the pan joint's name in joint_topic (required with it)
  /* The pan joint's axis in BODY (any length; its position turns the camera right-handedly about
      it) and a point on that axis (m, in BODY). yawdepth's vision frame turns the camera about its +Y
      through its origin: with a joint, the motion log is written for the vision frame v whose +Y is
      this axis and whose origin is this point (wMv = wMb bMv), and camera_pose is vMc. The default,
      +Y through BODY's origin, is yawdepth's own convention; REP 103's z-up base_link needs
      {0, 0, 1} and the joint's position (from the robot's URDF). */
  std::array<double, 3> joint_axis{0, 1, 0};
  std::array<double, 3> joint_origin{0, 0, 0}; // see joint_axis
  double start = 0.0;             // seconds after the bag's first message to start at
  double duration = -1.0;         // seconds to read from start; negative: to the end
  int every = 1;                  // keep every Nth image (N >= 1)
  double time_offset = 0.0;       // image at camera time t was taken at motion time t + time_offset (s)
  double max_pose_gap = 0.2;      // an image between pose samples further apart is skipped (s)
  /* Called after each image message of the window is read, with (images read, the image topic's
      message count in the whole bag, 0 when the bag does not say); empty (the default): not called.
      The library never prints: a command line shows it. */
  std::function<void(std::size_t, std::size_t)> progress;
  /* Throws yawdepth::Error naming the option that is wrong (none or several motion sources, ...). */
  void validate() const;
};

/* What was read, matched and written. */
struct BagImportResult {
  std::string images_dir;    // `images/`: one PNG per kept image, named by its header stamp (ns)
  std::string motion_path;   // `motion.csv`: frame-based, 6-DoF wMb (wMv with a joint), with `t`, `image` and (with a joint) `yaw` columns
  std::string camera_path;   // `camera.yaml`: the ROS camera_info YAML of the first `camera_info`
  std::string rig_path;      // `rig.yaml`: `camera_pose` (bMc, or vMc with a joint, from /tf_static; identity when camera frame = body)
  std::vector<std::string> topics_used; // "topic (type): N messages" for each topic read
  std::size_t images_read = 0;    // images in the window
  std::size_t images_kept = 0;    // kept by `--every`
  std::size_t images_matched = 0; // given a pose (and a joint reading): written
  std::size_t skipped_before = 0; // before the motion's (or the joint's) first sample
  std::size_t skipped_after = 0;  // after its last
  std::size_t skipped_gap = 0;    // in a gap over max_pose_gap (or outside a moving mount's readings)
  std::size_t poses = 0;          // motion samples read
  std::size_t joint_readings = 0; // pan joint readings read
  double image_first = 0;         // the first image's stamp (s)
  double image_last = 0;          // the last image's stamp (s)
  double motion_first = 0;        // the first motion sample's stamp (s)
  double motion_last = 0;         // the last motion sample's stamp (s)
  std::vector<std::string> warnings;        // e.g. camera_info changing during the bag
  /* The summary import-bag prints: topics used, message counts, time spans, images matched and skipped. */
  std::string summary() const;
};

/*
  Read the bag and write the files (each one whole or not at all: on any error nothing is
  left in out_dir that looks complete).
  Throws yawdepth::Error with a one-line reason naming the bag, topic or frame: a missing topic
  (listing the bag's topics and types), a wrong message type, a TF chain that does not connect
  (naming the frames that exist), images of another size than camera_info, a corrupt bag.
*/
BagImportResult importBag(const BagImportOptions &options);

} // namespace yawdepth
