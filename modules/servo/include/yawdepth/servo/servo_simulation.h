#pragma once
/*!
  \file servo_simulation.h
  \brief A mobile robot with a yawing (pan) camera, and an image-based servo on a tag's four
  corners with true, constant or estimated depth: the simulation behind
  examples/servo_ibvs_yawing_camera, examples/servo_table.sh and tests/test_servo.cpp.

  Robot (`UnicyclePanRobot`): a unicycle (forward speed v, turn rate omega about +Y, down) whose
  pan (yaw) axis sits `axle_to_yaw` m ahead of the wheel axle, and a camera whose optical centre
  is at `rig.cameraOffset()` from the yaw axis (yawdepth::YawRig). Frames use the camera
  convention (X right, Y down, Z forward); the world is the robot's ground plane, Y = 0. Its
  camera-frame Jacobian `cJq` maps the joint rates (v, omega, pan rate) to the camera's twist
  (vx, vy, vz, wx, wy, wz): with the yaw axis off the axle, omega also moves the camera sideways,
  so the three joints control the camera's planar pose (X, Z, yaw) fully.

  Servo: vpServo EYEINHAND_L_cVe_eJe with cVe = identity and eJe = cJq, interaction matrix
  CURRENT, gain `lambda`, joint rates saturated (scaled together) at the robot's limits; the
  features are the undistorted normalised corners, observed with pixel noise. Depth of each
  feature: `True` the true depth, `Constant` desired depth x (1 + constant_error) for every
  feature, `Estimated` a yawdepth::DepthProvider fed with the robot's dead-reckoned odometry
  (velocity noise) and pan readings (noise). Convergence: the true mean corner distance to the
  desired corners below `tolerance_px`.
*/
#include <cstdint>
#include <functional>
#include <string>
#include <vector>
#include <Eigen/Core>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpMatrix.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/servo/depth_provider.h>
#include <yawdepth/servo/yaw_helper.h>

namespace yawdepth {

/*! \brief Unicycle robot with a pan camera (see the file). State: wheel-axle centre (x, z), heading, pan. */
struct UnicyclePanRobot {
  double axle_to_yaw = 0.2; //!< yaw axis ahead of the wheel axle (m)
  YawRig rig;               //!< optical centre offset from the yaw axis
  /*! wheel-axle centre in the world: X (m) */
  double x = 0, z = 0;      //!< wheel-axle centre in the world: Z (m)
  double heading = 0;       //!< about +Y (rad)
  double pan = 0;           //!< camera yaw relative to the robot (rad)

