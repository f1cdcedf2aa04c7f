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
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpMath.h>
#include <visp3/core/vpMeterPixelConversion.h>
#include <visp3/core/vpPoint.h>
#include <visp3/robot/vpSimulatorPioneerPan.h>
#include <visp3/visual_features/vpFeatureBuilder.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>

#include <yawdepth/servo/depth_provider.h>
#include <yawdepth/servo/pioneer_pan.h>

namespace {

void usage()
{
  std::printf("usage: servo_pioneer_pan [--depth true|constant|estimated] [--scenario front|side]\n"
              "       [--constant-error E] [--seed N] [--sigma-px S] [--odom-noise R] [--pan-noise DEG]\n"
              "       [--max-iterations N] [--pose-api] [--quiet] [--verbose]\n");
}

struct Args {
  std::string depth_mode = "estimated", scenario = "front";
  double constant_error = 0.0, sigma_px = 0.3, odom_noise = 0.02, pan_noise_deg = 0.05;
  unsigned seed = 1;
  int max_iterations = 3000;
  bool quiet = false, verbose = false;
  bool pose_api = false; // DepthProvider::update(wMv, points, yaw) instead of update(MotionSample, points)
};

Args parse(int argc, char **argv)
{
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string o = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc)
        throw std::runtime_error("missing value after " + o);
      return argv[++i];
    };
    if (o == "--depth") {
      a.depth_mode = next();
      if (a.depth_mode != "true" && a.depth_mode != "constant" && a.depth_mode != "estimated")
        throw std::runtime_error("--depth: true, constant or estimated");
    } else if (o == "--scenario") {
      a.scenario = next();
      if (a.scenario != "front" && a.scenario != "side")
        throw std::runtime_error("--scenario: front or side");
    } else if (o == "--constant-error")
      a.constant_error = std::stod(next());
    else if (o == "--seed")
      a.seed = static_cast<unsigned>(std::stoul(next()));
    else if (o == "--sigma-px")
      a.sigma_px = std::stod(next());
    else if (o == "--odom-noise")
      a.odom_noise = std::stod(next());
    else if (o == "--pan-noise")
      a.pan_noise_deg = std::stod(next());
    else if (o == "--max-iterations")
      a.max_iterations = std::stoi(next());
    else if (o == "--pose-api")
      a.pose_api = true;
    else if (o == "--quiet")
      a.quiet = true;
    else if (o == "--verbose")
      a.verbose = true;
    else if (o == "--help" || o == "-h") {
      usage();
      std::exit(0);
    } else
      throw std::runtime_error("unknown option " + o);
  }
  if (!(a.sigma_px >= 0.0) || !(a.odom_noise >= 0.0) || !(a.pan_noise_deg >= 0.0) || !(a.constant_error > -1.0) ||
      a.max_iterations <= 0)
    throw std::runtime_error("noise levels >= 0, --constant-error > -1 and --max-iterations > 0");
  return a;
}

} // namespace

