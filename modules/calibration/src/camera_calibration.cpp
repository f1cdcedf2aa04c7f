/*!
  \file camera_calibration.cpp
  \brief Camera calibration: OpenCV's Brown and Kannala-Brandt (cv::fisheye) models, ViSP's two
  models, diagnostics.
*/
#include "board_pose.h"
#include "text.h"

#include <yawdepth/calibration/camera_calibration.h>
#include <yawdepth/camera/camera_file.h>
#include "quiet_visp.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <mutex>
#include <streambuf>
#include <sstream>
#include <unistd.h>
#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <visp3/core/vpException.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpXmlParserCamera.h>
#include <visp3/vision/vpCalibration.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

using calibration_detail::fixed;
using calibration_detail::kDeg;
using calibration_detail::num;


std::string oneLine(std::string s)
{
  for (char &c : s)
    if (c == '\n' || c == '\r' || c == '\t')
      c = ' ';
  while (!s.empty() && s.back() == ' ')
    s.pop_back();
  return s;
}

/*! Tries a chessboard of another size on a few images: the usual mistake is counting squares. */
std::string sizeHint(const BoardLayout &board, const std::vector<cv::Mat> &images, const DetectorOptions &options)
{
  if (board.pattern.kind != PatternSpec::Kind::Chessboard)
    return {};
  const int c = board.pattern.cols, r = board.pattern.rows;
  // One image only: a failed search costs OpenCV's exhaustive detector a second or so.
  const std::pair<int, int> candidates[] = {{c - 1, r - 1}, {c + 1, r + 1}, {c - 1, r}, {c, r - 1}};
  DetectorOptions fast = options;
  fast.subpixel = false;
  for (std::size_t i = 0; i < images.size() && i < 1; ++i) {
    if (images[i].empty())
      continue;
    for (const auto &cand : candidates) {
      if (cand.first < 3 || cand.second < 3)
        continue;
      PatternSpec p = board.pattern;
      p.cols = cand.first;
      p.rows = cand.second;
      try {
        PatternDetector d(p, fast);
        if (d.detect(images[i], 0).found)
          return "; a " + std::to_string(cand.first) + "x" + std::to_string(cand.second) +
                 " chessboard is there: COLSxROWS counts inner corners (squares minus one), use --pattern " +
                 p.toString();
      } catch (const Error &) {
      }
    }
  }
  return {};
}

/* The largest angle between two of the unit vectors (board normals). */
double largestAngle(const std::vector<Eigen::Vector3d> &normals)
{
  double spread = 0;
  for (std::size_t i = 0; i < normals.size(); ++i)
    for (std::size_t j = i + 1; j < normals.size(); ++j)
      spread = std::max(spread, std::acos(std::clamp(normals[i].dot(normals[j]), -1.0, 1.0)));
  return spread;
}

/* The cell of a pixel in the image's 8 x 6 grid, row by row (computed in the pixel's own type). */
template <class T>
std::size_t coverageCell(T x, T y, int width, int height)
{
  const int cx = std::clamp(static_cast<int>(x / width * 8), 0, 7);
  const int cy = std::clamp(static_cast<int>(y / height * 6), 0, 5);
  return static_cast<std::size_t>(cy) * 8 + cx;
}

/*! Board normal (camera frame) from a homography with a guessed camera, for a failed calibration. */
double homographySpread(const std::map<long, Eigen::Vector3d> &pts, const std::vector<CalibrationView> &views, int width,
                        int height)
{
  const double f = std::max(width, height);
  const Eigen::Matrix3d Kinv =
      (Eigen::Matrix3d() << f, 0, 0.5 * (width - 1), 0, f, 0.5 * (height - 1), 0, 0, 1).finished().inverse();
  std::vector<Eigen::Vector3d> normals;
  for (const auto &v : views) {
    std::vector<cv::Point2d> src, dst;
    for (const auto &ft : v.features) {
      auto it = pts.find(ft.id);
      if (it == pts.end())
        continue;
      src.emplace_back(it->second.x(), it->second.y());
      dst.emplace_back(ft.u, ft.v);
    }
    if (src.size() < 4)
      continue;
    const cv::Mat H = cv::findHomography(src, dst);
    if (H.empty())
      continue;
    Eigen::Matrix3d He;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        He(i, j) = H.at<double>(i, j);
    const Eigen::Matrix3d A = Kinv * He;
    const Eigen::Vector3d r1 = A.col(0).normalized(), r2 = A.col(1).normalized();
    Eigen::Vector3d n = r1.cross(r2);
    if (n.norm() < 1e-9)
      continue;
    n.normalize();
    if (n.z() < 0)
      n = -n;
    normals.push_back(n);
  }
  return largestAngle(normals);
}


struct OpenCvSolution {
  cv::Mat K, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intrinsics;
};

using Distortion = CameraCalibrationOptions::Distortion;

int coefficientsOf(Distortion d) { return d == Distortion::K8 ? 8 : d == Distortion::K5 ? 5 : 4; }

std::string modelName(Distortion d) {
  if (d == Distortion::Fisheye)
    return "Kannala-Brandt k1..k4 (fisheye)";
  return d == Distortion::K8 ? "k1..k6 p1 p2 (rational)" : d == Distortion::K5 ? "k1 k2 p1 p2 k3" : "k1 k2 p1 p2";
}

/*! cv::fisheye's flags under the options (it has no aspect-ratio constraint and no tangential terms). */
int fisheyeFlags(const CameraCalibrationOptions &o) {
  int flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW;
  if (o.fix_principal_point)
    flags |= cv::fisheye::CALIB_FIX_PRINCIPAL_POINT;
  return flags;
}

