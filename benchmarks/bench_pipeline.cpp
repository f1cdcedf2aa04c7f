// The whole per-frame pipeline of `measure` / the servo provider at 640x480: chessboard detection
// with sub-pixel corners, then tracking by id and the `fused` update of every corner, against
// detection alone. Target (docs/method.md): the estimation costs under 5 % on top of detection.
//
//   bench_pipeline [--frames N] [--repeat R]
//
// Images are rendered once (the paper's camera and rig, side view, 90 mm of travel over the
// sequence, a 7x5 board of 20 mm squares 1 m away that stays in view, blur 0.7 px, noise 2 gray
// levels); each stage is timed over the sequence R times and the median per frame is printed.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#include <yawdepth/window/stream_estimator.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/render/renderer.h>

using namespace yawdepth;
using Clock = std::chrono::steady_clock;

namespace {

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

} // namespace

int main(int argc, char **argv)
{
  int frames = 30, repeat = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--frames"))
      frames = std::max(2, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--repeat"))
      repeat = std::max(1, std::atoi(argv[i + 1]));
  }
  const CameraModel camera =
      CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
  const YawRig rig(Eigen::Vector3d(-0.1503, 0, 0));
  BoardLayout board;
  board.pattern = PatternSpec::parse("chessboard:7x5:0.02");
  // Board facing the first camera (side view), 1 m away, starting left so it crosses the image.
  std::vector<MotionSample> motion(static_cast<std::size_t>(frames));
  for (int k = 0; k < frames; ++k) {
    motion[k].frame = k;
    motion[k].z = 0.09 * k / (frames - 1); // 90 mm in all, whatever the frame count
    motion[k].yaw = M_PI / 2;
  }
  const Eigen::Isometry3d wMc0 = toIsometry(wMc(rig, motion[0]));
  Eigen::Isometry3d cMb = Eigen::Isometry3d::Identity();
  cMb.translation() = Eigen::Vector3d(-0.06 - 0.045, -0.04, 1.0); // pattern centre 45 mm left
  const Eigen::Isometry3d wMb = wMc0 * cMb;
  RenderOptions ro;
  ro.blur_sigma_px = 0.7;
  ro.noise_sigma = 2.0;
  std::vector<cv::Mat> images;
  for (int k = 0; k < frames; ++k) {
    ro.seed = static_cast<std::uint64_t>(k + 1);
    images.push_back(renderBoard(camera, rig, motion[k], board, wMb, ro));
  }

  std::vector<double> t_detect, t_estimate;
  int found = 0, features = 0;
  for (int r = 0; r < repeat; ++r) {
    PatternDetector detector(board.pattern);
    detector.setCamera(camera);
    StreamOptions so; // the streaming entry point, as the servo's DepthProvider runs it
    so.method = StreamMethod::Fused;
    StreamEstimator fused(camera, rig, so);
    double detect_s = 0, estimate_s = 0;
    found = features = 0;
    for (int k = 0; k < frames; ++k) {
      const auto t0 = Clock::now();
      const FrameDetection d = detector.detect(images[k], k);
      const auto t1 = Clock::now();
      fused.addFrame(motion[k], d.features); // the detector's (id, pixel) are the estimator's input
      const auto t2 = Clock::now();
      detect_s += std::chrono::duration<double>(t1 - t0).count();
      estimate_s += std::chrono::duration<double>(t2 - t1).count();
      found += d.found;
      features += static_cast<int>(d.features.size());
    }
    t_detect.push_back(detect_s / frames);
    t_estimate.push_back(estimate_s / frames);
  }
  const double det = median(t_detect) * 1e3, est = median(t_estimate) * 1e3;
  std::printf("yawdepth per-frame pipeline, 640x480, chessboard 7x5 (35 corners), side view, %d frames x %d runs\n",
              frames, repeat);
  std::printf("pattern found in %d of %d frames, %.1f features per frame\n\n", found, frames,
              static_cast<double>(features) / frames);
  std::printf("%-52s %12s\n", "stage (median over runs, per frame)", "time (ms)");
  std::printf("%-52s %12.3f\n", "detection + sub-pixel corners (PatternDetector)", det);
  std::printf("%-52s %12.4f\n", "tracking by id + fused update (StreamEstimator)", est);
  std::printf("%-52s %12.3f\n", "whole pipeline", det + est);
  // The target docs/method.md states: checked, not only printed.
  const bool met = est < 0.05 * det;
  std::printf("\nestimation on top of detection: %.2f %% (target: under 5 %%: %s)\n", 100.0 * est / det,
              met ? "met" : "MISSED");
  return met ? 0 : 1;
}
