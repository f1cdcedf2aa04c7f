// Camera calibration: the image's coverage by the corners (the share of an 8 x 6 grid, the coverage
// picture) and the projection uncertainty over the image.
#include "camera_calibration_impl.h"
#include "text.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace calibration_detail {

namespace {

/* The cell of a pixel in the image's 8 x 6 grid, row by row (computed in the pixel's own type). */
template <class T>
std::size_t coverageCell(T x, T y, int width, int height)
{
  const int cx = std::clamp(static_cast<int>(x / width * 8), 0, 7);
  const int cy = std::clamp(static_cast<int>(y / height * 6), 0, 5);
  return static_cast<std::size_t>(cy) * 8 + cx;
}

} // namespace

/* Projection uncertainty at the centres of the 8 x 6 cells of the image, row by row. */
std::vector<double> uncertaintyGrid(const CameraCalibration &calibration, int width, int height)
{
  std::vector<double> grid;
  for (int cy = 0; cy < 6; ++cy)
    for (int cx = 0; cx < 8; ++cx)
      grid.push_back(projectionUncertainty(calibration, (cx + 0.5) * width / 8.0 - 0.5, (cy + 0.5) * height / 6.0 - 0.5));
  return grid;
}

/* Share of the 8 x 6 cells of the image with a corner of a used view. */
double coverageOf(const CameraFit &fit, const std::vector<std::size_t> &used)
{
  std::vector<int> cells(48, 0);
  for (std::size_t i : used)
    for (const auto &p : fit.image[i])
      ++cells[coverageCell(p.x, p.y, fit.width, fit.height)];
  return static_cast<double>(std::count_if(cells.begin(), cells.end(), [](int c) { return c > 0; })) / 48.0;
}

} // namespace calibration_detail

double projectionUncertainty(const CameraCalibration &calibration, double u, double v)
{
  const CameraModel &cam = calibration.camera;
  // The covariance is of the camera's own parameters: Brown's, or Kannala-Brandt's k1..k4 in the
  // places of k1 k2 p1 p2 (calibrateCamera() fits both).
  const bool fisheye = cam.distortion() == CameraModel::Distortion::KannalaBrandt;
  const double w = cam.width(), h = cam.height();
  const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.kx(), 0, cam.u0(), 0, cam.ky(), cam.v0(), 0, 0, 1);
  const std::vector<double> &coefficients = fisheye ? cam.kannalaBrandtCoefficients() : cam.brownCoefficients();
  cv::Mat dist(1, static_cast<int>(coefficients.size()), CV_64F);
  for (int i = 0; i < dist.cols; ++i)
    dist.at<double>(i) = coefficients[static_cast<std::size_t>(i)];
  // Rays of (u, v) (first) and of a 16 x 12 grid over the image (the rotation is fitted on them).
  std::vector<cv::Point3f> rays;
  Eigen::Vector2d m;
  if (!cam.undistort(Eigen::Vector2d(u, v), m))
    return std::numeric_limits<double>::infinity();
  rays.emplace_back(static_cast<float>(m.x()), static_cast<float>(m.y()), 1.f);
  if (w > 0 && h > 0)
    for (int gy = 0; gy < 12; ++gy)
      for (int gx = 0; gx < 16; ++gx)
        if (cam.undistort(Eigen::Vector2d((gx + 0.5) * w / 16 - 0.5, (gy + 0.5) * h / 12 - 0.5), m))
          rays.emplace_back(static_cast<float>(m.x()), static_cast<float>(m.y()), 1.f);
  Eigen::MatrixXd Jint, Jrot; // Jrot: d(pixel)/d(rvec) at rvec = 0, i.e. a small rotation of the camera
  calibration_detail::projectionJacobians(rays, cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), K, dist,
                                          fisheye, Jint, Jrot);
  const Eigen::Index n = Jint.rows();
  Eigen::MatrixXd Jq = Jint.topRows(2);
  if (n > 8) {
    const Eigen::MatrixXd Aw = Jrot.bottomRows(n - 2).leftCols(3), At = Jint.bottomRows(n - 2);
    // The rotation that best absorbs an intrinsics change over the image, then what is left at (u, v).
    const Eigen::MatrixXd G = (Aw.transpose() * Aw).ldlt().solve(Aw.transpose() * At); // 3 x 12
    Jq -= Jrot.topRows(2).leftCols(3) * G;
  }
  const Eigen::Matrix2d C = Jq * calibration.intrinsics_covariance * Jq.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  return std::sqrt(std::max(0.0, es.eigenvalues()(1)));
}