/*! The projection of a view's board points through a fit's K and distortion (`d`: its model). */
std::vector<cv::Point2f> projectView(const std::vector<cv::Point3f> &obj, const cv::Mat &rvec, const cv::Mat &tvec,
                                     const cv::Mat &K, const cv::Mat &dist, Distortion d) {
  std::vector<cv::Point2f> proj;
  if (d == Distortion::Fisheye)
    cv::fisheye::projectPoints(obj, proj, rvec, tvec, K, dist);
  else
    cv::projectPoints(obj, rvec, tvec, K, dist, proj);
  return proj;
}

/*! OpenCV flags of a model under the options' other constraints. */
int modelFlags(Distortion d, const CameraCalibrationOptions &o) {
  int flags = 0;
  if (d == Distortion::K4)
    flags |= cv::CALIB_FIX_K3;
  if (d == Distortion::K8)
    flags |= cv::CALIB_RATIONAL_MODEL;
  if (o.zero_tangential)
    flags |= cv::CALIB_ZERO_TANGENT_DIST;
  if (o.fix_aspect_ratio)
    flags |= cv::CALIB_FIX_ASPECT_RATIO;
  if (o.fix_principal_point)
    flags |= cv::CALIB_FIX_PRINCIPAL_POINT;
  return flags;
}

/*!
  The map from the free parameters of a fit to fx fy u0 v0 k1 k2 p1 p2 k3 k4 k5 k6 (12 x free):
  fixed parameters have zero rows; with a fixed aspect ratio fx = (fx / fy) fy moves with fy.
*/
Eigen::MatrixXd freeParameterMap(Distortion d, const CameraCalibrationOptions &o, double aspect) {
  std::vector<Eigen::VectorXd> cols;
  auto unit = [](int i) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(12);
    e[i] = 1;
    return e;
  };
  if (d == Distortion::Fisheye) { // fx fy u0 v0 k1..k4 in the first eight places
    for (int i = 0; i < 8; ++i)
      if (!(o.fix_principal_point && (i == 2 || i == 3)))
        cols.push_back(unit(i));
  } else if (o.fix_aspect_ratio) {
    Eigen::VectorXd e = unit(1);
    e[0] = aspect;
    cols.push_back(e);
  } else {
    cols.push_back(unit(0));
    cols.push_back(unit(1));
  }
  if (d != Distortion::Fisheye) {
    if (!o.fix_principal_point) {
      cols.push_back(unit(2));
      cols.push_back(unit(3));
    }
    cols.push_back(unit(4));
    cols.push_back(unit(5));
    if (!o.zero_tangential) {
      cols.push_back(unit(6));
      cols.push_back(unit(7));
    }
    if (d != Distortion::K4)
      cols.push_back(unit(8));
    if (d == Distortion::K8)
      for (int i = 9; i < 12; ++i)
        cols.push_back(unit(i));
  }
  Eigen::MatrixXd S(12, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j)
    S.col(static_cast<Eigen::Index>(j)) = cols[j];
  return S;
}

/*! d(pixel)/d(fx fy u0 v0 k1..k6) (2N x 12) and d(pixel)/d(rvec tvec) (2N x 6) of OpenCV's projection;
    for the fisheye model (`fisheye`, cv::fisheye's projection) d(pixel)/d(fx fy u0 v0 k1..k4) in the
    first eight columns. */
void projectionJacobians(const std::vector<cv::Point3f> &obj, const cv::Mat &rvec, const cv::Mat &tvec, const cv::Mat &K,
                         const cv::Mat &dist, bool fisheye, Eigen::MatrixXd &Jint, Eigen::MatrixXd &Jpose,
                         std::vector<cv::Point2d> *proj = nullptr) {
  std::vector<cv::Point3d> o(obj.begin(), obj.end());
  std::vector<cv::Point2d> p;
  cv::Mat J;
  if (fisheye) // columns: f (2), c (2), k (4), rvec (3), tvec (3), skew (1)
    cv::fisheye::projectPoints(o, p, rvec, tvec, K, dist, 0.0, J);
  else // columns: rvec (3), tvec (3), f (2), c (2), distortion
    cv::projectPoints(o, rvec, tvec, K, dist, p, J);
  const int n = static_cast<int>(o.size());
  const int nd = static_cast<int>(dist.total());
  Jint = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(n), 12);
  Jpose = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(n), 6);
  for (int r = 0; r < 2 * n; ++r) {
    const double *row = J.ptr<double>(r);
    const int pose0 = fisheye ? 8 : 0, int0 = fisheye ? 0 : 6;
    for (int c = 0; c < 6; ++c)
      Jpose(r, c) = row[pose0 + c];
    for (int c = 0; c < 4; ++c)
      Jint(r, c) = row[int0 + c];
    for (int c = 0; c < std::min(nd, 8); ++c)
      Jint(r, 4 + c) = row[fisheye ? 4 + c : 10 + c];
  }
  if (proj)
    *proj = p;
}

/* The views' message when the board's orientation hardly varies (the focal length is then unknown). */
std::string degenerateMessage(double spread, std::size_t n)
{
  return "degenerate views: the board's orientation varies by only " + fixed(spread / kDeg, 1) + " deg over the " +
         std::to_string(n) + " views (all fronto-parallel or all tilted alike); the focal length cannot be "
         "told from the distance: tilt the board 20 to 45 degrees in different directions";
}

/* Adds the squared pixel errors of projections against the observed points to sse (a float
   projection is differenced in float, as before). */
template <class Point>
void addSquaredErrors(const std::vector<Point> &proj, const std::vector<cv::Point2f> &observed, double &sse)
{
  for (std::size_t j = 0; j < proj.size(); ++j) {
    const double du = proj[j].x - observed[j].x, dv = proj[j].y - observed[j].y;
    sse += du * du + dv * dv;
  }
}

