/*
  servo_pioneer_pan: image-based visual servoing of ViSP's Pioneer with a pan head
  (vpSimulatorPioneerPan: three joints, the forward speed v, the turn rate wz and the pan rate) on the
  four corners of a 0.2 m square, as a ViSP user writes it: vpServo EYEINHAND_L_cVe_eJe, interaction
  matrix CURRENT, lambda 0.6, 40 ms period, a 640x480 camera with a 600 px focal length, the goal
  0.6 m in front of the square. Each feature's depth Z from
    --depth true       the true depth,
    --depth constant   the desired depth 0.6 m x (1 + --constant-error) for every feature,
    --depth estimated  yawdepth::DepthProvider with its default options, fed with the robot's
                       odometry (x, y, theta integrated from the measured v and wz) and pan reading
                       through yawdepth::pioneerPanOdometry(), and the noisy pixels.

  --pose-api gives the provider the same odometry as a pose (DepthProvider::update(wMv, points, q),
  the 6-DoF entry point) instead of a planar MotionSample.

  --scenario front: the square 1.4 m ahead, 0.15 m to the left, turned 15 degrees, the pan at 0.
  --scenario side:  the pan turned 60 degrees to the right, the square 1.1 m along the camera's axis
                    (the robot drives at 60 degrees to the line of sight: a side view).
  Noise (every depth mode servoes on the same noisy pixels): --sigma-px pixel noise (0.3 px), the
  odometry's v and wz each off by a relative --odom-noise (2 %) per period, --pan-noise (0.05 deg)
  on each pan reading; --seed draws it. The run stops when the true mean corner error is under
  0.5 px (converged), when a corner leaves the image or the square is behind the camera (diverged),
  or after --max-iterations.

  The last line is the same as servo_ibvs_4pts's:
    converged iterations=N final_error=E      (E: true mean corner error in pixels)
  or  diverged iterations=N final_error=E reason=R
  and the line before it gives the camera's path length, the depth error at the end and its sign, and
  the first iteration at which the provider used each corner's estimate (-1: never, or not estimated)
  and how often its convergence was revoked (DepthProviderOptions::revoke_sigmas):
    path_length=L depth_error=D depth_bias=B converged_at=I0,I1,I2,I3 revocations=R
                                              (L in m; D: mean |Z used - Z true| / Z true;
                                               B: mean (Z used - Z true) / Z true)
*/
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpMath.h>
#include <visp3/core/vpPoint.h>
#include <visp3/robot/vpSimulatorPioneerPan.h>
#include <visp3/visual_features/vpFeatureBuilder.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>

#include <yawdepth/servo/depth_provider.h>
#include <yawdepth/servo/pioneer_pan.h>

#include "servo_sim/servo_example.h" // the command line, the square, the observation, the printed lines

