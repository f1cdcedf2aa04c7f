#include <yawdepth/report/cloud_report.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>
#include <yawdepth/geometry/rig.h>

#include "figure_support.h"

namespace yawdepth {

using report_detail::text;

namespace {

/* A point in the drawn camera's frame. */
struct CameraPoint {
  Eigen::Vector3d c_P;
  double sigma_z;
};

std::vector<CameraPoint> inCamera(const CloudReportInput &in)
{
  std::vector<CameraPoint> out;
  out.reserve(in.points.size());
  const Eigen::Isometry3d cMw = toIsometry(in.cMw);
  for (const CloudPoint &p : in.points) {
    const Eigen::Vector3d c = cMw * p.w_P;
    if (c.allFinite())
      out.push_back({c, p.sigma_z});
  }
  return out;
}

/* The depth range of the points in front of the camera (near, far); (0, 1) when there is none. */
std::pair<double, double> depthRange(const std::vector<CameraPoint> &pts)
{
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (const CameraPoint &p : pts)
    if (p.c_P.z() > 0) {
      lo = std::min(lo, p.c_P.z());
      hi = std::max(hi, p.c_P.z());
    }
  if (!(hi > 0))
    return {0.0, 1.0};
  if (hi - lo < 1e-6)
    hi = lo + 1e-6;
  return {lo, hi};
}

/* TURBO colour of depth z on [lo, hi]. */
cv::Scalar depthColour(double z, double lo, double hi)
{
  static const cv::Mat lut = [] {
    cv::Mat ramp(1, 256, CV_8UC1), out;
    for (int i = 0; i < 256; ++i)
      ramp.at<unsigned char>(0, i) = static_cast<unsigned char>(i);
    cv::applyColorMap(ramp, out, cv::COLORMAP_TURBO);
    return out;
  }();
  const int i = static_cast<int>(std::lround(255 * std::clamp((z - lo) / (hi - lo), 0.0, 1.0)));
  const cv::Vec3b &c = lut.at<cv::Vec3b>(0, i);
  return cv::Scalar(c[0], c[1], c[2]);
}


std::string metres(double v, int decimals = 2)
{
  char b[32];
  std::snprintf(b, sizeof b, "%.*f m", decimals, v);
  return b;
}

/* The colour scale: a strip from lo to hi across `r`. */
void drawScale(cv::Mat &img, const cv::Rect &r, double lo, double hi)
{
  for (int x = 0; x < r.width; ++x)
    cv::line(img, cv::Point(r.x + x, r.y), cv::Point(r.x + x, r.y + r.height),
             depthColour(lo + (hi - lo) * x / std::max(1, r.width - 1), lo, hi));
  text(img, metres(lo), cv::Point(r.x, r.y + r.height + 14), 0.4);
  const std::string far = metres(hi);
  text(img, far, cv::Point(r.x + r.width - 8 * static_cast<int>(far.size()), r.y + r.height + 14), 0.4);
  text(img, "depth", cv::Point(r.x + r.width / 2 - 20, r.y + r.height + 14), 0.4);
}

} // namespace

cv::Mat cloudOverlay(const CloudReportInput &in)
{
  if (in.image.empty() || (in.image.type() != CV_8UC1 && in.image.type() != CV_8UC3))
    throw Error("cloud report: the image must be 8-bit gray or BGR");
  if (in.image.cols != static_cast<int>(in.camera.width()) || in.image.rows != static_cast<int>(in.camera.height()))
    throw Error("cloud report: the image is " + std::to_string(in.image.cols) + "x" + std::to_string(in.image.rows) +
                " but the camera is " + std::to_string(in.camera.width()) + "x" + std::to_string(in.camera.height()));
  cv::Mat base;
  if (in.image.type() == CV_8UC1)
    cv::cvtColor(in.image, base, cv::COLOR_GRAY2BGR);
  else
    base = in.image.clone();
  base = base * 0.7 + cv::Scalar(40, 40, 40); // lighter, so that the colours stand out
  cv::Mat img(base.rows + 44, base.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  base.copyTo(img(cv::Rect(0, 0, base.cols, base.rows)));
  const std::vector<CameraPoint> pts = inCamera(in);
  const auto [lo, hi] = depthRange(pts);
  int drawn = 0;
  for (const CameraPoint &p : pts) {
    if (!(p.c_P.z() > 0))
      continue;
    const Eigen::Vector2d uv = in.camera.project(Eigen::Vector2d(p.c_P.x() / p.c_P.z(), p.c_P.y() / p.c_P.z()));
    if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < base.cols && uv.y() < base.rows))
      continue;
    const cv::Point c(static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y())));
    cv::circle(img, c, 4, depthColour(p.c_P.z(), lo, hi), cv::FILLED, cv::LINE_AA);
    cv::circle(img, c, 4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    ++drawn;
  }
  text(img, in.title, cv::Point(8, 18), 0.42, cv::Scalar(255, 255, 255));
  text(img, std::to_string(drawn) + " points in view", cv::Point(8, 38), 0.45, cv::Scalar(255, 255, 255));
  drawScale(img, cv::Rect(base.cols / 4, base.rows + 6, base.cols / 2, 14), lo, hi);
  return img;
}