/* The camera of a fit: Brown (5 coefficients, 8 for the rational model) or Kannala-Brandt (4). */
CameraModel cameraOf(const OpenCvSolution &s, Distortion d, int width, int height)
{
  std::vector<double> c(static_cast<std::size_t>(d == Distortion::K8 ? 8 : d == Distortion::Fisheye ? 4 : 5));
  for (std::size_t i = 0; i < c.size(); ++i)
    c[i] = s.dist.at<double>(static_cast<int>(i));
  if (d == Distortion::Fisheye)
    return CameraModel::kannalaBrandt(s.K.at<double>(0, 0), s.K.at<double>(1, 1), s.K.at<double>(0, 2),
                                      s.K.at<double>(1, 2), c, static_cast<unsigned>(width),
                                      static_cast<unsigned>(height));
  return CameraModel::brown(s.K.at<double>(0, 0), s.K.at<double>(1, 1), s.K.at<double>(0, 2), s.K.at<double>(1, 2), c,
                            static_cast<unsigned>(width), static_cast<unsigned>(height));
}

/* Projection uncertainty at the centres of the 8 x 6 cells of the image, row by row. */
std::vector<double> uncertaintyGrid(const CameraCalibration &calibration, int width, int height)
{
  std::vector<double> grid;
  for (int cy = 0; cy < 6; ++cy)
    for (int cx = 0; cx < 8; ++cx)
      grid.push_back(projectionUncertainty(calibration, (cx + 0.5) * width / 8.0 - 0.5, (cy + 0.5) * height / 6.0 - 0.5));
  return grid;
}

/* The board's correspondences in every view, and OpenCV's fits and their diagnostics on subsets of
   the views (`idx`: indices into `views`; a fit's poses follow idx's order). */
struct CameraFit {
  const std::map<long, Eigen::Vector3d> pts;
  const std::vector<CalibrationView> &views;
  const int width, height;
  const CameraCalibrationOptions &options;
  std::vector<std::vector<cv::Point3f>> object; // per view: board points with a finite observation
  std::vector<std::vector<cv::Point2f>> image;  // per view: their pixels

  OpenCvSolution solve(const std::vector<std::size_t> &idx, Distortion d) const;
  double heldOut(const std::vector<std::size_t> &idx, Distortion d, const OpenCvSolution &all) const;
  bool intrinsicsCovariance(const std::vector<std::size_t> &idx, const OpenCvSolution &s, Distortion d,
                            Eigen::Matrix<double, 12, 12> &out) const;
  std::string admissibility(const OpenCvSolution &s, Distortion d, const std::vector<std::size_t> &idx) const;
};

OpenCvSolution CameraFit::solve(const std::vector<std::size_t> &idx, Distortion d) const
{
  if (d == Distortion::Fisheye && options.fix_aspect_ratio)
    throw Error("the fisheye model (cv::fisheye) cannot keep fx = fy: drop --fix-aspect-ratio (fix_aspect_ratio)");
  const int flags = modelFlags(d, options);
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> img;
  std::vector<CalibrationView> sel;
  for (std::size_t i : idx) {
    obj.push_back(object[i]);
    img.push_back(image[i]);
    sel.push_back(views[i]);
  }
  // Before OpenCV: a homography-based orientation check (independent of the focal length's value
  // for fronto-parallel boards, whose homographies have no perspective part).
  const double pre = homographySpread(pts, sel, width, height);
  if (pre < 0.25 * options.min_orientation_spread)
    throw Error(degenerateMessage(pre, idx.size()));
  OpenCvSolution s;
  s.K = cv::Mat::eye(3, 3, CV_64F);
  s.dist = cv::Mat::zeros(1, d == Distortion::K8 ? 8 : d == Distortion::Fisheye ? 4 : 5, CV_64F);
  cv::Mat std_ext, per_view;
  try {
    if (d == Distortion::Fisheye)
      cv::fisheye::calibrate(obj, img, cv::Size(width, height), s.K, s.dist, s.rvecs, s.tvecs, fisheyeFlags(options),
                             cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-15));
    else
      cv::calibrateCamera(obj, img, cv::Size(width, height), s.K, s.dist, s.rvecs, s.tvecs, s.std_intrinsics, std_ext,
                          per_view, flags, cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-15));
  } catch (const cv::Exception &e) {
    if (pre < options.min_orientation_spread)
      throw Error(degenerateMessage(pre, idx.size()));
    throw Error("calibration failed (OpenCV: " + oneLine(e.err) + ")");
  }
  const double fx = s.K.at<double>(0, 0), fy = s.K.at<double>(1, 1);
  if (!cv::checkRange(s.K) || !cv::checkRange(s.dist) || !(fx > 0) || !(fy > 0)) {
    if (pre < options.min_orientation_spread)
      throw Error(degenerateMessage(pre, idx.size()));
    throw Error("calibration failed: no finite solution (views too few or too alike?)");
  }
  return s;
}

