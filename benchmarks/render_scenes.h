#pragma once
/*!
  \file render_scenes.h
  \brief Seeded random chessboard scenes with the renderer's exact truth (the paper's camera and a
  wide camera with strong barrel distortion) and the per-corner error statistics; shared by
  bench_corner_refinement and test_features.
*/
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>
#include <Eigen/Geometry>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/geometry/rig.h>

#include "bench_common.h" // paperCamera(), paperRig()

namespace yawdepth {
namespace bench {

/*! A wide camera with strong barrel distortion: small squares in pixels, curved edges. */
inline CameraModel wideCamera() {
  return CameraModel::brown(600.0, 602.0, 322.5, 238.0, {-0.28, 0.09, 0.0005, -0.0003, -0.012}, 640, 480);
}
/*! True (distorted) pixel of every board feature, by id; false when one is behind the camera. */
inline bool truthPixels(const CameraModel &cam, const YawRig &rig, const MotionSample &s, const BoardLayout &board,
                        const Eigen::Isometry3d &wMb, std::map<long, Eigen::Vector2d> &out) {
  const Eigen::Isometry3d cMb = toIsometry(wMc(rig, s)).inverse() * wMb;
  out.clear();
  for (const auto &f : board.features()) {
    const Eigen::Vector3d c = cMb * f.second;
    if (!(c.z() > 0))
      return false;
    out[f.first] = cam.project(Eigen::Vector2d(c.x() / c.z(), c.y() / c.z()));
  }
  return true;
}

/*!
  A pose of the board in front of the camera: board centre at depth `depth` near the optical axis
  (offset by `off_x`, `off_y`), tilted by `tilt_x`, `tilt_y` about two axes, rotated in plane by
  `roll`. Returns wMb.
*/
inline Eigen::Isometry3d boardPose(const YawRig &rig, const MotionSample &s, const BoardLayout &board, double depth,
                                   double tilt_x, double tilt_y, double roll, double off_x, double off_y) {
  const Eigen::Vector4d e = board.extent();
  const Eigen::Vector3d centre(0.5 * (e[0] + e[2]), 0.5 * (e[1] + e[3]), 0.0);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(tilt_x, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(tilt_y, Eigen::Vector3d::UnitY()))
                                .toRotationMatrix();
  Eigen::Isometry3d cMb = Eigen::Isometry3d::Identity();
  cMb.linear() = R;
  cMb.translation() = Eigen::Vector3d(off_x, off_y, depth) - R * centre;
  return toIsometry(wMc(rig, s)) * cMb;
}

/*! True when every pixel is at least `margin` px inside the image. */
inline bool allInside(const std::map<long, Eigen::Vector2d> &px, const CameraModel &cam, double margin) {
  for (const auto &kv : px)
    if (kv.second.x() < margin || kv.second.y() < margin || kv.second.x() > cam.width() - 1 - margin ||
        kv.second.y() > cam.height() - 1 - margin)
      return false;
  return true;
}

/*! Per-corner 2D errors: RMS of the 2D error (not per coordinate), bias per axis, largest. */
struct ErrorStats {
  double sx = 0, sy = 0, sxx = 0, syy = 0, max = 0;
  long n = 0;
  void add(const Eigen::Vector2d &e) {
    sx += e.x();
    sy += e.y();
    sxx += e.x() * e.x();
    syy += e.y() * e.y();
    max = std::max(max, e.norm());
    ++n;
  }
  double rms() const { return n ? std::sqrt((sxx + syy) / static_cast<double>(n)) : NAN; }
  double biasX() const { return n ? sx / static_cast<double>(n) : NAN; }
  double biasY() const { return n ? sy / static_cast<double>(n) : NAN; }
};

/*! One rendered scene: camera, board, robot pose, board pose and the true pixel of every corner. */
struct AccuracyScene {
  CameraModel cam;
  BoardLayout board;
  MotionSample sample;
  Eigen::Isometry3d wMb;
  std::map<long, Eigen::Vector2d> truth;
};

/*!
  Seeded random scenes with every corner at least 25 px inside the image: the paper's camera or the
  wide one (even odds), a 5x4, 7x6 or 6x6 board of 20 mm squares, yaw within +-45 degrees, tilts
  within +-40 degrees about two axes, any roll.
*/
inline std::vector<AccuracyScene> accuracyScenes(int count, std::uint64_t seed) {
  constexpr double kDeg = M_PI / 180.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<AccuracyScene> out;
  const YawRig rig = paperRig();
  int attempts = 0;
  while (static_cast<int>(out.size()) < count && attempts < 100 * count) {
    ++attempts;
    AccuracyScene sc;
    const bool wide = U(rng) < 0.5;
    sc.cam = wide ? wideCamera() : paperCamera();
    const int pick = static_cast<int>(U(rng) * 3);
    sc.board.pattern = PatternSpec::parse(pick == 0 ? "chessboard:5x4:0.02" : pick == 1 ? "chessboard:7x6:0.02"
                                                                                         : "chessboard:6x6:0.02");
    sc.sample.yaw = (U(rng) - 0.5) * 90 * kDeg;
    sc.sample.x = (U(rng) - 0.5) * 0.1;
    sc.sample.z = (U(rng) - 0.5) * 0.1;
    sc.sample.heading = (U(rng) - 0.5) * 20 * kDeg;
    const double depth = wide ? 0.25 + 0.35 * U(rng) : 0.55 + 0.4 * U(rng);
    sc.wMb = boardPose(rig, sc.sample, sc.board, depth, (U(rng) - 0.5) * 80 * kDeg, (U(rng) - 0.5) * 80 * kDeg,
                       U(rng) * 2 * M_PI, (U(rng) - 0.5) * 0.2 * depth, (U(rng) - 0.5) * 0.15 * depth);
    if (!truthPixels(sc.cam, rig, sc.sample, sc.board, sc.wMb, sc.truth) || !allInside(sc.truth, sc.cam, 25))
      continue;
    out.push_back(sc);
  }
  return out;
}

} // namespace bench
} // namespace yawdepth