  /*! \brief The vision frame's pose (at the yaw axis) and the pan, as a motion-log row. */
  MotionSample sample(long frame = 0) const;
  /*! \brief Camera pose in the world. */
  vpHomogeneousMatrix wMc() const;
  /*! \brief 6x3 Jacobian: camera twist in the camera frame per joint rate (v, omega, pan rate). */
  vpMatrix cJq() const;
  /*! \brief Velocity of the vision frame's origin in the vision frame for joint rates (v, omega). */
  Eigen::Vector3d visionVelocity(double v, double omega) const;
  /*! \brief Integrate joint rates (v, omega, pan rate) over dt (exact arc for the unicycle). */
  void step(const vpColVector &qdot, double dt);
  /*! \brief Place the robot so that its camera has world pose wMc_target with the given heading. */
  void placeCamera(const vpHomogeneousMatrix &wMc_target, double heading_rad);
};

/*! \brief How each feature's depth is obtained. */
enum class ServoDepthMode { True, Constant, Estimated };
/*! \brief "true", "constant", "estimated". */
const char *toString(ServoDepthMode m);
/*! \brief Parse "true" | "constant" | "estimated"; throws yawdepth::Error. */
ServoDepthMode servoDepthModeFromString(const std::string &s);

/*! \brief The simulated servo run. */
struct ServoSimOptions {
  ServoDepthMode depth = ServoDepthMode::Estimated; //!< how each feature's depth is obtained
  double constant_error = 0.5;  //!< Constant mode: Z = desired depth x (1 + constant_error)
  bool side_view = false;       //!< false: front view (robot drives toward the tag); true: side view (pan 90 deg, drives past it)
  bool yaw_helper = false;      //!< add recommendYawRate() as a secondary task (large projection operator) while depths are unconverged
  double dt = 0.05;             //!< control period (s)
  double lambda = 1.0;          //!< servo gain (1/s)
  int max_iterations = 2000;    //!< stop after this many control periods
  double tolerance_px = 0.5;    //!< converged when the true mean corner error is below this (px)
  /*! joint rate limit: forward speed (m/s) */
  double max_v = 0.3, max_omega = 1.0, max_pan_rate = 1.0; //!< joint rate limit: pan rate (rad/s)
  /*!
    \var max_omega
    joint rate limit: turn rate (rad/s)
  */
  double tag_size = 0.2;        //!< tag side (m)
  double desired_depth = 0.6;   //!< camera to tag at the goal (m)
  double sigma_px = 0.3;        //!< pixel noise of the observed corners (px)
  double sigma_odom_rel = 0.02; //!< odometry: relative noise of the measured v and omega per period
  double sigma_pan = 0.0005;    //!< noise of each pan reading (rad)
  std::uint64_t seed = 1;       //!< noise seed
  CameraModel camera = defaultCamera(); //!< needs an image size
  YawRig rig = YawRig(Eigen::Vector3d(0.0, 0.0, 0.03)); //!< the robot's yaw mechanism
  double axle_to_yaw = 0.2;     //!< yaw axis ahead of the wheel axle (m)
  DepthProviderOptions provider; //!< Estimated mode
  YawHelperOptions helper;       //!< yaw helper options (when `yaw_helper`)
  /*! \brief 640x480, 600 px focal length, mild barrel distortion (k1 = -0.05). */
  static CameraModel defaultCamera();
};

/*! \brief One control period of the run. */
struct ServoSimStep {
  int iteration = 0;                   //!< control iteration (0-based)
  double time = 0;                     //!< time since the start (s)
  double error_px = 0;                 //!< true mean corner distance to the desired corners (px)
  std::vector<Eigen::Vector2d> pixels; //!< true (noise-free) observed corners (px)
  /*! per corner: true depth (m) */
  std::vector<double> true_Z, used_Z, sigma_Z; //!< per corner: 1-sigma of used_Z (provider's, 0 otherwise)
  /*!
    \var used_Z
    per corner: depth given to the control law (m)
  */
  std::vector<bool> converged;         //!< per corner: estimate in use (Estimated mode)
  std::vector<Status> status;          //!< per corner: the estimator's status (Estimated mode)
  std::vector<double> estimate_Z;      //!< per corner: the estimate, converged or not (NaN if none)
  double yaw_helper_rate = 0;          //!< secondary task's requested pan rate (rad/s)
  MotionSample robot;                  //!< true pose of the vision frame and pan
  vpColVector qdot;                    //!< applied joint rates (v, omega, pan rate)
};

/*! \brief Outcome of a run. */
struct ServoSimResult {
  bool converged = false;      //!< the error fell below tolerance_px
  int iterations = 0;          //!< control iterations run
  double final_error_px = 0;   //!< true mean corner error at the end (px)
  std::string reason;          //!< "converged", "max_iterations", "lost_features", "not_finite"
  std::vector<Eigen::Vector2d> desired_pixels; //!< the corners at the goal (px)
  std::vector<ServoSimStep> steps;             //!< every control period
};

/*! \brief Run the servo (see the file). `on_step` (optional) is called after each period. Throws yawdepth::Error for bad options. */
ServoSimResult runServoSimulation(const ServoSimOptions &options,
                                  const std::function<void(const ServoSimStep &)> &on_step = nullptr);

} // namespace yawdepth