// Held-out error of a model: views left out in folds, each predicted by a calibration without
// it (its pose fitted to its own corners). Infinite when a fold's calibration fails.
double CameraFit::heldOut(const std::vector<std::size_t> &idx, Distortion d, const OpenCvSolution &all) const
{
  const std::size_t folds = std::min<std::size_t>(idx.size(), static_cast<std::size_t>(std::max(2, options.cv_folds)));
  double sse = 0;
  std::size_t n = 0;
  for (std::size_t f = 0; f < folds; ++f) {
    std::vector<std::vector<cv::Point3f>> obj;
    std::vector<std::vector<cv::Point2f>> img;
    for (std::size_t k = 0; k < idx.size(); ++k)
      if (k % folds != f) {
        obj.push_back(object[idx[k]]);
        img.push_back(image[idx[k]]);
      }
    // Started from the fit on every view: a fold's solution is near it.
    cv::Mat K = all.K.clone(), dist = all.dist.clone();
    std::vector<cv::Mat> rv, tv;
    try {
      const cv::TermCriteria stop(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12);
      if (d == Distortion::Fisheye)
        cv::fisheye::calibrate(obj, img, cv::Size(width, height), K, dist, rv, tv,
                               fisheyeFlags(options) | cv::fisheye::CALIB_USE_INTRINSIC_GUESS, stop);
      else
        cv::calibrateCamera(obj, img, cv::Size(width, height), K, dist, rv, tv,
                            modelFlags(d, options) | cv::CALIB_USE_INTRINSIC_GUESS, stop);
      if (!cv::checkRange(K) || !cv::checkRange(dist))
        return std::numeric_limits<double>::infinity();
      for (std::size_t k = f; k < idx.size(); k += folds) {
        cv::Mat r, t;
        bool posed = false;
        if (d == Distortion::Fisheye) { // the pose from the undistorted (normalised) corners
          std::vector<cv::Point2f> normalised;
          cv::fisheye::undistortPoints(image[idx[k]], normalised, K, dist, cv::noArray(), cv::noArray(),
                                       cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-14));
          posed = cv::solvePnP(object[idx[k]], normalised, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), r, t, false,
                               cv::SOLVEPNP_ITERATIVE);
        } else {
          posed = cv::solvePnP(object[idx[k]], image[idx[k]], K, dist, r, t, false, cv::SOLVEPNP_ITERATIVE);
        }
        if (!posed)
          return std::numeric_limits<double>::infinity();
        const std::vector<cv::Point2f> proj = projectView(object[idx[k]], r, t, K, dist, d);
        addSquaredErrors(proj, image[idx[k]], sse);
        n += proj.size();
      }
    } catch (const cv::Exception &) {
      return std::numeric_limits<double>::infinity();
    }
  }
  const double r = std::sqrt(sse / static_cast<double>(std::max<std::size_t>(n, 1)));
  return std::isfinite(r) ? r : std::numeric_limits<double>::infinity();
}

// Covariance of the intrinsics: Gauss-Newton normal equations of a fit, the poses marginalised
// view by view (Schur complement), the residual variance over 2N - parameters. False (and zero)
// when the reduced normal matrix is singular after scaling each parameter to unit diagonal.
bool CameraFit::intrinsicsCovariance(const std::vector<std::size_t> &idx, const OpenCvSolution &s, Distortion d,
                                     Eigen::Matrix<double, 12, 12> &out) const
{
  out.setZero();
  const Eigen::MatrixXd S = freeParameterMap(d, options, s.K.at<double>(0, 0) / s.K.at<double>(1, 1));
  const Eigen::Index nf = S.cols();
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(nf, nf);
  double sse = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < idx.size(); ++k) {
    Eigen::MatrixXd Jint, Jpose;
    std::vector<cv::Point2d> proj;
    projectionJacobians(object[idx[k]], s.rvecs[k], s.tvecs[k], s.K, s.dist, d == Distortion::Fisheye, Jint, Jpose,
                        &proj);
    const Eigen::MatrixXd B = Jint * S;
    const Eigen::Matrix<double, 6, 6> V = Jpose.transpose() * Jpose;
    const Eigen::MatrixXd W = B.transpose() * Jpose;
    U += B.transpose() * B - W * V.ldlt().solve(W.transpose());
    addSquaredErrors(proj, image[idx[k]], sse);
    n += proj.size();
  }
  const double dof = 2.0 * static_cast<double>(n) - static_cast<double>(nf) - 6.0 * static_cast<double>(idx.size());
  if (!(dof > 0))
    return false;
  const Eigen::VectorXd dg = U.diagonal();
  if (!(dg.minCoeff() > 0))
    return false;
  const Eigen::VectorXd sc = dg.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd Us = sc.asDiagonal() * U * sc.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Us);
  if (!(es.eigenvalues().minCoeff() > 1e-12 * es.eigenvalues().maxCoeff()))
    return false;
  const Eigen::MatrixXd cov = (sse / dof) * (sc.asDiagonal() * es.eigenvectors() *
                                             es.eigenvalues().cwiseInverse().asDiagonal() *
                                             es.eigenvectors().transpose() * sc.asDiagonal());
  out = S * cov * S.transpose();
  return out.allFinite();
}

// A fit is admissible when its camera is usable over the whole image (what loadCameraFile()
// would accept): a high-order model can bend back beyond the corners' reach. Empty when it is.
std::string CameraFit::admissibility(const OpenCvSolution &s, Distortion d, const std::vector<std::size_t> &idx) const
{
  Eigen::Matrix<double, 12, 12> cov;
  if (!intrinsicsCovariance(idx, s, d, cov))
    return modelName(d) + ": the views do not determine its parameters (singular covariance)";
  try {
    checkCameraPlausible(cameraOf(s, d, width, height), modelName(d));
  } catch (const Error &e) {
    return e.what();
  }
  return {};
}

/* Fills fit.object and fit.image and the views' names and point counts; the views with enough
   points (the others are marked unused, with a note). */
std::vector<std::size_t> collectCorrespondences(CameraFit &fit, CameraCalibration &result)
{
  const std::vector<CalibrationView> &views = fit.views;
  result.views.resize(views.size());
  fit.object.assign(views.size(), {});
  fit.image.assign(views.size(), {});
  std::vector<std::size_t> usable;
  for (std::size_t i = 0; i < views.size(); ++i) {
    result.views[i].name = views[i].name;
    for (const auto &f : views[i].features) {
      auto it = fit.pts.find(f.id);
      if (it == fit.pts.end() || !std::isfinite(f.u) || !std::isfinite(f.v))
        continue;
      fit.object[i].emplace_back(static_cast<float>(it->second.x()), static_cast<float>(it->second.y()), 0.0f);
      fit.image[i].emplace_back(static_cast<float>(f.u), static_cast<float>(f.v));
    }
    result.views[i].points = static_cast<int>(fit.object[i].size());
    if (result.views[i].points >= std::max(4, fit.options.min_points_per_view))
      usable.push_back(i);
    else {
      result.views[i].used = false;
      result.notes.push_back(views[i].name + ": only " + std::to_string(result.views[i].points) +
                             " points, view not used");
    }
  }
  return usable;
}

/* A model fitted on the usable views and scored: RMS, held-out RMS, projection uncertainty over
   the image and their combination (or why the model is not usable). */
