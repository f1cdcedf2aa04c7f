#include "track_checks.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {
namespace track_checks {

cv::Mat patchAt(const cv::Mat &image, const cv::Point2f &p, int size)
{
  cv::Mat patch;
  cv::getRectSubPix(image, cv::Size(size, size), p, patch, CV_32F);
  return patch;
}

double zeroMeanNcc(const cv::Mat &a, const cv::Mat &b)
{
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kFlatVariance = 0.25; // gray levels^2 (a standard deviation of 0.5): no appearance to compare
  if (a.empty() || a.size() != b.size() || a.type() != CV_32F || b.type() != CV_32F)
    return kNaN;
  // One pass, no allocation: this runs for every live feature in every frame.
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (int r = 0; r < a.rows; ++r) {
    const float *pa = a.ptr<float>(r), *pb = b.ptr<float>(r);
    for (int c = 0; c < a.cols; ++c) {
      const double x = pa[c], y = pb[c];
      sa += x;
      sb += y;
      saa += x * x;
      sbb += y * y;
      sab += x * y;
    }
  }
  const double n = static_cast<double>(a.total());
  const double va = saa / n - (sa / n) * (sa / n), vb = sbb / n - (sb / n) * (sb / n);
  if (!(va >= kFlatVariance && vb >= kFlatVariance))
    return kNaN;
  return (sab / n - (sa / n) * (sb / n)) / std::sqrt(va * vb);
}

EpipolarStep epipolarStep(const CameraModel &camera, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv,
                          const KltMotion &motion, double sigma_px, double rho0)
{
  EpipolarStep out;
  Eigen::Vector2d mp, mc;
  if (!camera.undistort(uv_prev, mp) || !camera.undistort(uv, mc))
    return out;
  const Eigen::Isometry3d M = toIsometry(motion.cMp);
  const Eigen::Vector3d t = M.translation();
  const Eigen::Vector3d a = M.linear() * Eigen::Vector3d(mp.x(), mp.y(), 1.0);
  rho0 = std::max(rho0, 0.0);
  const Eigen::Vector3d q = a + rho0 * t;
  constexpr double kFront = 1e-9;
  if (q.z() <= kFront)
    return out;
  // The prediction at rho0 and the image's derivative with respect to rho there, in pixels.
  const Eigen::Vector2d pred(q.x() / q.z(), q.y() / q.z());
  const Eigen::Vector2d J((t.x() * q.z() - q.x() * t.z()) / (q.z() * q.z()) * camera.kx(),
                          (t.y() * q.z() - q.y() * t.z()) / (q.z() * q.z()) * camera.ky());
  constexpr double kMinSlope = 1e-3; // px per unit of inverse depth (1/m): no depth information below
  const double j2 = J.squaredNorm();
  if (!(j2 >= kMinSlope * kMinSlope))
    return out;
  const Eigen::Vector2d d((mc.x() - pred.x()) * camera.kx(), (mc.y() - pred.y()) * camera.ky());
  const double f = std::max(camera.kx(), camera.ky());
  const double r = f * motion.sigma_rot, tr = f * motion.sigma_trans * rho0;
  const double step_sigma = std::sqrt(2 * sigma_px * sigma_px + r * r + tr * tr);
  out.rho = rho0 + J.dot(d) / j2;
  out.sigma = step_sigma / std::sqrt(j2);
  out.valid = std::isfinite(out.rho) && std::isfinite(out.sigma) && out.sigma > 0;
  return out;
}

bool isJump(const KltFeatureState &state, const EpipolarStep &step, double k)
{
  if (!step.valid || !(state.rho_weight > 0))
    return false;
  const double mean = state.rho_weighted / state.rho_weight;
  return std::abs(step.rho - mean) > k * std::sqrt(step.sigma * step.sigma + 1.0 / state.rho_weight);
}

void addStep(KltFeatureState &state, const EpipolarStep &step)
{
  if (!step.valid)
    return;
  const double w = 1.0 / (step.sigma * step.sigma);
  state.rho_weight += w;
  state.rho_weighted += w * step.rho;
}

void checkTracks(const CameraModel &camera, const KltOptions &options, const cv::Mat &image, const KltMotion *motion,
                 const std::map<long, cv::Point2f> &previous, std::vector<cv::Point2f> &points, std::vector<long> &ids,
                 std::map<long, KltFeatureState> &state, long &next_id, KltStats &stats, std::vector<long> &cut)
{
  const bool appearance = options.min_ncc > 0, jumps = options.jump_sigmas > 0 && motion != nullptr;
  if (!appearance && !jumps)
    return;
  std::size_t kept = 0;
  cv::Mat patch; // the current patch, its buffer reused
  for (std::size_t i = 0; i < points.size(); ++i) {
    const long id = ids[i];
    KltFeatureState &s = state[id];
    if (appearance && !s.reference.empty()) {
      cv::getRectSubPix(image, cv::Size(options.window, options.window), points[i], patch, CV_32F);
      const double ncc = zeroMeanNcc(s.reference, patch);
      if (ncc < options.min_ncc) { // NaN (a flat patch) is not evidence of a change
        ++stats.lost_appearance;
        cut.push_back(id);
        state.erase(id);
        continue;
      }
    }
    if (jumps) {
      const auto prev = previous.find(id);
      if (prev != previous.end()) {
        const double rho0 = s.rho_weight > 0 ? s.rho_weighted / s.rho_weight : 0.0;
        const EpipolarStep step =
            epipolarStep(camera, Eigen::Vector2d(prev->second.x, prev->second.y),
                         Eigen::Vector2d(points[i].x, points[i].y), *motion, options.sigma_px, rho0);
        if (isJump(s, step, options.jump_sigmas)) {
          ++stats.split_jump;
          state.erase(id);
          const long fresh = next_id++;
          KltFeatureState &n = state[fresh];
          if (appearance)
            n.reference = patchAt(image, points[i], options.window);
          ids[i] = fresh;
        } else {
          addStep(s, step);
        }
      }
    }
    points[kept] = points[i];
    ids[kept] = ids[i];
    ++kept;
  }
  points.resize(kept);
  ids.resize(kept);
}

} // namespace track_checks
} // namespace yawdepth
