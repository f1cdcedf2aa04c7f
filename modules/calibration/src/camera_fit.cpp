// Camera calibration: OpenCV's fits of the Brown and Kannala-Brandt (cv::fisheye) models on subsets of
// the views (CameraFit), their held-out error and covariance, and the final fit without its outlier views.
#include "board_pose.h"
#include "camera_calibration_impl.h"
#include "text.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace calibration_detail {

namespace {

/* The largest angle between two of the unit vectors (board normals). */
double largestAngle(const std::vector<Eigen::Vector3d> &normals)
{
  double spread = 0;
  for (std::size_t i = 0; i < normals.size(); ++i)
    for (std::size_t j = i + 1; j < normals.size(); ++j)
      spread = std::max(spread, std::acos(std::clamp(normals[i].dot(normals[j]), -1.0, 1.0)));
  return spread;
}

/* Board normal (camera frame) from a homography with a guessed camera, for a failed calibration. */
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

/* cv::fisheye's flags under the options (it has no aspect-ratio constraint and no tangential terms). */
int fisheyeFlags(const CameraCalibrationOptions &o) {
  int flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW;
  if (o.fix_principal_point)
    flags |= cv::fisheye::CALIB_FIX_PRINCIPAL_POINT;
  return flags;
}

/* OpenCV flags of a model under the options' other constraints. */
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

/*
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

/* The views' message when the board's orientation hardly varies (the focal length is then unknown). */
std::string degenerateMessage(double spread, std::size_t n)
{
  return "degenerate views: the board's orientation varies by only " + fixed(spread / kDeg, 1) + " deg over the " +
         std::to_string(n) + " views (all fronto-parallel or all tilted alike); the focal length cannot be "
         "told from the distance: tilt the board 20 to 45 degrees in different directions";
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

} // namespace

std::string oneLine(std::string s)
{
  for (char &c : s)
    if (c == '\n' || c == '\r' || c == '\t')
      c = ' ';
  while (!s.empty() && s.back() == ' ')
    s.pop_back();
  return s;
}

std::string modelName(Distortion d) {
  if (d == Distortion::Fisheye)
    return "Kannala-Brandt k1..k4 (fisheye)";
  return d == Distortion::K8 ? "k1..k6 p1 p2 (rational)" : d == Distortion::K5 ? "k1 k2 p1 p2 k3" : "k1 k2 p1 p2";
}

/* The projection of a view's board points through a fit's K and distortion (`d`: its model). */
std::vector<cv::Point2f> projectView(const std::vector<cv::Point3f> &obj, const cv::Mat &rvec, const cv::Mat &tvec,
                                     const cv::Mat &K, const cv::Mat &dist, Distortion d) {
  std::vector<cv::Point2f> proj;
  if (d == Distortion::Fisheye)
    cv::fisheye::projectPoints(obj, proj, rvec, tvec, K, dist);
  else
    cv::projectPoints(obj, rvec, tvec, K, dist, proj);
  return proj;
}

/* d(pixel)/d(fx fy u0 v0 k1..k6) (2N x 12) and d(pixel)/d(rvec tvec) (2N x 6) of OpenCV's projection;
    for the fisheye model (`fisheye`, cv::fisheye's projection) d(pixel)/d(fx fy u0 v0 k1..k4) in the
    first eight columns. */
void projectionJacobians(const std::vector<cv::Point3f> &obj, const cv::Mat &rvec, const cv::Mat &tvec, const cv::Mat &K,
                         const cv::Mat &dist, bool fisheye, Eigen::MatrixXd &Jint, Eigen::MatrixXd &Jpose,
                         std::vector<cv::Point2d> *proj) {
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

} // namespace calibration_detail
} // namespace yawdepth