DistortionModelScore scoreModel(const CameraFit &fit, const std::vector<std::size_t> &usable, Distortion d)
{
  DistortionModelScore m;
  m.name = modelName(d);
  m.coefficients = coefficientsOf(d);
  m.fisheye = d == Distortion::Fisheye;
  const OpenCvSolution s = fit.solve(usable, d);
  double sse = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < usable.size(); ++k) {
    const std::vector<cv::Point2f> proj = projectView(fit.object[usable[k]], s.rvecs[k], s.tvecs[k], s.K, s.dist, d);
    addSquaredErrors(proj, fit.image[usable[k]], sse);
    n += proj.size();
  }
  m.rms_px = std::sqrt(sse / static_cast<double>(n));
  m.heldout_rms_px = fit.heldOut(usable, d, s);
  m.inadmissible = fit.admissibility(s, d, usable);
  if (m.inadmissible.empty()) {
    CameraCalibration tmp;
    tmp.camera = cameraOf(s, d, fit.width, fit.height);
    fit.intrinsicsCovariance(usable, s, d, tmp.intrinsics_covariance);
    double u2 = 0;
    for (double u : uncertaintyGrid(tmp, fit.width, fit.height))
      u2 += u * u / 48.0;
    m.image_uncertainty_px = std::sqrt(u2);
    m.score_px = std::hypot(m.heldout_rms_px, m.image_uncertainty_px);
    if (!std::isfinite(m.score_px))
      m.inadmissible = m.name + ": its projection cannot be computed over the whole image";
  }
  return m;
}

/* Why model `pick` was chosen among the scored ones (`best`: the least score). */
std::string modelReason(const std::vector<DistortionModelScore> &models, std::size_t pick, std::size_t best,
                        double simpler_within)
{
  std::ostringstream why;
  why << models[pick].name << ": expected error over the image " << fixed(models[pick].score_px, 4) << " px";
  bool first = true;
  for (std::size_t i = 0; i < models.size(); ++i)
    if (i != pick) {
      why << (first ? " against " : ", ")
          << (models[i].inadmissible.empty() ? fixed(models[i].score_px, 4) : std::string("not usable")) << " ("
          << (models[i].fisheye ? std::string("fisheye") : std::to_string(models[i].coefficients) + " coefficients")
          << ")";
      first = false;
    }
  if (pick != best)
    why << "; the simpler model is within " << fixed(100 * simpler_within, 0) << " % of the best";
  return why.str();
}

/* Among the scored K4, K5, K8 and (when tried) the fisheye model, in this order: the simplest
   usable one within `simpler_within` of the best score, marked chosen; the reason into `reason`.
   Throws when none is usable. */
Distortion pickModel(std::vector<DistortionModelScore> &models, double simpler_within, std::string &reason)
{
  std::size_t best = models.size();
  for (std::size_t i = 0; i < models.size(); ++i)
    if (models[i].inadmissible.empty() && std::isfinite(models[i].score_px) &&
        (best == models.size() || models[i].score_px < models[best].score_px))
      best = i;
  if (best == models.size()) {
    std::string why;
    for (const auto &m : models)
      why += (why.empty() ? "" : "; ") + m.name + ": " +
             (m.inadmissible.empty() ? std::string("its calibration failed on views left out") : m.inadmissible);
    throw Error("no distortion model gives a usable camera (" + why +
                "): take views whose corners reach the image's corners and edges");
  }
  std::size_t pick = best;
  for (std::size_t i = 0; i < best; ++i) // the simplest within the margin
    if (models[i].inadmissible.empty() && models[i].score_px <= (1 + simpler_within) * models[best].score_px) {
      pick = i;
      break;
    }
  models[pick].chosen = true;
  reason = modelReason(models, pick, best, simpler_within);
  return pick == 0 ? Distortion::K4 : pick == 1 ? Distortion::K5 : pick == 2 ? Distortion::K8 : Distortion::Fisheye;
}

/* The distortion model: given, or chosen by the held-out error (result.models, model_reason). */
Distortion chooseModel(const CameraFit &fit, const std::vector<std::size_t> &usable, CameraCalibration &result)
{
  Distortion model = fit.options.distortion;
  if (model == Distortion::Auto && fit.options.estimate_k3)
    model = Distortion::K5;
  if (model != Distortion::Auto) {
    DistortionModelScore m;
    m.name = modelName(model);
    m.coefficients = coefficientsOf(model);
    m.fisheye = model == Distortion::Fisheye;
    m.chosen = true;
    result.models.push_back(m);
    result.model_reason = modelName(model) + ": as asked";
    return model;
  }
  if (usable.size() < 4) {
    model = Distortion::K4;
    result.model_reason = "k1 k2 p1 p2: too few views (" + std::to_string(usable.size()) +
                          ") to compare models on views left out";
    DistortionModelScore m;
    m.name = modelName(model);
    m.coefficients = 4;
    m.chosen = true;
    result.models.push_back(m);
    return model;
  }
  for (Distortion d : {Distortion::K4, Distortion::K5, Distortion::K8})
    result.models.push_back(scoreModel(fit, usable, d));
  if (fit.options.try_fisheye) {
    try {
      result.models.push_back(scoreModel(fit, usable, Distortion::Fisheye));
    } catch (const Error &e) { // cv::fisheye failed (or cannot keep the aspect ratio): not usable
      DistortionModelScore m;
      m.name = modelName(Distortion::Fisheye);
      m.coefficients = 4;
      m.fisheye = true;
      m.inadmissible = m.name + ": " + e.what();
      result.models.push_back(m);
    }
  }
  return pickModel(result.models, fit.options.simpler_within, result.model_reason);
}

/* A fit's board poses into the used views' results (pose, tilt); the largest angle between the
   board normals. */
