/*
  servo_ibvs_4pts: ViSP's classic image-based visual servo on four points (tutorial-ibvs-4pts.cpp:
  vpSimulatorCamera, a free-flying camera; vpServo EYEINHAND_CAMERA, interaction matrix CURRENT,
  lambda 0.5, 40 ms period; a 0.2 m square; the goal 0.75 m in front of it) with each feature's
  depth Z from
    --depth true       the true depth (what vpFeatureBuilder::create(p, point) sets in the tutorial),
    --depth constant   the desired depth 0.75 m x (1 + --constant-error) for every feature,
    --depth estimated  yawdepth::DepthProvider with its default options: the depth from the camera's
                       pose (vpSimulatorCamera::getPosition(), the vision frame = the camera) and the
                       image motion of the noisy pixels.

  The loop is the tutorial's, written as a ViSP user would write it; what differs from the tutorial:
  the corners are observed with --sigma-px pixel noise (0.3 px; every depth mode servoes on the same
  noisy pixels), the camera is 640x480 with a 600 px focal length, and the run stops when the true
  mean corner error is under 0.5 px (converged) or after --max-iterations, or when a corner leaves
  the image (diverged). --pose 0 (the default) is the tutorial's starting pose; --pose N draws one
  from N (0.5 to 1.6 m from the square, up to 0.25 m off its axis, tilted up to 20 degrees, turned
  up to 80 degrees about the optical axis, the square at least 40 px inside the image). --seed
  draws the pixel noise.

  The last line is the same as servo_ibvs_yawing_camera's:
    converged iterations=N final_error=E      (E: true mean corner error in pixels)
  or  diverged iterations=N final_error=E reason=R
  and the line before it gives the camera's path length and the depth error at the end:
    path_length=L depth_error=D               (L in m; D: mean |Z used - Z true| / Z true)
*/
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpMath.h>
#include <visp3/core/vpMeterPixelConversion.h>
#include <visp3/core/vpPoint.h>
#include <visp3/robot/vpSimulatorCamera.h>
#include <visp3/visual_features/vpFeatureBuilder.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>

#include <yawdepth/servo/depth_provider.h>

#include "servo_sim/servo_example.h" // the command line, the square, the observation, the printed lines

