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

#include "servo_sim/servo_sim.h"

namespace servo_sim {

ServoSimResult runServoSimulation(const ServoSimOptions &o, const std::function<void(const ServoSimStep &)> &on_step)
{
  // The simulated world: the tag, the goal and the robot at its start. The robot's odometry
  // dead-reckons from the same start.
  const TagScene scene(o);
  const yawdepth::CameraModel &camera = o.camera;
  const std::size_t n = scene.ids.size();
  UnicyclePanRobot robot = scene.start;
  UnicyclePanRobot odometry = robot;
  Noise noise(o.seed);

  // Desired features: the corners seen from the goal.
  ServoSimResult result;
  std::vector<vpFeaturePoint> s(n), sd(n);
  const vpHomogeneousMatrix cdMw = scene.wMcd.inverse();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d P = scene.cameraPoint(cdMw, i);
    sd[i].buildFrom(P.x() / P.z(), P.y() / P.z(), P.z());
    result.desired_pixels.push_back(camera.project(Eigen::Vector2d(P.x() / P.z(), P.y() / P.z())));
  }

  // The task: the three joints (v, omega, pan rate) move the camera through eJe = the robot's
  // Jacobian cJq (cVe = identity); the interaction matrix of the current features, whose depths
  // are what the provider sets.
  vpServo task;
  task.setServo(vpServo::EYEINHAND_L_cVe_eJe);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(o.lambda);
  task.set_cVe(vpVelocityTwistMatrix());
  for (std::size_t i = 0; i < n; ++i)
    task.addFeature(s[i], sd[i]);

  yawdepth::DepthProvider provider(camera, o.rig, o.provider);

  vpColVector qdot(3, 0.0);
  result.reason = "max_iterations";
  for (int k = 0; k <= o.max_iterations; ++k) {
    ServoSimStep st;
    st.iteration = k;
    st.time = k * o.dt;
    st.robot = robot.sample(k);

    // Observe the corners: (id, pixel) as a tracker gives them, and the truth for the record.
    const CornerView view = scene.observe(robot, noise);
    st.pixels = view.pixels;
    st.true_Z = view.true_Z;
    double err = 0;
    for (std::size_t i = 0; i < n; ++i)
      err += (st.pixels[i] - result.desired_pixels[i]).norm();
    st.error_px = err / n;
    result.final_error_px = st.error_px;
    result.iterations = k;
    if (view.lost) {
      result.reason = "lost_features";
      break;
    }
    if (!std::isfinite(st.error_px)) {
      result.reason = "not_finite";
      break;
    }
    if (st.error_px < o.tolerance_px) {
      result.converged = true;
      result.reason = "converged";
      result.steps.push_back(st);
      if (on_step)
        on_step(result.steps.back());
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
    for (std::size_t i = 0; i < n; ++i) {
      double Z = 1.0, sigma = 0, est = std::numeric_limits<double>::quiet_NaN();
      bool conv = false;
      yawdepth::Status status = yawdepth::Status::TooFewFrames;
      switch (o.depth) {
      case ServoDepthMode::True:
        Z = view.true_Z[i];
        break;
      case ServoDepthMode::Constant:
        Z = o.desired_depth * (1.0 + o.constant_error);
        break;
      case ServoDepthMode::Estimated: {
        const yawdepth::FeatureDepth f = provider.info(scene.ids[i]);
        Z = f.depth;
        sigma = f.sigma;
        conv = f.converged;
        status = f.status;
        est = f.estimate;
        break;
      }
      }
      double x = 0, y = 0;
      camera.pixelToMeter(view.observed[i].second, x, y);
      s[i].buildFrom(x, y, Z);
      st.used_Z.push_back(Z);
      st.sigma_Z.push_back(sigma);
      st.converged.push_back(conv);
      st.status.push_back(status);
      st.estimate_Z.push_back(est);
    }

    // Control: the robot's Jacobian at the measured pan.
    UnicyclePanRobot measured = robot;
    measured.pan = odo.yaw;
    task.set_eJe(measured.cJq());
    qdot = task.computeControlLaw();

    // Optional secondary task: pan for parallax while some depth has not converged.
    if (o.yaw_helper && o.depth == ServoDepthMode::Estimated) {
      std::vector<yawdepth::YawHelperFeature> hf;
      bool any = false;
      for (std::size_t i = 0; i < n; ++i) {
        yawdepth::YawHelperFeature f;
        f.x = s[i].get_x();
        f.y = s[i].get_y();
        f.Z = s[i].get_Z();
        f.weight = st.converged[i] ? 0.0 : 1.0;
        any = any || !st.converged[i];
        hf.push_back(f);
      }
      if (any) {
        const yawdepth::YawRecommendation r =
            yawdepth::recommendYawRate(camera, o.rig, odo.yaw, measured.visionVelocity(qdot[0], qdot[1]), hf, o.helper);
        vpColVector de2dt(3, 0.0);
        de2dt[2] = r.rate;
        st.yaw_helper_rate = r.rate;
        qdot += task.secondaryTask(de2dt, true);
      }
    }
    // Saturation: scale every rate together.
    const double scale = std::max({1.0, std::abs(qdot[0]) / o.max_v, std::abs(qdot[1]) / o.max_omega,
                                   std::abs(qdot[2]) / o.max_pan_rate});
    qdot /= scale;
    if (!std::isfinite(qdot.sumSquare())) {
      result.reason = "not_finite";
      break;
    }
    st.qdot = qdot;
    result.steps.push_back(st);
    if (on_step)
      on_step(result.steps.back());

    // Move the robot; its wheel odometry measures v and omega with noise.
    robot.step(qdot, o.dt);
    vpColVector measured_rates = qdot;
    measured_rates[0] *= 1.0 + o.sigma_odom_rel * noise();
    measured_rates[1] *= 1.0 + o.sigma_odom_rel * noise();
    odometry.step(measured_rates, o.dt);
  }
  return result;
}

} // namespace servo_sim