double storeBoardPoses(const OpenCvSolution &sol, const std::vector<std::size_t> &used, CameraCalibration &result)
{
  std::vector<Eigen::Vector3d> normals;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const Eigen::Isometry3d M = calibration_detail::isometryOf(sol.rvecs[k], sol.tvecs[k]);
    CalibrationViewResult &vr = result.views[used[k]];
    vr.cMb = M;
    const Eigen::Vector3d n = M.linear().col(2);
    vr.tilt = std::acos(std::min(1.0, std::abs(n.z())));
    normals.push_back(n);
  }
  return largestAngle(normals);
}

/* A fit's reprojection RMS of each used view (into its result, and returned in used's order) and
   over all (result.rms_px), in double precision. */
std::vector<double> storeViewErrors(const CameraFit &fit, const OpenCvSolution &sol, Distortion model,
                                    const std::vector<std::size_t> &used, CameraCalibration &result)
{
  double sum2 = 0;
  std::size_t n_all = 0;
  std::vector<double> rms;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const std::vector<cv::Point2f> proj =
        projectView(fit.object[used[k]], sol.rvecs[k], sol.tvecs[k], sol.K, sol.dist, model);
    double s2 = 0;
    addSquaredErrors(proj, fit.image[used[k]], s2);
    sum2 += s2;
    n_all += proj.size();
    result.views[used[k]].rms_px = std::sqrt(s2 / static_cast<double>(proj.size()));
    rms.push_back(result.views[used[k]].rms_px);
  }
  result.rms_px = std::sqrt(sum2 / static_cast<double>(n_all));
  return rms;
}

/* Flags the outlier views (on the first pass only: RMS above ratio x the median and above the
   floor); the used views that are not, and the median RMS in `median`. */
std::vector<std::size_t> flagOutliers(const std::vector<double> &rms, const std::vector<std::size_t> &used, int pass,
                                      const CameraCalibrationOptions &options, CameraCalibration &result, double &median)
{
  std::vector<double> sorted = rms;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  median = sorted[sorted.size() / 2];
  std::vector<std::size_t> kept;
  for (std::size_t k = 0; k < used.size(); ++k) {
    CalibrationViewResult &vr = result.views[used[k]];
    vr.outlier = pass == 0 && rms[k] > options.outlier_ratio * median && rms[k] > options.outlier_min_px;
    if (!vr.outlier)
      kept.push_back(used[k]);
  }
  return kept;
}

/* The fit of `model` on the `used` views, refitted once without its outlier views when the
   options drop them (`used` then the views kept); poses, errors and spread into result. */
OpenCvSolution fitDroppingOutliers(const CameraFit &fit, Distortion model, int min_views, std::vector<std::size_t> &used,
                                   CameraCalibration &result)
{
  const CameraCalibrationOptions &options = fit.options;
  OpenCvSolution sol;
  for (int pass = 0; pass < 2; ++pass) {
    sol = fit.solve(used, model);
    result.orientation_spread = storeBoardPoses(sol, used, result);
    if (result.orientation_spread < options.min_orientation_spread)
      throw Error(degenerateMessage(result.orientation_spread, used.size()));
    const std::vector<double> rms = storeViewErrors(fit, sol, model, used, result);
    double median = 0;
    const std::vector<std::size_t> kept = flagOutliers(rms, used, pass, options, result, median);
    if (pass == 1 || !options.drop_outliers || kept.size() == used.size())
      break;
    if (static_cast<int>(kept.size()) < min_views)
      throw Error("too few views: " + std::to_string(kept.size()) + " left after dropping " +
                  std::to_string(used.size() - kept.size()) + " outlier view(s), at least " +
                  std::to_string(min_views) + " are needed");
    for (std::size_t i : used)
      if (std::find(kept.begin(), kept.end(), i) == kept.end()) {
        result.views[i].used = false;
        result.views[i].outlier = true;
        result.notes.push_back(result.views[i].name + ": outlier view dropped (RMS " + fixed(result.views[i].rms_px) +
                               " px against a median of " + fixed(median) + " px)");
      }
    used = kept;
  }
  return sol;
}

/* The final fit's camera (refused when not usable over the image), its covariance, standard
   deviations and uncertainty grid. */