int main(int argc, char **argv)
{
  Args args;
  try {
    args = parse(argc, argv);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_pioneer_pan: %s\n", e.what());
    usage();
    return 2;
  }

  const vpCameraParameters cam(600, 600, 320, 240);
  const unsigned width = 640, height = 480;
  const double dt = 0.040;
  const vpHomogeneousMatrix cdMo(0, 0, 0.6, 0, 0, 0);

  vpPoint point[4];
  point[0].setWorldCoordinates(-0.1, -0.1, 0);
  point[1].setWorldCoordinates(0.1, -0.1, 0);
  point[2].setWorldCoordinates(0.1, 0.1, 0);
  point[3].setWorldCoordinates(-0.1, 0.1, 0);

  // The robot starts at the world origin, the pan at q0; the square is placed relative to the camera.
  vpSimulatorPioneerPan robot;
  robot.setSamplingTime(dt);
  const bool side = args.scenario == "side";
  const double q0 = side ? vpMath::rad(60) : 0.0;
  {
    vpColVector q(3, 0.0);
    q[2] = q0 / dt; // one period of pan velocity brings the pan to q0
    robot.setMaxRotationVelocity(q[2] + 1.0);
    robot.setVelocity(vpRobot::ARTICULAR_FRAME, q); // within the limits: nothing printed
    robot.setMaxRotationVelocity(vpMath::rad(90));
  }
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
  vpImagePoint desired[4];
  for (unsigned i = 0; i < 4; i++) {
    point[i].track(cdMo);
    vpFeatureBuilder::create(pd[i], point[i]);
    vpMeterPixelConversion::convertPoint(cam, point[i].get_x(), point[i].get_y(), desired[i]);
    point[i].track(cMo_start);
    vpFeatureBuilder::create(p[i], point[i]);
    task.addFeature(p[i], pd[i]);
  }

  // The depth estimator, default options, the Pioneer's rig.
  yawdepth::DepthProvider provider(cam, yawdepth::pioneerPanRig());

  std::mt19937 rng(1000003u * args.seed + 17u);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Odometry: the platform's pose integrated from the measured wheel speeds (2 % off per period).
  double x_odo = 0.0, y_odo = 0.0, theta_odo = 0.0, q_true = q0;
  double path_length = 0.0, final_error = 0.0, depth_error = 0.0, depth_bias = 0.0;
  vpTranslationVector previous_centre = wMc.getTranslationVector();
  std::string outcome;
  int iter = 0;
  int converged_at[4] = {-1, -1, -1, -1}; // first iteration at which the provider used each corner's estimate
  if (!args.quiet)
    std::printf("servo: depth=%s scenario=%s seed=%u sigma_px=%.2f\n", args.depth_mode.c_str(), args.scenario.c_str(),
                args.seed, args.sigma_px);
  for (; iter < args.max_iterations; ++iter) {
    robot.getPosition(wMc);
    const vpHomogeneousMatrix cMo = wMc.inverse() * wMo;
    path_length += (wMc.getTranslationVector() - previous_centre).frobeniusNorm();
    previous_centre = wMc.getTranslationVector();

    // Observe: the true projection, then pixel noise.
    std::vector<std::pair<long, vpImagePoint>> observed;
    double error = 0.0;
    bool outside = false;
    for (unsigned i = 0; i < 4; i++) {
      point[i].track(cMo);
      vpImagePoint truth;
      vpMeterPixelConversion::convertPoint(cam, point[i].get_x(), point[i].get_y(), truth);
      error += vpImagePoint::distance(truth, desired[i]) / 4.0;
      outside = outside || point[i].get_Z() <= 0 || truth.get_u() < 0 || truth.get_v() < 0 ||
                truth.get_u() > width - 1 || truth.get_v() > height - 1;
      observed.emplace_back(i, vpImagePoint(truth.get_i() + args.sigma_px * gauss(rng),
                                            truth.get_j() + args.sigma_px * gauss(rng)));
    }
    final_error = error;
    if (outside) {
      outcome = "reason=feature_left_image";
      break;
    }
    if (error < 0.5) {
      outcome = "converged";
      break;
    }

    // The features: x, y from the noisy pixels, Z from the chosen source.
    if (args.depth_mode == "estimated") {
      const double q_read = q_true + vpMath::rad(args.pan_noise_deg) * gauss(rng);
      const yawdepth::MotionSample odometry = yawdepth::pioneerPanOdometry(x_odo, y_odo, theta_odo, q_read);
      if (args.pose_api) // the same odometry as a pose (vision frame in the odometry world) and the pan reading
        provider.update(yawdepth::wMv(odometry), observed, q_read);
      else
        provider.update(odometry, observed);
    }
    depth_error = depth_bias = 0.0;
    for (unsigned i = 0; i < 4; i++) {
      const vpImagePoint &ip = observed[i].second;
      double Z = point[i].get_Z();
      if (args.depth_mode == "estimated") {
        provider.buildFrom(i, ip, p[i]);
        Z = p[i].get_Z();
        if (converged_at[i] < 0 && provider.converged(i))
          converged_at[i] = iter;
      } else {
        vpFeatureBuilder::create(p[i], cam, ip);
        if (args.depth_mode == "constant")
          Z = cdMo[2][3] * (1.0 + args.constant_error);
        p[i].set_Z(Z);
      }
      depth_error += std::fabs(Z - point[i].get_Z()) / point[i].get_Z() / 4.0;
      depth_bias += (Z - point[i].get_Z()) / point[i].get_Z() / 4.0;
    }
    robot.get_eJe(eJe);
    task.set_eJe(eJe);
    vpColVector v = task.computeControlLaw();
    // What the robot will do (its velocity limits, a hair inside so that the simulator does not
    // saturate again), so that the odometry integrates the same.
    vpColVector v_max(3);
    v_max[0] = robot.getMaxTranslationVelocity() * (1 - 1e-9);
    v_max[1] = v_max[2] = robot.getMaxRotationVelocity() * (1 - 1e-9);
    v = vpRobot::saturateVelocities(v, v_max, false);
    robot.setVelocity(vpRobot::ARTICULAR_FRAME, v);
    const double v_meas = v[0] * (1.0 + args.odom_noise * gauss(rng));
    const double w_meas = v[1] * (1.0 + args.odom_noise * gauss(rng));
    x_odo += dt * v_meas * std::cos(theta_odo);
    y_odo += dt * v_meas * std::sin(theta_odo);
    theta_odo += dt * w_meas;
    q_true += dt * v[2];

    if (!args.quiet && iter % (args.verbose ? 10 : 50) == 0) {
      std::printf("it %4d  error %8.3f px  path %.4f  Z used", iter, error, path_length);
      for (unsigned i = 0; i < 4; i++)
        std::printf(" %.3f", p[i].get_Z());
      std::printf("  (true");
      for (unsigned i = 0; i < 4; i++)
        std::printf(" %.3f", point[i].get_Z());
      std::printf(")\n");
      if (args.verbose && args.depth_mode == "estimated")
        for (unsigned i = 0; i < 4; i++) {
          const yawdepth::FeatureDepth f = provider.info(i);
          std::printf("    %u: %s estimate %.4f +- %.4f%s\n", i, yawdepth::toString(f.status), f.estimate,
                      f.estimate_sigma, f.converged ? " (used)" : "");
        }
    }
  }
  if (outcome.empty())
    outcome = "reason=max_iterations";
  long revocations = 0;
  for (unsigned i = 0; i < 4; i++)
    revocations += provider.info(i).revocations;
  std::printf("path_length=%.4f depth_error=%.4f depth_bias=%+.4f converged_at=%d,%d,%d,%d revocations=%ld\n",
              path_length, depth_error, depth_bias, converged_at[0], converged_at[1], converged_at[2], converged_at[3],
              revocations);
  if (outcome == "converged") {
    std::printf("converged iterations=%d final_error=%.4f\n", iter, final_error);
    return 0;
  }
  std::printf("diverged iterations=%d final_error=%.4f %s\n", iter, final_error, outcome.c_str());
  return 3;
}
