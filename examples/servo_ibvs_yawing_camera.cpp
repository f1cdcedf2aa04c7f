/*
  servo_ibvs_yawing_camera: image-based visual servoing of a mobile robot with a yawing (pan)
  camera on the four corners of a tag, with each feature's depth Z from
    --depth true       the true depth (what a depth sensor would give),
    --depth constant   desired depth x (1 + --constant-error) for every feature (ViSP's usual guess),
    --depth estimated  yawdepth::DepthProvider: the depth from the robot's odometry and the image
                       motion, the prior (1 m) until each feature's estimate has converged.

  The robot: a unicycle (v, omega) with the pan axis 0.2 m ahead of the wheel axle and the camera
  3 cm ahead of the pan axis; the servo drives (v, omega, pan rate) with vpServo
  (EYEINHAND_L_cVe_eJe, interaction matrix CURRENT: the current depths are what the estimate
  changes). --view front: the robot drives toward the tag (camera along the motion: depth poorly
  observed); --view side: the camera panned 90 degrees, the robot drives past the tag. Odometry
  (dead-reckoned, 2 % velocity noise), pan readings (0.03 deg) and corner pixels (0.3 px) are noisy.
  --yaw-helper adds yawdepth::recommendYawRate() as a secondary task (ViSP's large projection
  operator) while some depth has not converged.

  The servo loop is written here (runServoSimulation()), as ViSP's tutorials write theirs
  (tutorial-ibvs-4pts, servoSimuPoint2DCamVelocity): the desired and current vpFeaturePoint's, the
  vpServo task, and each period: observe the corners, give the DepthProvider the odometry and the
  pan reading, set each feature's Z, compute the control law, saturate it, move the robot. The
  simulated world (the robot's kinematics, the tag, the noise, the PNG) is in servo_sim/, beside
  this file; tests/test_servo.cpp and servo_table.sh run this same loop (the test compiles this file
  without its main: servo_sim/CMakeLists.txt).

  Writes a PNG only when asked (--png FILE; nothing by default): the corners' image trajectories and
  the depths over time. --display opens a ViSP window. The last line is
    converged iterations=N final_error=E      (E: true mean corner error in pixels)
  or  diverged iterations=N final_error=E reason=R
*/
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpVelocityTwistMatrix.h>
#include <visp3/gui/vpDisplayOpenCV.h>
#include <visp3/gui/vpDisplayX.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>

#include <yawdepth/servo/depth_provider.h>
#include <yawdepth/servo/yaw_helper.h>

#include "servo_sim/servo_example.h" // the command line and the last line, as the other servo examples
#include "servo_sim/servo_sim.h"

