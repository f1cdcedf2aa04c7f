#pragma once
/*!
  \file servo_sim.h
  \brief The simulated world of examples/servo_ibvs_yawing_camera: a mobile robot with a yawing
  (pan) camera, a tag's four corners seen with pixel noise, and the run's options and record. Not
  part of the library (not installed): the servo loop itself, what a user writes, is in
  examples/servo_ibvs_yawing_camera.cpp (runServoSimulation()), which tests/test_servo.cpp and
  examples/servo_table.sh run too.

  Robot (`UnicyclePanRobot`): a unicycle (forward speed v, turn rate omega about +Y, down) whose
  pan (yaw) axis sits `axle_to_yaw` m ahead of the wheel axle, and a camera whose optical centre
  is at `rig.cameraOffset()` from the yaw axis (yawdepth::YawRig). Frames use the camera
  convention (X right, Y down, Z forward); the world is the robot's ground plane, Y = 0. Its
  camera-frame Jacobian `cJq` maps the joint rates (v, omega, pan rate) to the camera's twist
  (vx, vy, vz, wx, wy, wz): with the yaw axis off the axle, omega also moves the camera sideways,
  so the three joints control the camera's planar pose (X, Z, yaw) fully.

  Scene (`TagScene`): the tag's corners, the goal camera `desired_depth` in front of it, and the
  robot's start (front view: behind the goal on the robot's path; side view: the pan at 90 degrees,
  the robot drives past the tag). Depth of each feature (`ServoDepthMode`): `True` the true depth,
  `Constant` desired depth x (1 + constant_error) for every feature, `Estimated` a
  yawdepth::DepthProvider fed with the robot's dead-reckoned odometry (velocity noise) and pan
  readings (noise). Convergence: the true mean corner distance to the desired corners below
  `tolerance_px`.
*/
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>
#include <Eigen/Core>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpMatrix.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/servo/depth_provider.h>
#include <yawdepth/servo/yaw_helper.h>

/*! \brief The example's simulation (examples/servo_sim/): not the library's API. */
namespace servo_sim {

/*! \brief Unicycle robot with a pan camera (see the file). State: wheel-axle centre (x, z), heading, pan. */
struct UnicyclePanRobot {
  double axle_to_yaw = 0.2; //!< yaw axis ahead of the wheel axle (m)
  yawdepth::YawRig rig;     //!< optical centre offset from the yaw axis
  /*! wheel-axle centre in the world: X (m) */
  double x = 0, z = 0;      //!< wheel-axle centre in the world: Z (m)
  double heading = 0;       //!< about +Y (rad)
  double pan = 0;           //!< camera yaw relative to the robot (rad)

  /*! \brief The vision frame's pose (at the yaw axis) and the pan, as a motion-log row. */
  yawdepth::MotionSample sample(long frame = 0) const;
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
  yawdepth::CameraModel camera = defaultCamera(); //!< needs an image size
  yawdepth::YawRig rig = yawdepth::YawRig(Eigen::Vector3d(0.0, 0.0, 0.03)); //!< the robot's yaw mechanism
  double axle_to_yaw = 0.2;     //!< yaw axis ahead of the wheel axle (m)
  yawdepth::DepthProviderOptions provider; //!< Estimated mode
  yawdepth::YawHelperOptions helper;       //!< yaw helper options (when `yaw_helper`)
  /*! \brief 640x480, 600 px focal length, mild barrel distortion (k1 = -0.05). */
  static yawdepth::CameraModel defaultCamera();
  /*! \brief Throws yawdepth::Error for options the run cannot take. */
  void validate() const;
};

/*! \brief The seeded noise of a run: one generator and one standard normal draw for every noise. */
class Noise {
public:
  /*! \brief Seeded generator. */
  explicit Noise(std::uint64_t seed) : rng_(seed) {}
  /*! \brief One standard normal draw. */
  double operator()() { return N01_(rng_); }

private:
  std::mt19937_64 rng_;
  std::normal_distribution<double> N01_{0.0, 1.0};
};

/*! \brief What the camera sees of the tag in one period. */
struct CornerView {
  std::vector<std::pair<long, vpImagePoint>> observed; //!< (corner id, noisy pixel), as a tracker gives them
  std::vector<Eigen::Vector2d> pixels;                 //!< true (noise-free) pixels; NaN behind the camera
  std::vector<double> true_Z;                          //!< true depth of each corner in front of the camera (m)
  bool lost = false;                                   //!< a corner is behind the camera or out of the image
};

/*! \brief The tag, the goal and the robot's start (see the file). */
struct TagScene {
  std::vector<long> ids;               //!< corner ids 1..4 (bottom-left, bottom-right, top-right, top-left)
  std::vector<Eigen::Vector3d> w_P;    //!< corners in the world (m): the tag's centre at the origin, facing -Z
  vpHomogeneousMatrix wMcd;            //!< goal camera pose: desired_depth in front of the tag, facing it
  UnicyclePanRobot start;              //!< robot at the start, its pan aimed near the tag
  yawdepth::CameraModel camera;        //!< the robot's camera
  double sigma_px = 0;                 //!< pixel noise of the observed corners (px)

  /*! \brief The scene of the options (validated). */
  explicit TagScene(const ServoSimOptions &o);
  /*! \brief Corner i in the camera frame of pose wMc (m). */
  Eigen::Vector3d cameraPoint(const vpHomogeneousMatrix &wMc, std::size_t i) const;
  /*! \brief The corners from the robot's camera: true projection, then pixel noise. */
  CornerView observe(const UnicyclePanRobot &robot, Noise &noise) const;
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
  std::vector<yawdepth::Status> status; //!< per corner: the estimator's status (Estimated mode)
  std::vector<double> estimate_Z;      //!< per corner: the estimate, converged or not (NaN if none)
  double yaw_helper_rate = 0;          //!< secondary task's requested pan rate (rad/s)
  yawdepth::MotionSample robot;        //!< true pose of the vision frame and pan
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

/*!
  \brief Run the servo: the loop of examples/servo_ibvs_yawing_camera.cpp, which defines it (see
  there). `on_step` (optional) is called after each period. Throws yawdepth::Error for bad options.
*/
ServoSimResult runServoSimulation(const ServoSimOptions &options,
                                  const std::function<void(const ServoSimStep &)> &on_step = nullptr);

/*! \brief A PNG of a run: the corners' image trajectories and the depths over time. Prints to stderr if it cannot write. */
void writePlot(const std::string &path, const ServoSimOptions &o, const ServoSimResult &r);

} // namespace servo_sim
