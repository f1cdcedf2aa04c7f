#include "board_pose.h"

#include <algorithm>
#include <opencv2/calib3d.hpp>

namespace yawdepth {
namespace calibration_detail {

std::map<long, Eigen::Vector3d> boardPoints(const BoardLayout &board)
{
  std::map<long, Eigen::Vector3d> pts;
  const bool tags = board.pattern.kind == PatternSpec::Kind::AprilTag;
  for (const auto &f : board.features())
    if (!tags || f.first % 5 != 0)
      pts[f.first] = f.second;
  return pts;
}

bool boardPoseByPnP(const CameraModel &camera, const std::map<long, Eigen::Vector3d> &points,
                    const std::vector<FeatureObservation> &features, int min_points, Eigen::Isometry3d &cMb,
                    std::vector<Eigen::Vector3d> &P, std::vector<Eigen::Vector2d> &uv)
{
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> norm;
  P.clear();
  uv.clear();
  for (const auto &f : features) {
    const auto it = points.find(f.id);
    Eigen::Vector2d m;
    if (it == points.end() || !camera.undistort(Eigen::Vector2d(f.u, f.v), m))
      continue;
    obj.emplace_back(it->second.x(), it->second.y(), it->second.z());
    norm.emplace_back(m.x(), m.y());
    P.push_back(it->second);
    uv.emplace_back(f.u, f.v);
  }
  if (static_cast<int>(obj.size()) < std::max(4, min_points))
    return false;
  cv::Mat rvec, tvec;
  const cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
  if (!cv::solvePnP(obj, norm, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_IPPE))
    return false;
  cv::solvePnP(obj, norm, K, cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
  cMb = isometryOf(rvec, tvec);
  return true;
}

Eigen::Isometry3d isometryOf(const cv::Mat &rvec, const cv::Mat &tvec)
{
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b)
      M.linear()(a, b) = R.at<double>(a, b);
    M.translation()(a) = tvec.at<double>(a);
  }
  return M;
}

} // namespace calibration_detail
} // namespace yawdepth