namespace {

// The usage lines (on stdout, as --help prints them).
void usage()
{
  std::printf("usage: servo_pioneer_pan [--depth true|constant|estimated] [--scenario front|side]\n"
              "       [--constant-error E] [--seed N] [--sigma-px S] [--odom-noise R] [--pan-noise DEG]\n"
              "       [--max-iterations N] [--pose-api] [--quiet] [--verbose]\n");
}

// The options: the shared ones (servo_example.h) and the Pioneer's.
struct Args : servo_sim::PointServoArgs {
  std::string scenario = "front";
  double odom_noise = 0.02, pan_noise_deg = 0.05;
  bool pose_api = false; // DepthProvider::update(wMv, points, yaw) instead of update(MotionSample, points)
  Args() { max_iterations = 3000; }
};

// Reads the command line (exits with 2 on one the example cannot take, with 0 after --help).
Args parse(int argc, char **argv)
{
  Args a;
  servo_sim::readOptions(argc, argv, "servo_pioneer_pan", usage,
                         [&](const std::string &o, const servo_sim::NextValue &next) {
                           if (o == "--scenario") {
                             a.scenario = next();
                             if (a.scenario != "front" && a.scenario != "side")
                               throw std::runtime_error("--scenario: front or side");
                           } else if (o == "--odom-noise")
                             a.odom_noise = std::stod(next());
                           else if (o == "--pan-noise")
                             a.pan_noise_deg = std::stod(next());
                           else if (o == "--pose-api")
                             a.pose_api = true;
                           else
                             return servo_sim::readPointServoOption(o, next, a);
                           return true;
                         });
  if (!(a.sigma_px >= 0.0) || !(a.odom_noise >= 0.0) || !(a.pan_noise_deg >= 0.0) || !(a.constant_error > -1.0) ||
      a.max_iterations <= 0)
    servo_sim::exitWithUsage("servo_pioneer_pan", "noise levels >= 0, --constant-error > -1 and --max-iterations > 0",
                             usage);
  return a;
}

// The world: the camera, the square, the goal 0.6 m in front of it, the control period.
struct Scene {
  const vpCameraParameters cam = vpCameraParameters(600, 600, 320, 240);
  const unsigned width = 640, height = 480;
  const double dt = 0.040;
  const vpHomogeneousMatrix cdMo = vpHomogeneousMatrix(0, 0, 0.6, 0, 0, 0);
  vpPoint point[4];
  vpImagePoint desired[4]; // the corners' pixels at the goal
  Scene() { servo_sim::setSquare(point); }
};

// Turns the pan to q0 (the robot stays at the world origin): one period of pan velocity.
void setPan(vpSimulatorPioneerPan &robot, double q0, double dt)
{
  vpColVector q(3, 0.0);
  q[2] = q0 / dt; // one period of pan velocity brings the pan to q0
  robot.setMaxRotationVelocity(q[2] + 1.0);
  robot.setVelocity(vpRobot::ARTICULAR_FRAME, q); // within the limits: nothing printed
  robot.setMaxRotationVelocity(vpMath::rad(90));
}

// What the robot will do with the joint velocities v (its velocity limits, a hair inside so that
// the simulator does not saturate again), so that the odometry integrates the same.
vpColVector saturateAsRobot(const vpSimulatorPioneerPan &robot, const vpColVector &v)
{
  vpColVector v_max(3);
  v_max[0] = robot.getMaxTranslationVelocity() * (1 - 1e-9);
  v_max[1] = v_max[2] = robot.getMaxRotationVelocity() * (1 - 1e-9);
  return vpRobot::saturateVelocities(v, v_max, false);
}

// Odometry: the platform's pose integrated from the measured wheel speeds.
struct Odometry {
  double x = 0.0, y = 0.0, theta = 0.0;
  // One period at the forward speed v[0] and turn rate v[1], each measured off by a relative
  // `noise` x gauss() (drawn in that order).
  template <class Gauss>
  void integrate(const vpColVector &v, double noise, Gauss &&gauss, double dt)
  {
    const double v_meas = v[0] * (1.0 + noise * gauss());
    const double w_meas = v[1] * (1.0 + noise * gauss());
    x += dt * v_meas * std::cos(theta);
    y += dt * v_meas * std::sin(theta);
    theta += dt * w_meas;
  }
};

// How a run went: what the line before the last reports.
struct Run : servo_sim::PointServoRun {
  int converged_at[4] = {-1, -1, -1, -1}; // first iteration at which the provider used each corner's estimate
};

// The servo loop: observe the corners, give the provider the odometry and the pan reading, set
// each feature's Z, compute the control law, move the robot, integrate its odometry.
Run servo(const Args &args, Scene &scene, vpServo &task, vpFeaturePoint (&p)[4], vpSimulatorPioneerPan &robot,
          const vpHomogeneousMatrix &wMo, double q0, yawdepth::DepthProvider &provider)
{
  std::mt19937 rng(1000003u * args.seed + 17u);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Odometry odo; // 2 % off per period by default
  double q_true = q0;
  Run run;
  vpHomogeneousMatrix wMc;
  robot.getPosition(wMc);
  run.start(wMc);
  vpPoint(&point)[4] = scene.point;
  vpMatrix eJe;
  for (; run.iterations < args.max_iterations; ++run.iterations) {
    robot.getPosition(wMc);
    const vpHomogeneousMatrix cMo = wMc.inverse() * wMo;
    run.moveTo(wMc);

    // Observe: the true projection, then pixel noise.
    const servo_sim::SquareView view = servo_sim::observeSquare(
        point, cMo, scene.cam, scene.width, scene.height, scene.desired, [&] { return args.sigma_px * gauss(rng); });
    if (run.ends(view))
      break;

    // The features: x, y from the noisy pixels, Z from the chosen source.
    if (args.depth_mode == "estimated") {
      const double q_read = q_true + vpMath::rad(args.pan_noise_deg) * gauss(rng);
      const yawdepth::MotionSample odometry = yawdepth::pioneerPanOdometry(odo.x, odo.y, odo.theta, q_read);
      if (args.pose_api) // the same odometry as a pose (vision frame in the odometry world) and the pan reading
        provider.update(yawdepth::wMv(odometry), view.observed, q_read);
      else
        provider.update(odometry, view.observed);
    }
    run.clearDepthErrors();
    for (unsigned i = 0; i < 4; i++) {
      const vpImagePoint &ip = view.observed[i].second;
      if (args.depth_mode == "estimated") {
        provider.buildFrom(i, ip, p[i]); // x, y undistorted, Z the provider's depth
        if (run.converged_at[i] < 0 && provider.converged(i))
          run.converged_at[i] = run.iterations;
      } else {
        vpFeatureBuilder::create(p[i], scene.cam, ip);
        p[i].set_Z(args.depth_mode == "constant" ? scene.cdMo[2][3] * (1.0 + args.constant_error) : point[i].get_Z());
      }
      run.addDepth(p[i].get_Z(), point[i].get_Z());
    }
    robot.get_eJe(eJe);
    task.set_eJe(eJe);
    const vpColVector v = saturateAsRobot(robot, task.computeControlLaw());
    robot.setVelocity(vpRobot::ARTICULAR_FRAME, v);
    servo_sim::printProgress(args, run, view.error, p, point, provider);
    odo.integrate(v, args.odom_noise, [&] { return gauss(rng); }, scene.dt);
    q_true += scene.dt * v[2];
  }
  return run;
}

} // namespace