void storeCamera(const CameraFit &fit, const OpenCvSolution &sol, Distortion model, const std::vector<std::size_t> &used,
                 CameraCalibration &result)
{
  result.camera = cameraOf(sol, model, fit.width, fit.height);
  const std::string bad = fit.admissibility(sol, model, used);
  if (!bad.empty())
    throw Error("the calibrated camera is not usable: " + bad +
                "; take views whose corners reach the image's corners and edges" +
                (model != Distortion::K4 ? std::string(", or a model with fewer coefficients") : std::string()));
  for (auto &m : result.models)
    if (m.chosen && m.rms_px == 0)
      m.rms_px = result.rms_px;
  if (!fit.intrinsicsCovariance(used, sol, model, result.intrinsics_covariance))
    result.notes.emplace_back("the intrinsics' covariance is singular: the views do not determine every parameter");
  result.std_devs.assign(12, 0.0);
  for (int i = 0; i < 12; ++i)
    result.std_devs[static_cast<std::size_t>(i)] = std::sqrt(std::max(0.0, result.intrinsics_covariance(i, i)));
  result.uncertainty_grid = uncertaintyGrid(result, fit.width, fit.height);
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

/* Notes on few views, poor coverage and outlier views kept. */
void addQualityNotes(CameraCalibration &result)
{
  if (result.views_used < 8)
    result.notes.push_back("only " + std::to_string(result.views_used) +
                           " views used: 10 to 20 views give more reliable parameters");
  if (result.coverage < 0.6)
    result.notes.push_back("the corners cover only " + fixed(100 * result.coverage, 0) +
                           " % of the image: the distortion is poorly known where there are none (see the coverage picture)");
  for (const auto &v : result.views)
    if (v.outlier && v.used)
      result.notes.push_back(v.name + ": outlier view (RMS " + fixed(v.rms_px) + " px); --drop-outliers recalibrates without it");
}

/* One vpCalibration per used view, with its board points and pixels. */
std::vector<vpCalibration> vispCalibrationTable(const CameraFit &fit, const std::vector<std::size_t> &used)
{
  std::vector<vpCalibration> table;
  for (std::size_t i : used) {
    vpCalibration calib;
    calib.clearPoint();
    if (fit.options.fix_aspect_ratio)
      calib.setAspectRatio(1.0);
    for (std::size_t j = 0; j < fit.object[i].size(); ++j) {
      vpImagePoint ip(fit.image[i][j].y, fit.image[i][j].x);
      calib.addPoint(fit.object[i][j].x, fit.object[i][j].y, fit.object[i][j].z, ip);
    }
    table.push_back(calib);
  }
  return table;
}

/* Reprojection RMS of ViSP's two models, each with its own poses (and of kdu, the inverse
   distortion), into result. */
void storeVispErrors(const CameraFit &fit, const std::vector<std::size_t> &used, const std::vector<vpCalibration> &table,
                     CameraCalibration &result)
{
  double s_wo = 0, s_w = 0, s_kdu = 0;
  std::size_t n = 0;
  const vpCameraParameters &cw = result.visp_with, &c0 = result.visp_without;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const std::size_t i = used[k];
    const vpHomogeneousMatrix &M0 = table[k].cMo, &M1 = table[k].cMo_dist;
    for (std::size_t j = 0; j < fit.object[i].size(); ++j) {
      const double X = fit.object[i][j].x, Y = fit.object[i][j].y, Z = fit.object[i][j].z;
      const double u = fit.image[i][j].x, v = fit.image[i][j].y;
      auto proj = [&](const vpHomogeneousMatrix &M, double &x, double &y) {
        const double cx = M[0][0] * X + M[0][1] * Y + M[0][2] * Z + M[0][3];
        const double cy = M[1][0] * X + M[1][1] * Y + M[1][2] * Z + M[1][3];
        const double cz = M[2][0] * X + M[2][1] * Y + M[2][2] * Z + M[2][3];
        x = cx / cz;
        y = cy / cz;
      };
      double x, y;
      proj(M0, x, y);
      s_wo += std::pow(c0.get_u0() + c0.get_px() * x - u, 2) + std::pow(c0.get_v0() + c0.get_py() * y - v, 2);
      proj(M1, x, y);
      const double r2 = x * x + y * y;
      s_w += std::pow(cw.get_u0() + cw.get_px() * x * (1 + cw.get_kud() * r2) - u, 2) +
             std::pow(cw.get_v0() + cw.get_py() * y * (1 + cw.get_kud() * r2) - v, 2);
      // kdu: observed pixel to undistorted pixel, compared with the pinhole projection.
      const double xd = (u - cw.get_u0()) / cw.get_px(), yd = (v - cw.get_v0()) / cw.get_py();
      const double f = 1 + cw.get_kdu() * (xd * xd + yd * yd);
      s_kdu += std::pow(cw.get_u0() + cw.get_px() * xd * f - (cw.get_u0() + cw.get_px() * x), 2) +
               std::pow(cw.get_v0() + cw.get_py() * yd * f - (cw.get_v0() + cw.get_py() * y), 2);
      ++n;
    }
  }
  result.visp_rms_without = std::sqrt(s_wo / static_cast<double>(n));
  result.visp_rms_with = std::sqrt(s_w / static_cast<double>(n));
  result.visp_rms_kdu = std::sqrt(s_kdu / static_cast<double>(n));
}

/* ViSP's two models, fitted by vpCalibration as ViSP's calibration tool does, from OpenCV's
   result; a note instead when they cannot be. */
void fitVispModels(const CameraFit &fit, const OpenCvSolution &sol, const std::vector<std::size_t> &used,
                   CameraCalibration &result)
{
  try {
    const detail::QuietVisp quiet; // vpCalibration prints, and its gain is a static
    std::vector<vpCalibration> table = vispCalibrationTable(fit, used);
    vpCalibration::setLambda(0.5);
    vpCameraParameters cam;
    cam.initPersProjWithoutDistortion(sol.K.at<double>(0, 0), sol.K.at<double>(1, 1), sol.K.at<double>(0, 2),
                                      sol.K.at<double>(1, 2));
    double err = 0;
    if (vpCalibration::computeCalibrationMulti(vpCalibration::CALIB_VIRTUAL_VS, table, cam, err, false) != 0)
      throw Error("vpCalibration failed (model without distortion)");
    result.visp_without = cam;
    if (vpCalibration::computeCalibrationMulti(vpCalibration::CALIB_VIRTUAL_VS_DIST, table, cam, err, false) != 0)
      throw Error("vpCalibration failed (model with distortion)");
    result.visp_with = cam;
    storeVispErrors(fit, used, table, result);
    result.visp_fitted = std::isfinite(result.visp_rms_with) && std::isfinite(result.visp_rms_without);
    if (!result.visp_fitted)
      result.notes.emplace_back("ViSP models: non-finite fit");
  } catch (const Error &e) {
    result.notes.push_back(std::string("ViSP models not fitted: ") + e.what());
  } catch (const vpException &e) {
    result.notes.push_back("ViSP models not fitted: " + oneLine(e.getStringMessage()));
  }
}

} // namespace