cv::Mat cloudTopView(const CloudReportInput &in)
{
  const int W = 900, H = 700;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  const std::vector<CameraPoint> pts = inCamera(in);
  const auto [lo, hi] = depthRange(pts);
  // The plotted area: x right, depth up, the camera at the bottom centre; equal scales.
  const cv::Rect plot(60, 50, W - 90, H - 120);
  double x_max = 0.05, z_max = 0.1;
  for (const CameraPoint &p : pts)
    if (p.c_P.z() > 0) {
      x_max = std::max(x_max, std::abs(p.c_P.x()));
      z_max = std::max(z_max, p.c_P.z());
    }
  const double scale = std::min(plot.width / (2.2 * x_max), plot.height / (1.1 * z_max));
  const cv::Point cam(plot.x + plot.width / 2, plot.y + plot.height);
  const auto toPx = [&](double x, double z) {
    return cv::Point(static_cast<int>(std::lround(cam.x + scale * x)), static_cast<int>(std::lround(cam.y - scale * z)));
  };
  cv::rectangle(img, plot, cv::Scalar(200, 200, 200));
  // Depth rings every `step` metres.
  const double raw = z_max / 5, mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
  for (double z = step; z <= 1.1 * z_max; z += step) {
    cv::line(img, toPx(-x_max * 1.1, z), toPx(x_max * 1.1, z), cv::Scalar(230, 230, 230));
    text(img, metres(z, step < 0.1 ? 2 : 1), toPx(-x_max * 1.1, z) + cv::Point(-55, 4), 0.35, cv::Scalar(120, 120, 120));
  }
  // The field of view: the image's left and right edges at its middle row.
  Eigen::Vector2d left, right;
  const double mid_v = 0.5 * (in.camera.height() > 0 ? in.camera.height() - 1.0 : 2 * in.camera.v0());
  const double last_u = in.camera.width() > 0 ? in.camera.width() - 1.0 : 2 * in.camera.u0();
  if (in.camera.undistort(Eigen::Vector2d(0, mid_v), left) && in.camera.undistort(Eigen::Vector2d(last_u, mid_v), right)) {
    const double z = 1.1 * z_max;
    for (const double x : {left.x(), right.x()}) {
      cv::Point a = cam, b = toPx(x * z, z);
      if (cv::clipLine(plot, a, b))
        cv::line(img, a, b, cv::Scalar(170, 170, 170), 1, cv::LINE_AA);
    }
  }
  cv::circle(img, cam, 6, cv::Scalar(0, 0, 0), cv::FILLED);
  text(img, "camera", cam + cv::Point(10, -4), 0.4);
  int drawn = 0;
  for (const CameraPoint &p : pts) {
    if (!(p.c_P.z() > 0))
      continue;
    // The 2-sigma depth interval along the point's ray.
    const Eigen::Vector3d ray = p.c_P / p.c_P.z();
    const double z0 = std::max(1e-3, p.c_P.z() - 2 * p.sigma_z), z1 = p.c_P.z() + 2 * p.sigma_z;
    const cv::Scalar colour = depthColour(p.c_P.z(), lo, hi);
    cv::Point a = toPx(ray.x() * z0, z0), b = toPx(ray.x() * z1, z1);
    if (cv::clipLine(plot, a, b)) // an unbounded far end stops at the plot's edge
      cv::line(img, a, b, colour, 1, cv::LINE_AA);
    cv::circle(img, toPx(p.c_P.x(), p.c_P.z()), 3, colour, cv::FILLED, cv::LINE_AA);
    ++drawn;
  }
  text(img, in.title, cv::Point(10, 22), 0.5, cv::Scalar(0, 0, 0));
  text(img, "seen from above in the last camera: x right, depth up; " + std::to_string(drawn) +
                " points, each with its 2-sigma depth interval along its ray",
       cv::Point(10, 42), 0.4);
  drawScale(img, cv::Rect(W / 4, H - 50, W / 2, 14), lo, hi);
  return img;
}

void writeCloudReport(const std::string &dir, const CloudReportInput &in)
{
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw Error(dir + ": cannot create the report folder: " + ec.message());
  const std::filesystem::path d(dir);
  AtomicFiles files; // the three files together, after both pictures are drawn: all or nothing
  files.add((d / "report.txt").string(), in.title + "\n\n" + in.summary);
  const std::string overlay = (d / "overlay.png").string(), top = (d / "top_view.png").string();
  files.add(overlay, report_detail::encodePng(cloudOverlay(in), overlay));
  files.add(top, report_detail::encodePng(cloudTopView(in), top));
  files.commit();
}

std::vector<std::string> cloudReportFiles(const std::string &dir)
{
  const std::filesystem::path d(dir);
  return {(d / "report.txt").string(), (d / "overlay.png").string(), (d / "top_view.png").string()};
}

} // namespace yawdepth