#ifndef SERVO_SIM_LOOP_ONLY // defined where this file is compiled for tests/test_servo.cpp (servo_sim/CMakeLists.txt)

namespace {

void usage()
{
  std::printf("usage: servo_ibvs_yawing_camera [--depth true|constant|estimated] [--constant-error E]\n"
              "       [--view front|side] [--yaw-helper] [--prior Z] [--seed N] [--sigma-px S] [--sigma-odom R]\n"
              "       [--sigma-pan RAD] [--max-iterations N] [--png FILE|none] [--display] [--quiet]\n");
}

} // namespace

int main(int argc, char **argv)
{
  servo_sim::ServoSimOptions o;
  std::string png = "none"; // write nothing unless asked: a run must not litter the current folder
  bool display = false, quiet = false, verbose = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc)
          throw std::runtime_error("missing value after " + a);
        return argv[++i];
      };
      if (a == "--depth")
        o.depth = servo_sim::servoDepthModeFromString(next());
      else if (a == "--constant-error")
        o.constant_error = std::stod(next());
      else if (a == "--view") {
        const std::string v = next();
        if (v != "front" && v != "side")
          throw std::runtime_error("--view: front or side");
        o.side_view = v == "side";
      } else if (a == "--yaw-helper")
        o.yaw_helper = true;
      else if (a == "--converged-sigma")
        o.provider.converged_relative_sigma = std::stod(next());
      else if (a == "--prior")
        o.provider.prior_depth = std::stod(next());
      else if (a == "--seed")
        o.seed = std::stoull(next());
      else if (a == "--sigma-px")
        o.sigma_px = std::stod(next());
      else if (a == "--sigma-odom")
        o.sigma_odom_rel = std::stod(next());
      else if (a == "--sigma-pan")
        o.sigma_pan = std::stod(next());
      else if (a == "--max-iterations")
        o.max_iterations = std::stoi(next());
      else if (a == "--png")
        png = next();
      else if (a == "--display")
        display = true;
      else if (a == "--verbose")
        verbose = true;
      else if (a == "--quiet")
        quiet = true;
      else if (a == "--help" || a == "-h") {
        usage();
        return 0;
      } else
        throw std::runtime_error("unknown option " + a);
    }
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_ibvs_yawing_camera: %s\n", e.what());
    usage();
    return 2;
  }
  // The estimator's noise model: what the simulated robot's sensors have.
  o.provider.noise.sigma_px = std::max(o.sigma_px, 0.05);
  o.provider.noise.sigma_yaw = std::max(o.sigma_pan, 1e-4);

  // Optional ViSP display of the image plane.
  vpImage<unsigned char> I(o.camera.height(), o.camera.width(), 255);
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

  std::printf("servo: depth=%s%s view=%s yaw-helper=%s seed=%llu\n", servo_sim::toString(o.depth),
              o.depth == servo_sim::ServoDepthMode::Constant
                  ? (" (Z = " + std::to_string(o.desired_depth * (1 + o.constant_error)) + " m)").c_str()
                  : "",
              o.side_view ? "side" : "front", o.yaw_helper ? "on" : "off", static_cast<unsigned long long>(o.seed));
  std::vector<servo_sim::ServoSimStep> trail;
  servo_sim::ServoSimResult r;
  try {
    r = servo_sim::runServoSimulation(o, [&](const servo_sim::ServoSimStep &st) {
      if (!quiet && st.iteration % 25 == 0) {
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
      if (disp) {
        trail.push_back(st);
        vpDisplay::display(I);
        for (const auto &t : trail)
          for (const auto &p : t.pixels)
            vpDisplay::displayPoint(I, vpImagePoint(p.y(), p.x()), vpColor::blue);
        for (const auto &p : st.pixels)
          vpDisplay::displayCross(I, vpImagePoint(p.y(), p.x()), 12, vpColor::red, 2);
        vpDisplay::flush(I);
      }
    });
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_ibvs_yawing_camera: %s\n", e.what());
    return 1;
  }
  if (png != "none")
    servo_sim::writePlot(png, o, r);
  if (disp && !quiet) {
    vpDisplay::displayText(I, 20, 20, "Click to quit", vpColor::red);
    vpDisplay::flush(I);
    vpDisplay::getClick(I);
  }
  if (r.converged)
    std::printf("converged iterations=%d final_error=%.4f\n", r.iterations, r.final_error_px);
  else
    std::printf("diverged iterations=%d final_error=%.4f reason=%s\n", r.iterations, r.final_error_px, r.reason.c_str());
  return r.converged ? 0 : 3;
}

#endif // SERVO_SIM_LOOP_ONLY
