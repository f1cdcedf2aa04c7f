#include <yawdepth/online/frame_outputs.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

Eigen::Vector3d outputsToWorld(const vpHomogeneousMatrix &wMc_, const Eigen::Vector3d &c_P)
{
  Eigen::Vector3d w;
  for (unsigned i = 0; i < 3; ++i)
    w[i] = wMc_[i][0] * c_P[0] + wMc_[i][1] * c_P[1] + wMc_[i][2] * c_P[2] + wMc_[i][3];
  return w;
}

} // namespace

std::vector<CloudPoint> frameCloud(const OnlineFrame &frame, const YawRig &rig, double interval_sigmas)
{
  if (!std::isfinite(interval_sigmas) || interval_sigmas < 0)
    throw Error("frameCloud: interval_sigmas must be finite and not negative");
  const vpHomogeneousMatrix M = wMc(rig, frame.pose);
  const bool gray = !frame.image.empty() && frame.image.type() == CV_8UC1;
  std::vector<CloudPoint> cloud;
  cloud.reserve(frame.points.size());
  for (const OnlinePoint &p : frame.points) {
    const PointEstimate &e = p.estimate;
    if (!e.ok() || !e.c_P.allFinite() || !(e.c_P.z() > 0))
      continue;
    CloudPoint c;
    c.id = p.id;
    c.u = p.u;
    c.v = p.v;
    c.c_P = e.c_P;
    c.w_P = outputsToWorld(M, e.c_P);
    c.sigma_z = e.sigmaZ();
    if (gray) {
      const int col = std::clamp(static_cast<int>(std::lround(p.u)), 0, frame.image.cols - 1);
      const int row = std::clamp(static_cast<int>(std::lround(p.v)), 0, frame.image.rows - 1);
      c.intensity = frame.image.at<unsigned char>(row, col);
    }
    // The interval along the ray through c_P: the point scaled to depth Z -+ k sigma (the near end
    // kept in front of the camera, at 1 % of Z).
    const double Z = e.c_P.z(), k = std::isfinite(c.sigma_z) ? interval_sigmas * c.sigma_z : 0.0;
    const double near_z = std::max(Z - k, 0.01 * Z), far_z = Z + k;
    c.w_near = outputsToWorld(M, e.c_P * (near_z / Z));
    c.w_far = outputsToWorld(M, e.c_P * (far_z / Z));
    cloud.push_back(c);
  }
  return cloud;
}

std::vector<std::pair<Status, std::size_t>> countByStatus(const OnlineFrame &frame)
{
  std::map<int, std::size_t> n;
  for (const OnlinePoint &p : frame.points)
    ++n[static_cast<int>(p.estimate.status)];
  std::vector<std::pair<Status, std::size_t>> out;
  out.reserve(n.size());
  for (const auto &[s, k] : n)
    out.emplace_back(static_cast<Status>(s), k);
  return out;
}

cv::Mat drawTracks(const OnlineFrame &frame, bool label_depths)
{
  cv::Mat bgr;
  if (frame.image.empty())
    throw Error("drawTracks: the frame has no image");
  if (frame.image.type() == CV_8UC1)
    cv::cvtColor(frame.image, bgr, cv::COLOR_GRAY2BGR);
  else if (frame.image.type() == CV_8UC3)
    bgr = frame.image.clone();
  else
    throw Error("drawTracks: the frame's image is not 8-bit gray or BGR");
  for (const OnlinePoint &p : frame.points) {
    const Status s = p.estimate.status;
    const cv::Scalar color = s == Status::Ok             ? cv::Scalar(0, 200, 0)
                             : s == Status::TooFewFrames ? cv::Scalar(0, 210, 255)
                                                         : cv::Scalar(0, 0, 255);
    const cv::Point2d at(p.u, p.v);
    cv::circle(bgr, at, 3, color, 1, cv::LINE_AA);
    if (label_depths && s == Status::Ok && std::isfinite(p.estimate.c_P.z())) {
      char text[32];
      std::snprintf(text, sizeof text, "%.2f", p.estimate.c_P.z());
      cv::putText(bgr, text, at + cv::Point2d(4, -4), cv::FONT_HERSHEY_PLAIN, 0.7, color, 1, cv::LINE_AA);
    }
  }
  return bgr;
}

} // namespace yawdepth
