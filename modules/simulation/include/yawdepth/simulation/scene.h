#pragma once
/*!
  \file scene.h
  \brief Seeded synthetic scenes with known truth: a robot driving with a yawing camera (or any
  6-DoF trajectory, e.g. an arm's), random 3D points, their observed (distorted, noisy) pixels and
  a dead-reckoned (noisy) motion log.

  Used by the tests, the benchmarks and `yawdepth simulate`. The same seed gives the same scene.
*/
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief How to make a scene. Lengths in m, angles in rad, noise 1-sigma. */
struct SceneOptions {
  int frames = 10;            //!< Number of frames (>= 1).
  double step = 0.02;         //!< Forward translation per frame along the vision frame's +Z (m).
  double lateral_step = 0.0;  //!< Translation per frame along the vision frame's +X (m).
  double yaw = 0.0;           //!< Camera yaw at frame 0 (rad).
  double yaw_rate = 0.0;      //!< Yaw change per frame (rad).
  double heading = 0.0;       //!< Robot heading at frame 0 (rad).
  double turn_rate = 0.0;     //!< Heading change per frame (rad).
  int points = 30;            //!< Number of 3D points.
  double min_depth = 0.5;     //!< Points' depth range in the first camera frame (m).
  double max_depth = 3.0;     //!< Upper end of the depth range (m).
  double margin_px = 20.0;    //!< Points start at least this far inside the image border (px).
  /*! A 6-DoF trajectory: the true pose of the vision frame in the world (wMv) per frame. When not
      empty it replaces the planar one (step, lateral_step, heading, turn_rate), `frames` is its
      length, and the motion logs are 6-DoF (MotionSample::six_dof). See armTrajectory(). */
  std::vector<vpHomogeneousMatrix> vision_poses;
  /*! Points given in the world frame (m), ids = index: when not empty they replace the drawn ones
      (`points`, `min_depth`, `max_depth`, `margin_px` are then unused). For long sequences where
      features appear and vanish (a robot driving past a wall of points). */
  std::vector<Eigen::Vector3d> world_points;
  NoiseModel noise{0.0, 0.0, 0.0, 0.0, 0.0}; //!< Noise added to pixels and to the motion log (default: none).
  std::uint64_t seed = 1;     //!< Random seed.
  /*! \brief Throws yawdepth::Error for invalid options. */
  void validate() const;
};

/*! \brief A synthetic scene. */
struct Scene {
  std::vector<MotionSample> truth;    //!< True motion log.
  std::vector<MotionSample> measured; //!< Dead-reckoned motion log (odometry and yaw noise): each
                                      //!< increment perturbed (translation, and heading or 6-DoF rotation) and accumulated.
  std::vector<Track> tracks;          //!< Observed pixels (distortion and pixel noise), ids 0..points-1.
  std::vector<Eigen::Vector3d> w_points; //!< True points in the world frame, by id.
  /*! \brief True point of feature `id` in the camera frame at motion-log row `index`. */
  Eigen::Vector3d cameraPoint(const YawRig &rig, long id, std::size_t index) const;
};

/*!
  \brief Build a scene. Points are drawn uniformly in the first image (inside the margin) and in
  depth; a point is observed in every frame where it is in front of the camera and inside the image
  (the image size is the camera's, or 640x480 when the camera has none).
*/
Scene simulateScene(const CameraModel &camera, const YawRig &rig, const SceneOptions &options);

/*!
  \brief Add a tracker's errors to every track's pixels: per axis an AR(1) process along the track
  (NoiseModel::pixel_correlation's model), stationary 1-sigma `sigma` (px), correlation `phi` from one
  frame to the next (phi^gap across a gap), seeded. A scene simulated with sigma_px 0 then has the
  errors of a tracker that follows its corners from image to image. Throws yawdepth::Error for a
  sigma that is not finite and non-negative or a phi outside [0, 0.99].
*/
void addTrackerErrors(std::vector<Track> &tracks, double sigma, double phi, std::uint64_t seed);

/*! \brief Kinds of arm-like camera paths (armTrajectory()). */
enum class ArmPath {
  Approach, //!< toward the target along the optical axis, drifting sideways, 30 % of the distance
  Orbit,    //!< an arc of 40 degrees around the target at constant distance, swaying vertically
  Random    //!< random positions within 15 % of the distance around the start, random roll
};
/*! \brief "approach", "orbit", "random"; throws yawdepth::Error for another word. */
ArmPath armPathFromString(const std::string &word);

/*!
  \brief An arm-like 6-DoF trajectory: the camera always looks at a target `distance` metres ahead
  of its first pose (within a few degrees), the world frame being the first camera frame. Returns
  the vision frame's poses wMv for SceneOptions::vision_poses, through the rig's mount at `yaw`.
  \param rig The camera mount (the camera's path is turned into the vision frame's through it).
  \param path The kind of path. \param frames Number of poses. \param distance Distance of the
  target from the first camera pose (m).
  \param seed Random perturbations (Random path, and a small look-at jitter on every path).
  \param yaw The pan joint's angle (rad) at which the mount is taken.
*/
std::vector<vpHomogeneousMatrix> armTrajectory(const YawRig &rig, ArmPath path, int frames, double distance,
                                               std::uint64_t seed, double yaw = 0.0);

} // namespace yawdepth
