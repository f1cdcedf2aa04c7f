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
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

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

namespace {

void usage()
{
  std::printf("usage: servo_ibvs_4pts [--depth true|constant|estimated] [--constant-error E]\n"
              "       [--pose N] [--seed N] [--sigma-px S] [--max-iterations N] [--quiet] [--verbose]\n");
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

} // namespace

int main(int argc, char **argv)
{
  std::string depth_mode = "estimated";
  unsigned pose = 0;
  double constant_error = 0.0, sigma_px = 0.3;
  unsigned seed = 1;
  int max_iterations = 2000;
  bool quiet = false, verbose = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc)
          throw std::runtime_error("missing value after " + a);
        return argv[++i];
      };
      if (a == "--depth") {
        depth_mode = next();
        if (depth_mode != "true" && depth_mode != "constant" && depth_mode != "estimated")
          throw std::runtime_error("--depth: true, constant or estimated");
      } else if (a == "--constant-error")
        constant_error = std::stod(next());
      else if (a == "--pose")
        pose = static_cast<unsigned>(std::stoul(next()));
      else if (a == "--seed")
        seed = static_cast<unsigned>(std::stoul(next()));
      else if (a == "--sigma-px")
        sigma_px = std::stod(next());
      else if (a == "--max-iterations")
        max_iterations = std::stoi(next());
      else if (a == "--quiet")
        quiet = true;
      else if (a == "--verbose")
        verbose = true;
      else if (a == "--help" || a == "-h") {
        usage();
        return 0;
      } else
        throw std::runtime_error("unknown option " + a);
    }
    if (!(sigma_px >= 0.0) || !(constant_error > -1.0) || max_iterations <= 0)
      throw std::runtime_error("--sigma-px >= 0, --constant-error > -1 and --max-iterations > 0");
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_ibvs_4pts: %s\n", e.what());
    usage();
    return 2;
  }

  const vpCameraParameters cam(600, 600, 320, 240);
  const unsigned width = 640, height = 480;
  const vpHomogeneousMatrix cdMo(0, 0, 0.75, 0, 0, 0);

  vpPoint point[4];
  point[0].setWorldCoordinates(-0.1, -0.1, 0);
  point[1].setWorldCoordinates(0.1, -0.1, 0);
  point[2].setWorldCoordinates(0.1, 0.1, 0);
  point[3].setWorldCoordinates(-0.1, 0.1, 0);
  vpHomogeneousMatrix cMo = startPose(pose, cam, width, height, point);

  vpServo task;
  task.setServo(vpServo::EYEINHAND_CAMERA);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(0.5);

  vpFeaturePoint p[4], pd[4];
  vpImagePoint desired[4];
  for (unsigned i = 0; i < 4; i++) {
    point[i].track(cdMo);
    vpFeatureBuilder::create(pd[i], point[i]);
    vpMeterPixelConversion::convertPoint(cam, point[i].get_x(), point[i].get_y(), desired[i]);
    point[i].track(cMo);
    vpFeatureBuilder::create(p[i], point[i]);
    task.addFeature(p[i], pd[i]);
  }

  vpHomogeneousMatrix wMc, wMo;
  vpSimulatorCamera robot;
  robot.setSamplingTime(0.040);
  robot.getPosition(wMc);
  wMo = wMc * cMo;

  // The depth estimator: the camera is the vision frame (identity camera_pose), default options.
  yawdepth::DepthProvider provider(cam, yawdepth::YawRig(vpHomogeneousMatrix()));

  std::mt19937 rng(1000003u * seed + 17u);
  std::normal_distribution<double> noise(0.0, sigma_px);
  double path_length = 0.0, final_error = 0.0, depth_error = 0.0;
  vpTranslationVector previous_centre = wMc.getTranslationVector();
  std::string outcome;
  int iter = 0;
  if (!quiet)
    std::printf("servo: depth=%s pose=%u seed=%u sigma_px=%.2f\n", depth_mode.c_str(), pose, seed, sigma_px);
  for (; iter < max_iterations; ++iter) {
    robot.getPosition(wMc);
    cMo = wMc.inverse() * wMo;
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
      observed.emplace_back(i, vpImagePoint(truth.get_i() + noise(rng), truth.get_j() + noise(rng)));
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
    if (depth_mode == "estimated")
      provider.update(wMc, observed);
    depth_error = 0.0;
    for (unsigned i = 0; i < 4; i++) {
      const vpImagePoint &ip = observed[i].second;
      double Z = point[i].get_Z();
      if (depth_mode == "estimated") {
        provider.buildFrom(i, ip, p[i]);
        Z = p[i].get_Z();
      } else {
        vpFeatureBuilder::create(p[i], cam, ip);
        if (depth_mode == "constant")
          Z = cdMo[2][3] * (1.0 + constant_error);
        p[i].set_Z(Z);
      }
      depth_error += std::fabs(Z - point[i].get_Z()) / point[i].get_Z() / 4.0;
    }
    vpColVector v = task.computeControlLaw();
    robot.setVelocity(vpRobot::CAMERA_FRAME, v);
    if (!quiet && iter % (verbose ? 10 : 50) == 0) {
      std::printf("it %4d  error %8.3f px  path %.4f  Z used", iter, error, path_length);
      for (unsigned i = 0; i < 4; i++)
        std::printf(" %.3f", p[i].get_Z());
      std::printf("  (true");
      for (unsigned i = 0; i < 4; i++)
        std::printf(" %.3f", point[i].get_Z());
      std::printf(")\n");
      if (verbose && depth_mode == "estimated")
        for (unsigned i = 0; i < 4; i++) {
          const yawdepth::FeatureDepth f = provider.info(i);
          std::printf("    %u: %s estimate %.4f +- %.4f%s\n", i, yawdepth::toString(f.status), f.estimate,
                      f.estimate_sigma, f.converged ? " (used)" : "");
        }
    }
  }
  if (outcome.empty())
    outcome = "reason=max_iterations";
  std::printf("path_length=%.4f depth_error=%.4f\n", path_length, depth_error);
  if (outcome == "converged") {
    std::printf("converged iterations=%d final_error=%.4f\n", iter, final_error);
    return 0;
  }
  std::printf("diverged iterations=%d final_error=%.4f %s\n", iter, final_error, outcome.c_str());
  return 3;
}