CalibrationDetections detectCalibrationViews(const BoardLayout &board, const std::vector<std::string> &names,
                                             const std::vector<cv::Mat> &images, const DetectorOptions &options,
                                             const std::function<void(std::size_t, std::size_t)> &progress)
{
  if (images.empty())
    throw Error("no calibration images given");
  if (names.size() != images.size())
    throw Error("detectCalibrationViews: " + std::to_string(names.size()) + " names for " +
                std::to_string(images.size()) + " images");
  const std::map<long, Eigen::Vector3d> pts = calibration_detail::boardPoints(board);
  PatternDetector detector(board.pattern, options);
  CalibrationDetections out;
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (progress)
      progress(i, images.size());
    const cv::Mat &img = images[i];
    if (img.empty()) {
      out.failures.push_back(names[i] + ": empty image");
      FrameDetection none;
      none.frame = static_cast<long>(i);
      none.reason = "empty image";
      out.detections.push_back(none);
      continue;
    }
    if (out.width == 0) {
      out.width = img.cols;
      out.height = img.rows;
    } else if (img.cols != out.width || img.rows != out.height) {
      throw Error(names[i] + ": image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) + " but " +
                  names.front() + " is " + std::to_string(out.width) + "x" + std::to_string(out.height) +
                  ": all calibration images must come from the same camera at the same resolution");
    }
    out.detections.push_back(detector.detect(img, static_cast<long>(i)));
    const FrameDetection &d = out.detections.back();
    for (const std::string &w : d.warnings)
      out.warnings.push_back(names[i] + ": " + w);
    if (!d.found) {
      out.failures.push_back(names[i] + ": " + d.reason);
      continue;
    }
    CalibrationView v;
    v.name = names[i];
    std::vector<long> off_board;
    for (const auto &f : d.features)
      if (pts.count(f.id))
        v.features.push_back(f);
      else
        off_board.push_back(f.id);
    if (!off_board.empty() && board.pattern.kind == PatternSpec::Kind::AprilTag) {
      std::set<long> tags;
      for (long id : off_board)
        tags.insert(id / 5); // pattern.h: tag t has features 5t .. 5t + 4
      std::string list;
      for (long t : tags)
        list += (list.empty() ? "" : " ") + std::to_string(t);
      out.warnings.push_back(names[i] + ": tag(s) " + list + " not on the board (--tags grid, --first-tag-id): ignored");
    }
    if (v.features.size() < 4) {
      out.failures.push_back(names[i] + ": only " + std::to_string(v.features.size()) +
                             " features of the board (tags outside the board's --tags grid?)");
      continue;
    }
    out.views.push_back(std::move(v));
  }
  if (out.views.empty()) {
    std::string msg = "the pattern " + board.pattern.toString() + " was not found in any of the " +
                      std::to_string(images.size()) + " images";
    if (!out.failures.empty())
      msg += " (" + out.failures.front() + ")";
    msg += sizeHint(board, images, options);
    throw Error(msg);
  }
  return out;
}

CameraCalibration calibrateCamera(const BoardLayout &board, const std::vector<CalibrationView> &views, int width,
                                  int height, const CameraCalibrationOptions &options)
{
  if (width <= 0 || height <= 0)
    throw Error("calibrateCamera: unknown image size");
  CameraFit fit{calibration_detail::boardPoints(board), views, width, height, options, {}, {}};
  CameraCalibration result;
  const std::vector<std::size_t> usable = collectCorrespondences(fit, result);
  const int min_views = std::max(1, options.min_views);
  if (static_cast<int>(usable.size()) < min_views)
    throw Error("too few views: " + std::to_string(usable.size()) + " usable view(s) of the board, at least " +
                std::to_string(min_views) + " are needed (10 to 20 views at different tilts are best)");
  const Distortion model = chooseModel(fit, usable, result);
  std::vector<std::size_t> used = usable;
  const OpenCvSolution sol = fitDroppingOutliers(fit, model, min_views, used, result);
  result.views_used = static_cast<int>(used.size());
  storeCamera(fit, sol, model, used, result);
  result.coverage = coverageOf(fit, used);
  addQualityNotes(result);
  if (options.fit_visp)
    fitVispModels(fit, sol, used, result);
  return result;
}

std::string vispCameraXmlText(const CameraCalibration &calibration, const std::string &camera_name,
                              const std::string &additional_info)
{
  if (!calibration.visp_fitted)
    throw Error("ViSP camera file: the ViSP models were not fitted");
  // vpXmlParserCamera only writes to a path: a private folder, read back, then removed.
  namespace fs = std::filesystem;
  std::error_code ec;
  std::string templ = (fs::temp_directory_path(ec) / "yawdepth-xml-XXXXXX").string();
  if (ec)
    templ = "/tmp/yawdepth-xml-XXXXXX";
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  if (!::mkdtemp(buf.data()))
    throw Error(std::string("ViSP camera file: cannot create a temporary folder (") + std::strerror(errno) + ")");
  const fs::path dir(buf.data());
  struct RemoveDir {
    fs::path dir;
    ~RemoveDir()
    {
      std::error_code e;
      fs::remove_all(dir, e);
    }
  } cleanup{dir};
  const std::string tmp = (dir / "camera.xml").string();
  const std::string name = camera_name.empty() ? std::string("Camera") : camera_name;
  const unsigned w = calibration.camera.width(), h = calibration.camera.height();
  try {
    const detail::QuietVisp quiet; // save() prints "Found camera with name ..."
    vpXmlParserCamera xml;
    if (xml.save(calibration.visp_without, tmp, name, w, h) != vpXmlParserCamera::SEQUENCE_OK)
      throw Error("ViSP camera file: cannot write the model without distortion");
    vpXmlParserCamera xml2;
    if (xml2.save(calibration.visp_with, tmp, name, w, h, additional_info) != vpXmlParserCamera::SEQUENCE_OK)
      throw Error("ViSP camera file: cannot write the model with distortion");
  } catch (const vpException &e) {
    throw Error("ViSP camera file: " + oneLine(e.getStringMessage()));
  }
  return readTextFile(tmp, std::size_t(16) << 20);
}

void saveVispCameraXml(const std::string &path, const CameraCalibration &calibration, const std::string &camera_name,
                       const std::string &additional_info)
{
  writeFileAtomically(path, vispCameraXmlText(calibration, camera_name, additional_info));
}

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
  projectionJacobians(rays, cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), K, dist, fisheye, Jint, Jrot);
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
    throw Error("coverage picture: cannot encode as '" + extension + "' (" + oneLine(e.err) + ")");
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