namespace servo_sim {

namespace {

// The task: the desired features sd (the corners seen from the goal, their pixels into
// desired_pixels), each with its current feature in s; the three joints (v, omega, pan rate) move
// the camera through eJe = the robot's Jacobian cJq (cVe = identity); the interaction matrix of the
// current features, whose depths are what the provider sets.
void setUpTask(vpServo &task, const TagScene &scene, double lambda, std::vector<vpFeaturePoint> &s,
               std::vector<vpFeaturePoint> &sd, std::vector<Eigen::Vector2d> &desired_pixels)
{
  const vpHomogeneousMatrix cdMw = scene.wMcd.inverse();
  for (std::size_t i = 0; i < sd.size(); ++i) {
    const Eigen::Vector3d P = scene.cameraPoint(cdMw, i);
    sd[i].buildFrom(P.x() / P.z(), P.y() / P.z(), P.z());
    desired_pixels.push_back(scene.camera.project(Eigen::Vector2d(P.x() / P.z(), P.y() / P.z())));
  }
  task.setServo(vpServo::EYEINHAND_L_cVe_eJe);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(lambda);
  task.set_cVe(vpVelocityTwistMatrix());
  for (std::size_t i = 0; i < s.size(); ++i)
    task.addFeature(s[i], sd[i]);
}

// The record of period k as observed: time, the robot's true pose, the corners' true pixels and
// depths, and their mean distance to the desired pixels.
ServoSimStep startStep(int k, double dt, const UnicyclePanRobot &robot, const CornerView &view,
                       const std::vector<Eigen::Vector2d> &desired_pixels)
{
  ServoSimStep st;
  st.iteration = k;
  st.time = k * dt;
  st.robot = robot.sample(k);
  st.pixels = view.pixels;
  st.true_Z = view.true_Z;
  double err = 0;
  for (std::size_t i = 0; i < desired_pixels.size(); ++i)
    err += (st.pixels[i] - desired_pixels[i]).norm();
  st.error_px = err / desired_pixels.size();
  return st;
}

// One feature's depth Z from the chosen source, and what the provider says of it (Estimated mode).
struct DepthChoice {
  double Z = 1.0, sigma = 0, estimate = std::numeric_limits<double>::quiet_NaN();
  bool converged = false;
  yawdepth::Status status = yawdepth::Status::TooFewFrames;
};

// The depth of feature `id` (true depth true_Z) as the options' depth mode gives it.
DepthChoice chooseDepth(const ServoSimOptions &o, const yawdepth::DepthProvider &provider, long id, double true_Z)
{
  DepthChoice d;
  switch (o.depth) {
  case ServoDepthMode::True:
    d.Z = true_Z;
    break;
  case ServoDepthMode::Constant:
    d.Z = o.desired_depth * (1.0 + o.constant_error);
    break;
  case ServoDepthMode::Estimated: {
    const yawdepth::FeatureDepth f = provider.info(id);
    d.Z = f.depth;
    d.sigma = f.sigma;
    d.converged = f.converged;
    d.status = f.status;
    d.estimate = f.estimate;
    break;
  }
  }
  return d;
}

// Each feature: x, y from the observed pixel, Z from the chosen source; the depths into the record.
void setFeatures(const ServoSimOptions &o, const TagScene &scene, const CornerView &view,
                 const yawdepth::DepthProvider &provider, std::vector<vpFeaturePoint> &s, ServoSimStep &st)
{
  for (std::size_t i = 0; i < s.size(); ++i) {
    const DepthChoice d = chooseDepth(o, provider, scene.ids[i], view.true_Z[i]);
    double x = 0, y = 0;
    o.camera.pixelToMeter(view.observed[i].second, x, y);
    s[i].buildFrom(x, y, d.Z);
    st.used_Z.push_back(d.Z);
    st.sigma_Z.push_back(d.sigma);
    st.converged.push_back(d.converged);
    st.status.push_back(d.status);
    st.estimate_Z.push_back(d.estimate);
  }
}

// The yaw helper's pan rate (recommendYawRate() on the features whose depth has not converged);
// false, and `rate` untouched, when every depth has converged.
bool yawHelperRate(const ServoSimOptions &o, const std::vector<vpFeaturePoint> &s, const std::vector<bool> &converged,
                   double yaw, const Eigen::Vector3d &vision_velocity, double &rate)
{
  std::vector<yawdepth::YawHelperFeature> hf;
  bool any = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    yawdepth::YawHelperFeature f;
    f.x = s[i].get_x();
    f.y = s[i].get_y();
    f.Z = s[i].get_Z();
    f.weight = converged[i] ? 0.0 : 1.0;
    any = any || !converged[i];
    hf.push_back(f);
  }
  if (!any)
    return false;
  rate = yawdepth::recommendYawRate(o.camera, o.rig, yaw, vision_velocity, hf, o.helper).rate;
  return true;
}

// Saturation: every joint rate scaled by the same factor until each is within its limit.
void saturate(vpColVector &qdot, const ServoSimOptions &o)
{
  const double scale = std::max({1.0, std::abs(qdot[0]) / o.max_v, std::abs(qdot[1]) / o.max_omega,
                                 std::abs(qdot[2]) / o.max_pan_rate});
  qdot /= scale;
}

// Moves the robot by qdot over one period; its wheel odometry measures v and omega with noise.
void moveRobot(UnicyclePanRobot &robot, UnicyclePanRobot &odometry, const vpColVector &qdot, const ServoSimOptions &o,
               Noise &noise)
{
  robot.step(qdot, o.dt);
  vpColVector measured_rates = qdot;
  measured_rates[0] *= 1.0 + o.sigma_odom_rel * noise();
  measured_rates[1] *= 1.0 + o.sigma_odom_rel * noise();
  odometry.step(measured_rates, o.dt);
}

// Keeps period st in the result, then gives it to on_step.
void keepStep(ServoSimResult &result, const ServoSimStep &st, const std::function<void(const ServoSimStep &)> &on_step)
{
  result.steps.push_back(st);
  if (on_step)
    on_step(result.steps.back());
}

} // namespace