int main(int argc, char **argv)
{
  const Args args = parse(argc, argv);
  Scene scene;

  // The robot starts at the world origin, the pan at q0; the square is placed relative to the camera.
  vpSimulatorPioneerPan robot;
  robot.setSamplingTime(scene.dt);
  const bool side = args.scenario == "side";
  const double q0 = side ? vpMath::rad(60) : 0.0;
  setPan(robot, q0, scene.dt);
  const vpHomogeneousMatrix cMo_start = side ? vpHomogeneousMatrix(0.10, 0, 1.1, 0, vpMath::rad(-25), 0)
                                             : vpHomogeneousMatrix(-0.15, 0, 1.4, 0, vpMath::rad(15), 0);
  vpHomogeneousMatrix wMc;
  robot.getPosition(wMc);
  const vpHomogeneousMatrix wMo = wMc * cMo_start;

  vpServo task;
  task.setServo(vpServo::EYEINHAND_L_cVe_eJe);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(0.6);
  task.set_cVe(robot.get_cVe());
  vpMatrix eJe;
  robot.get_eJe(eJe);
  task.set_eJe(eJe);

  vpFeaturePoint p[4], pd[4];
  servo_sim::addSquareFeatures(task, scene.point, scene.cam, scene.cdMo, cMo_start, p, pd, scene.desired);

  // The depth estimator, default options, the Pioneer's rig.
  yawdepth::DepthProvider provider(scene.cam, yawdepth::pioneerPanRig());

  if (!args.quiet)
    std::printf("servo: depth=%s scenario=%s seed=%u sigma_px=%.2f\n", args.depth_mode.c_str(), args.scenario.c_str(),
                args.seed, args.sigma_px);
  const Run run = servo(args, scene, task, p, robot, wMo, q0, provider);
  long revocations = 0;
  for (unsigned i = 0; i < 4; i++)
    revocations += provider.info(i).revocations;
  std::printf("path_length=%.4f depth_error=%.4f depth_bias=%+.4f converged_at=%d,%d,%d,%d revocations=%ld\n",
              run.path_length, run.depth_error, run.depth_bias, run.converged_at[0], run.converged_at[1],
              run.converged_at[2], run.converged_at[3], revocations);
  return servo_sim::printOutcome(run.converged, run.iterations, run.final_error, run.reason);
}
