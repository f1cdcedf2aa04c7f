#pragma once
// Test support: the paper's robot (camera, rig, noise), its synthetic scenes, and the statistics
// the Monte Carlo tests hold an estimator's depths to (shared by test_refine and test_window).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>
#include <Eigen/Core>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/simulation/scene.h>

namespace yawdepth {
namespace test {

/* The paper's camera (Brown, 640x480). */
inline CameraModel paperCamera()
{
  return CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
}
/* The paper's rig (Lb = 150.3 mm). */
inline YawRig paperRig() { return YawRig(Eigen::Vector3d(-0.1503, 0.0, 0.0)); }
/* The noise: 0.3 px, 1 mm per increment, 0.05 deg of heading and of yaw. */
inline NoiseModel paperNoise()
{
  constexpr double deg = M_PI / 180.0;
  return NoiseModel{0.3, 1e-3, 0.05 * deg, 0.05 * deg};
}

/* A planar scene of the paper's robot: `frames` steps of 20 mm, 30 points at 0.5 to 3 m (those are
   SceneOptions' defaults), the camera at `yaw`, the robot turning by `turn_rate` per frame; with
   paperNoise() unless `noisy` is false. */
inline SceneOptions paperScene(double yaw, double turn_rate, int frames, std::uint64_t seed, bool noisy = true)
{
  SceneOptions o;
  o.frames = frames;
  o.yaw = yaw;
  o.turn_rate = turn_rate;
  o.seed = seed;
  if (noisy)
    o.noise = paperNoise();
  return o;
}

/* A Catch2 fixture: the paper's camera, rig and noise. */
struct PaperSetup {
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  const NoiseModel noise = paperNoise();
};

/* Depth errors against the Cramer-Rao bound: RMSE / CRLB, the 2-sigma coverage of the estimator's
   own sigma, and the tracks it failed on. */
struct CrlbStats {
  double sum_norm2 = 0; // sum of (error / CRLB)^2
  int n = 0, covered = 0, failed = 0;
  void add(double err, double crlb, double sigma)
  {
    sum_norm2 += (err / crlb) * (err / crlb);
    covered += std::abs(err) <= 2 * sigma ? 1 : 0;
    ++n;
  }
  double ratio() const { return std::sqrt(sum_norm2 / std::max(n, 1)); }
  double coverage() const { return double(covered) / std::max(n, 1); }
};

/* The paper's scene seen at 45 degrees, turning 0.5 degree per frame, 20 frames (seed), its pixels
   with a tracker's errors instead of independent ones: AR(1) along each track, stationary 1-sigma
   sigma, phi from one frame to the next (seed + 400; addTrackerErrors). */
inline Scene trackerErrorScene(const CameraModel &camera, const YawRig &rig, double sigma, double phi, std::uint64_t seed)
{
  constexpr double deg = M_PI / 180.0;
  SceneOptions so = paperScene(45 * deg, 0.5 * deg, 20, seed);
  so.noise.sigma_px = 0; // the tracker's errors instead
  Scene s = simulateScene(camera, rig, so);
  addTrackerErrors(s.tracks, sigma, phi, seed + 400);
  return s;
}

} // namespace test
} // namespace yawdepth