ServoSimResult runServoSimulation(const ServoSimOptions &o, const std::function<void(const ServoSimStep &)> &on_step)
{
  // The simulated world: the tag, the goal and the robot at its start. The robot's odometry
  // dead-reckons from the same start.
  const TagScene scene(o);
  const std::size_t n = scene.ids.size();
  UnicyclePanRobot robot = scene.start;
  UnicyclePanRobot odometry = robot;
  Noise noise(o.seed);

  ServoSimResult result;
  std::vector<vpFeaturePoint> s(n), sd(n);
  vpServo task;
  setUpTask(task, scene, o.lambda, s, sd, result.desired_pixels);
  yawdepth::DepthProvider provider(o.camera, o.rig, o.provider);

  vpColVector qdot(3, 0.0);
  result.reason = "max_iterations";
  for (int k = 0; k <= o.max_iterations; ++k) {
    // Observe the corners: (id, pixel) as a tracker gives them, and the truth for the record.
    const CornerView view = scene.observe(robot, noise);
    ServoSimStep st = startStep(k, o.dt, robot, view, result.desired_pixels);
    result.final_error_px = st.error_px;
    result.iterations = k;
    if (view.lost || !std::isfinite(st.error_px)) {
      result.reason = view.lost ? "lost_features" : "not_finite";
      break;
    }
    if (st.error_px < o.tolerance_px) {
      result.converged = true;
      result.reason = "converged";
      keepStep(result, st, on_step);
      break;
    }
    if (k == o.max_iterations)
      break;

    // Odometry as the robot reports it: dead-reckoned pose, noisy pan reading.
    yawdepth::MotionSample odo = odometry.sample(k);
    odo.yaw = robot.pan + o.sigma_pan * noise();

    // Each feature: x, y from the observed pixel, Z from the chosen source.
    if (o.depth == ServoDepthMode::Estimated)
      provider.update(odo, view.observed);
    setFeatures(o, scene, view, provider, s, st);

    // Control: the robot's Jacobian at the measured pan.
    UnicyclePanRobot measured = robot;
    measured.pan = odo.yaw;
    task.set_eJe(measured.cJq());
    qdot = task.computeControlLaw();

    // Optional secondary task: pan for parallax while some depth has not converged.
    if (o.yaw_helper && o.depth == ServoDepthMode::Estimated &&
        yawHelperRate(o, s, st.converged, odo.yaw, measured.visionVelocity(qdot[0], qdot[1]), st.yaw_helper_rate)) {
      vpColVector de2dt(3, 0.0);
      de2dt[2] = st.yaw_helper_rate;
      qdot += task.secondaryTask(de2dt, true);
    }
    saturate(qdot, o);
    if (!std::isfinite(qdot.sumSquare())) {
      result.reason = "not_finite";
      break;
    }
    st.qdot = qdot;
    keepStep(result, st, on_step);
    moveRobot(robot, odometry, qdot, o, noise);
  }
  return result;
}

} // namespace servo_sim

#ifndef SERVO_SIM_LOOP_ONLY // defined where this file is compiled for tests/test_servo.cpp (servo_sim/CMakeLists.txt)