cv::Mat coverageImage(const CameraCalibration &calibration, const std::vector<CalibrationView> &views)
{
  using calibration_detail::coverageCell;
  using calibration_detail::fixed;
  const int w = static_cast<int>(calibration.camera.width()), h = static_cast<int>(calibration.camera.height());
  if (w <= 0 || h <= 0)
    throw Error("coverageImage: unknown image size");
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<int> cells(48, 0);
  for (std::size_t i = 0; i < views.size() && i < calibration.views.size(); ++i)
    if (calibration.views[i].used)
      for (const auto &f : views[i].features)
        ++cells[coverageCell(f.u, f.v, w, h)];
  for (int cy = 0; cy < 6; ++cy)
    for (int cx = 0; cx < 8; ++cx)
      if (cells[static_cast<std::size_t>(cy) * 8 + cx] == 0)
        cv::rectangle(img, cv::Point(cx * w / 8, cy * h / 6), cv::Point((cx + 1) * w / 8 - 1, (cy + 1) * h / 6 - 1),
                      cv::Scalar(200, 200, 255), cv::FILLED);
  for (int k = 1; k < 8; ++k)
    cv::line(img, cv::Point(k * w / 8, 0), cv::Point(k * w / 8, h - 1), cv::Scalar(180, 180, 180), 1);
  for (int k = 1; k < 6; ++k)
    cv::line(img, cv::Point(0, k * h / 6), cv::Point(w - 1, k * h / 6), cv::Scalar(180, 180, 180), 1);
  const int r = std::max(2, w / 320);
  for (std::size_t i = 0; i < views.size() && i < calibration.views.size(); ++i) {
    const bool used = calibration.views[i].used;
    cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(static_cast<double>((i * 37) % 180), 255, 200)), bgr;
    cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
    const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
    for (const auto &f : views[i].features) {
      const cv::Point p(static_cast<int>(std::lround(f.u)), static_cast<int>(std::lround(f.v)));
      if (used)
        cv::circle(img, p, r, cv::Scalar(c[0], c[1], c[2]), cv::FILLED, cv::LINE_AA);
      else {
        cv::line(img, p - cv::Point(r + 1, r + 1), p + cv::Point(r + 1, r + 1), cv::Scalar(0, 0, 255), 1);
        cv::line(img, p - cv::Point(r + 1, -r - 1), p + cv::Point(r + 1, -r - 1), cv::Scalar(0, 0, 255), 1);
      }
    }
  }
  const double scale = std::max(0.4, w / 1600.0);
  // Projection uncertainty per cell (px, 1 sigma): where the calibration knows the lens least.
  if (calibration.uncertainty_grid.size() == 48)
    for (int cy = 0; cy < 6; ++cy)
      for (int cx = 0; cx < 8; ++cx) {
        const double s = calibration.uncertainty_grid[static_cast<std::size_t>(cy) * 8 + cx];
        const std::string t = std::isfinite(s) ? fixed(s, s < 0.1 ? 3 : 2) : std::string("inf");
        const cv::Scalar col = !(s < 0.1) ? cv::Scalar(0, 0, 200) : s < 0.05 ? cv::Scalar(0, 140, 0) : cv::Scalar(0, 120, 220);
        cv::putText(img, t, cv::Point(cx * w / 8 + 4, (cy + 1) * h / 6 - 6), cv::FONT_HERSHEY_SIMPLEX, 0.8 * scale, col, 1,
                    cv::LINE_AA);
      }
  const std::string text = std::to_string(calibration.views_used) + " views, coverage " +
                           fixed(100 * calibration.coverage, 0) + " % (shaded: no corner); per cell: projection 1-sigma (px)";
  cv::putText(img, text, cv::Point(8, static_cast<int>(20 * scale / 0.4)), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return img;
}

std::string coverageImageBytes(const CameraCalibration &calibration, const std::vector<CalibrationView> &views,
                               const std::string &extension)
{
  const cv::Mat img = coverageImage(calibration, views);
  std::vector<unsigned char> bytes;
  bool ok = false;
  try {
    ok = cv::imencode(extension, img, bytes);
  } catch (const cv::Exception &e) {
    throw Error("coverage picture: cannot encode as '" + extension + "' (" + calibration_detail::oneLine(e.err) + ")");
  }
  if (!ok)
    throw Error("coverage picture: cannot encode as '" + extension + "'");
  return std::string(bytes.begin(), bytes.end());
}

void writeCoverageImage(const std::string &path, const CameraCalibration &calibration,
                        const std::vector<CalibrationView> &views)
{
  const std::string ext = std::filesystem::path(path).extension().string();
  writeFileAtomically(path, coverageImageBytes(calibration, views, ext.empty() ? std::string(".png") : ext));
}
} // namespace yawdepth