namespace {

// The usage lines (on stdout, as --help prints them).
void usage()
{
  std::printf("usage: servo_ibvs_4pts [--depth true|constant|estimated] [--constant-error E]\n"
              "       [--pose N] [--seed N] [--sigma-px S] [--max-iterations N] [--quiet] [--verbose]\n");
}

// The options: the shared ones (servo_example.h) and the starting pose.
struct Args : servo_sim::PointServoArgs {
  unsigned pose = 0;
  Args() { max_iterations = 2000; }
};

// Reads the command line (exits with 2 on one the example cannot take, with 0 after --help).
Args parse(int argc, char **argv)
{
  Args a;
  servo_sim::readOptions(argc, argv, "servo_ibvs_4pts", usage,
                         [&](const std::string &o, const servo_sim::NextValue &next) {
                           if (o != "--pose")
                             return servo_sim::readPointServoOption(o, next, a);
                           a.pose = static_cast<unsigned>(std::stoul(next()));
                           return true;
                         });
  if (!(a.sigma_px >= 0.0) || !(a.constant_error > -1.0) || a.max_iterations <= 0)
    servo_sim::exitWithUsage("servo_ibvs_4pts", "--sigma-px >= 0, --constant-error > -1 and --max-iterations > 0",
                             usage);
  return a;
}

// The starting pose of the camera relative to the square (cMo): 0 is the tutorial's, N > 0 a random
// one drawn from N, redrawn until the square is well inside the image.
vpHomogeneousMatrix startPose(unsigned pose, const vpCameraParameters &cam, unsigned width, unsigned height,
                              const vpPoint (&square)[4])
{
  if (pose == 0)
    return vpHomogeneousMatrix(0.15, -0.1, 1., vpMath::rad(10), vpMath::rad(-10), vpMath::rad(50));
  std::mt19937 rng(pose);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (;;) {
    const double Z = 0.5 + 0.55 * (U(rng) + 1.0); // 0.5 .. 1.6 m
    const vpHomogeneousMatrix cMo(0.25 * U(rng), 0.25 * U(rng), Z, vpMath::rad(20 * U(rng)), vpMath::rad(20 * U(rng)),
                                  vpMath::rad(80 * U(rng)));
    bool inside = true;
    for (vpPoint p : square) {
      p.track(cMo);
      vpImagePoint ip;
      vpMeterPixelConversion::convertPoint(cam, p.get_x(), p.get_y(), ip);
      inside = inside && p.get_Z() > 0 && ip.get_u() > 40 && ip.get_v() > 40 && ip.get_u() < width - 40 &&
               ip.get_v() < height - 40;
    }
    if (inside)
      return cMo;
  }
}

// The tutorial's world: the camera, the square and the goal 0.75 m in front of it.
struct Scene {
  const vpCameraParameters cam = vpCameraParameters(600, 600, 320, 240);
  const unsigned width = 640, height = 480;
  const vpHomogeneousMatrix cdMo = vpHomogeneousMatrix(0, 0, 0.75, 0, 0, 0);
  vpPoint point[4];
  vpImagePoint desired[4]; // the corners' pixels at the goal
  Scene() { servo_sim::setSquare(point); }
};

// The servo loop: observe the corners, give the provider the camera's pose and the pixels, set
// each feature's Z, compute the control law, move the camera.
servo_sim::PointServoRun servo(const Args &args, Scene &scene, vpServo &task, vpFeaturePoint (&p)[4],
                               vpSimulatorCamera &robot, const vpHomogeneousMatrix &wMo,
                               yawdepth::DepthProvider &provider)
{
  std::mt19937 rng(1000003u * args.seed + 17u);
  std::normal_distribution<double> noise(0.0, args.sigma_px);
  servo_sim::PointServoRun run;
  vpHomogeneousMatrix wMc;
  robot.getPosition(wMc);
  run.start(wMc);
  vpPoint(&point)[4] = scene.point;
  for (; run.iterations < args.max_iterations; ++run.iterations) {
    robot.getPosition(wMc);
    const vpHomogeneousMatrix cMo = wMc.inverse() * wMo;
    run.moveTo(wMc);

    // Observe: the true projection, then pixel noise.
    const servo_sim::SquareView view = servo_sim::observeSquare(point, cMo, scene.cam, scene.width, scene.height,
                                                                scene.desired, [&] { return noise(rng); });
    if (run.ends(view))
      break;

    // The features: x, y from the noisy pixels, Z from the chosen source.
    if (args.depth_mode == "estimated")
      provider.update(wMc, view.observed);
    run.clearDepthErrors();
    for (unsigned i = 0; i < 4; i++) {
      const vpImagePoint &ip = view.observed[i].second;
      if (args.depth_mode == "estimated")
        provider.buildFrom(i, ip, p[i]); // x, y undistorted, Z the provider's depth
      else {
        vpFeatureBuilder::create(p[i], scene.cam, ip);
        p[i].set_Z(args.depth_mode == "constant" ? scene.cdMo[2][3] * (1.0 + args.constant_error) : point[i].get_Z());
      }
      run.addDepth(p[i].get_Z(), point[i].get_Z());
    }
    vpColVector v = task.computeControlLaw();
    robot.setVelocity(vpRobot::CAMERA_FRAME, v);
    servo_sim::printProgress(args, run, view.error, p, point, provider);
  }
  return run;
}

} // namespace

int main(int argc, char **argv)
{
  const Args args = parse(argc, argv);

  // The square, and the camera's start (the tutorial's, or a random one).
  Scene scene;
  const vpHomogeneousMatrix cMo = startPose(args.pose, scene.cam, scene.width, scene.height, scene.point);

  vpServo task;
  task.setServo(vpServo::EYEINHAND_CAMERA);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(0.5);

  vpFeaturePoint p[4], pd[4];
  servo_sim::addSquareFeatures(task, scene.point, scene.cam, scene.cdMo, cMo, p, pd, scene.desired);

  vpHomogeneousMatrix wMc;
  vpSimulatorCamera robot;
  robot.setSamplingTime(0.040);
  robot.getPosition(wMc);
  const vpHomogeneousMatrix wMo = wMc * cMo;

  // The depth estimator: the camera is the vision frame (identity camera_pose), default options.
  yawdepth::DepthProvider provider(scene.cam, yawdepth::YawRig(vpHomogeneousMatrix()));

  if (!args.quiet)
    std::printf("servo: depth=%s pose=%u seed=%u sigma_px=%.2f\n", args.depth_mode.c_str(), args.pose, args.seed,
                args.sigma_px);
  const servo_sim::PointServoRun run = servo(args, scene, task, p, robot, wMo, provider);
  std::printf("path_length=%.4f depth_error=%.4f\n", run.path_length, run.depth_error);
  return servo_sim::printOutcome(run.converged, run.iterations, run.final_error, run.reason);
}