namespace {

// The usage lines (on stdout, as --help prints them).
void usage()
{
  std::printf("usage: servo_ibvs_yawing_camera [--depth true|constant|estimated] [--constant-error E]\n"
              "       [--view front|side] [--yaw-helper] [--prior Z] [--seed N] [--sigma-px S] [--sigma-odom R]\n"
              "       [--sigma-pan RAD] [--max-iterations N] [--png FILE|none] [--display] [--quiet]\n");
}

// The run's options and what to show of it.
struct Args {
  servo_sim::ServoSimOptions sim;
  std::string png = "none"; // write nothing unless asked: a run must not litter the current folder
  bool display = false, quiet = false, verbose = false;
};

// Reads the command line (exits with 2 on one the example cannot take, with 0 after --help).
Args parse(int argc, char **argv)
{
  Args a;
  servo_sim::ServoSimOptions &o = a.sim;
  servo_sim::readOptions(argc, argv, "servo_ibvs_yawing_camera", usage,
                         [&](const std::string &opt, const servo_sim::NextValue &next) {
                           if (opt == "--depth")
                             o.depth = servo_sim::servoDepthModeFromString(next());
                           else if (opt == "--constant-error")
                             o.constant_error = std::stod(next());
                           else if (opt == "--view") {
                             const std::string v = next();
                             if (v != "front" && v != "side")
                               throw std::runtime_error("--view: front or side");
                             o.side_view = v == "side";
                           } else if (opt == "--yaw-helper")
                             o.yaw_helper = true;
                           else if (opt == "--converged-sigma")
                             o.provider.converged_relative_sigma = std::stod(next());
                           else if (opt == "--prior")
                             o.provider.prior_depth = std::stod(next());
                           else if (opt == "--seed")
                             o.seed = std::stoull(next());
                           else if (opt == "--sigma-px")
                             o.sigma_px = std::stod(next());
                           else if (opt == "--sigma-odom")
                             o.sigma_odom_rel = std::stod(next());
                           else if (opt == "--sigma-pan")
                             o.sigma_pan = std::stod(next());
                           else if (opt == "--max-iterations")
                             o.max_iterations = std::stoi(next());
                           else if (opt == "--png")
                             a.png = next();
                           else if (opt == "--display")
                             a.display = true;
                           else if (opt == "--verbose")
                             a.verbose = true;
                           else if (opt == "--quiet")
                             a.quiet = true;
                           else
                             return false;
                           return true;
                         });
  // The estimator's noise model: what the simulated robot's sensors have.
  o.provider.noise.sigma_px = std::max(o.sigma_px, 0.05);
  o.provider.noise.sigma_yaw = std::max(o.sigma_pan, 1e-4);
  return a;
}

// The optional ViSP display of the image plane I (none when not asked or when ViSP has none).
std::unique_ptr<vpDisplay> openDisplay(vpImage<unsigned char> &I, bool display)
{
  std::unique_ptr<vpDisplay> disp;
  if (display) {
#if defined(VISP_HAVE_X11)
    disp.reset(new vpDisplayX(I, 0, 0, "servo_ibvs_yawing_camera"));
#elif defined(VISP_HAVE_OPENCV)
    disp.reset(new vpDisplayOpenCV(I, 0, 0, "servo_ibvs_yawing_camera"));
#else
    std::fprintf(stderr, "servo_ibvs_yawing_camera: no ViSP display available, running headless\n");
#endif
  }
  return disp;
}

// The first line: the depth source (with the constant's value), the view, the helper, the seed.
void printHeader(const servo_sim::ServoSimOptions &o)
{
  std::printf("servo: depth=%s%s view=%s yaw-helper=%s seed=%llu\n", servo_sim::toString(o.depth),
              o.depth == servo_sim::ServoDepthMode::Constant
                  ? (" (Z = " + std::to_string(o.desired_depth * (1 + o.constant_error)) + " m)").c_str()
                  : "",
              o.side_view ? "side" : "front", o.yaw_helper ? "on" : "off", static_cast<unsigned long long>(o.seed));
}

// The progress line of one period: the error, the depths used (* converged) and the true ones;
// verbose: each estimator's status and estimate, the joint rates and the helper's pan rate.
void printStep(const servo_sim::ServoSimStep &st, bool verbose)
{
  std::printf("it %4d  error %8.3f px  Z used", st.iteration, st.error_px);
  for (std::size_t i = 0; i < st.used_Z.size(); ++i)
    std::printf(" %.3f%s", st.used_Z[i], st.converged.size() > i && st.converged[i] ? "*" : "");
  if (verbose)
    for (std::size_t i = 0; i < st.status.size(); ++i)
      std::printf(" [%s %.3f]", yawdepth::toString(st.status[i]), st.estimate_Z[i]);
  if (verbose && st.qdot.size() == 3)
    std::printf(" qdot %.3f %.3f %.3f helper %.3f", st.qdot[0], st.qdot[1], st.qdot[2], st.yaw_helper_rate);
  std::printf("  (true");
  for (double z : st.true_Z)
    std::printf(" %.3f", z);
  std::printf(")\n");
}

// The display: every period's corners so far (blue dots) and the current ones (red crosses).
void drawTrail(vpImage<unsigned char> &I, const std::vector<servo_sim::ServoSimStep> &trail)
{
  vpDisplay::display(I);
  for (const auto &t : trail)
    for (const auto &p : t.pixels)
      vpDisplay::displayPoint(I, vpImagePoint(p.y(), p.x()), vpColor::blue);
  for (const auto &p : trail.back().pixels)
    vpDisplay::displayCross(I, vpImagePoint(p.y(), p.x()), 12, vpColor::red, 2);
  vpDisplay::flush(I);
}

} // namespace

int main(int argc, char **argv)
{
  const Args args = parse(argc, argv);
  const servo_sim::ServoSimOptions &o = args.sim;

  vpImage<unsigned char> I(o.camera.height(), o.camera.width(), 255);
  const std::unique_ptr<vpDisplay> disp = openDisplay(I, args.display);

  printHeader(o);
  std::vector<servo_sim::ServoSimStep> trail;
  servo_sim::ServoSimResult r;
  try {
    r = servo_sim::runServoSimulation(o, [&](const servo_sim::ServoSimStep &st) {
      if (!args.quiet && st.iteration % 25 == 0)
        printStep(st, args.verbose);
      if (disp) {
        trail.push_back(st);
        drawTrail(I, trail);
      }
    });
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_ibvs_yawing_camera: %s\n", e.what());
    return 1;
  }
  if (args.png != "none")
    servo_sim::writePlot(args.png, o, r);
  if (disp && !args.quiet) {
    vpDisplay::displayText(I, 20, 20, "Click to quit", vpColor::red);
    vpDisplay::flush(I);
    vpDisplay::getClick(I);
  }
  return servo_sim::printOutcome(r.converged, r.iterations, r.final_error_px, r.reason);
}

#endif // SERVO_SIM_LOOP_ONLY
