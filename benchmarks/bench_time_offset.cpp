// bench_time_offset: how well calibrate-rig --estimate-time-offset recovers a camera latency, against
// the pan's speed and the yaw readings' noise. Renders (yawdepth's renderer: a 6x5 board of 30 mm
// squares 0.75 m ahead, turned 12 deg, seen by a wide 640x480 camera, blur 0.7 px, noise 2 gray
// levels) of a static robot whose pan sweeps +-22 deg sinusoidally; images at 30 Hz for 2.5 s on the
// camera's clock, taken 30 ms after their stamps on the motion clock; yaw readings at 200 Hz with
// white noise. Prints one row per case; exits 1 when the case (the fastest sweep with noise
// of 2 % of a reading step, or 0.05 deg) misses 30 ms by 2 ms or more.
//
//   bench_time_offset
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>
#include <yawdepth/calibration/time_offset.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/render/renderer.h>

using namespace yawdepth;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kLatency = 0.030;
constexpr double kTargetError = 0.002;

struct Case {
  double frequency_hz;   // sweep frequency (amplitude 22 deg)
  double noise_deg;      // white noise of each yaw reading
  bool target;           // the case
};

struct Row {
  double offset = 0, sigma = 0;
  int images = 0;
  bool ok = false;
};

Row run(const Case &c, std::uint64_t seed)
{
  const CameraModel camera = CameraModel::brown(420.0, 421.0, 322.0, 238.5, {-0.25, 0.07, 0.0004, -0.0002}, 640, 480);
  BoardLayout board;
  board.pattern.kind = PatternSpec::Kind::Chessboard;
  board.pattern.cols = 6;
  board.pattern.rows = 5;
  board.pattern.square = 0.03;
  const Eigen::Vector3d t0(-0.1503, 0.002, 0.01);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.01, 1.0, -0.005).normalized();
  const double yaw_offset = 0.5 * kDeg;
  const auto yaw = [&](double t) { return 22 * kDeg * std::sin(2 * M_PI * c.frequency_hz * t); };
  // The board 0.75 m ahead, turned by 12 deg, centred.
  Eigen::Isometry3d wMb = Eigen::Isometry3d::Identity();
  wMb.linear() = rotY(12 * kDeg);
  wMb.translation() = Eigen::Vector3d(-0.12, 0, 0.75) - wMb.linear() * Eigen::Vector3d(0.075, 0.06, 0);

  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  MotionLog motion;
  motion.timestamped = true;
  for (int i = 0; -0.2 + i * 0.005 <= 2.9; ++i) {
    const double t = -0.2 + i * 0.005;
    MotionSample s;
    s.frame = i;
    s.yaw = yaw(t) - yaw_offset + c.noise_deg * kDeg * unit(rng);
    motion.samples.push_back(s);
    motion.times.push_back(t);
  }
  PatternDetector detector(board.pattern);
  detector.setCamera(camera);
  std::vector<double> times;
  std::vector<std::vector<FeatureObservation>> features;
  for (int k = 0; k / 30.0 <= 2.5; ++k) {
    const double t = k / 30.0;
    Eigen::Isometry3d vMc = Eigen::Isometry3d::Identity();
    vMc.linear() = Eigen::AngleAxisd(yaw(t + kLatency) + yaw_offset, axis).toRotationMatrix();
    vMc.translation() = vMc.linear() * t0;
    RenderOptions o;
    o.blur_sigma_px = 0.7;
    o.noise_sigma = 2.0;
    o.seed = seed * 1000 + static_cast<std::uint64_t>(k);
    const cv::Mat image = renderBoard(camera, YawRig(), MotionSample(), board, vMc.inverse() * wMb, o);
    const FrameDetection d = detector.detect(image, k);
    times.push_back(t);
    features.push_back(d.found ? d.features : std::vector<FeatureObservation>());
  }
  Row r;
  try {
    const TimedRigCalibration cal =
        calibrateRigWithTimeOffset(camera, board, motion, times, features, RigCalibrationOptions(), TimeOffsetSearch());
    r.offset = cal.time_offset.offset;
    r.sigma = cal.time_offset.sigma;
    r.images = cal.images_used;
    r.ok = true;
  } catch (const Error &e) {
    std::printf("  (%.2f Hz, %.3f deg: %s)\n", c.frequency_hz, c.noise_deg, e.what());
  }
  return r;
}

} // namespace

int main()
{
  // 2 % of a 200 Hz reading step at the fastest sweep's top speed: 0.02 * 2 pi 0.4 Hz * 22 deg / 200.
  const double two_percent = 0.02 * 2 * M_PI * 0.4 * 22 / 200.0;
  const std::vector<Case> cases = {{0.4, two_percent, true}, {0.4, 0.05, true},  {0.2, 0.05, false},
                                   {0.1, 0.05, false},       {0.4, 0.2, false}};
  std::printf("time offset of a 30 ms camera latency, pan sweeping +-22 deg (yawdepth renders, 76 images at 30 Hz)\n");
  std::printf("%9s %10s %11s %8s %12s %10s %10s\n", "sweep_Hz", "peak_deg/s", "noise_deg", "images", "offset_ms",
              "error_ms", "sigma_ms");
  bool missed = false;
  std::uint64_t seed = 1;
  for (const Case &c : cases) {
    const Row r = run(c, seed++);
    const double error = r.offset - kLatency;
    if (r.ok)
      std::printf("%9.2f %10.1f %11.4f %8d %12.4f %10.4f %10.4f\n", c.frequency_hz, 2 * M_PI * c.frequency_hz * 22,
                  c.noise_deg, r.images, 1e3 * r.offset, 1e3 * error, 1e3 * r.sigma);
    if (c.target && (!r.ok || !(std::abs(error) < kTargetError)))
      missed = true;
  }
  std::printf("target: the 0.4 Hz cases within %.1f ms of 30 ms: %s\n", 1e3 * kTargetError, missed ? "MISSED" : "met");
  return missed ? 1 : 0;
}
