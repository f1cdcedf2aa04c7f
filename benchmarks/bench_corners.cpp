/*!
  \file bench_corners.cpp
  \brief Corner accuracy on real photographs (and photo-like renders) without ground truth:
  yawdepth's detector beside OpenCV's cornerSubPix and findChessboardCornersSB, and the
  calibration each gives, side by side, per image set.

  Metrics (all in the undistorted image of the set's reference camera, px):
  - homography RMS: the corners of a planar board, undistorted, fit one homography per image; the
    residual per coordinate, sqrt(SSE / (2N - 8)), measures corner noise without ground truth.
  - straightness: RMS distance of each board row's and column's corners to their own fitted line,
    sqrt(SSE / (N_line - 2)) pooled.
  The reference camera of a set is OpenCV's calibrateCamera (k1 k2 p1 p2 k3) on the corners of
  the peer pipeline (findChessboardCorners + cornerSubPix 11x11), so it favours no yawdepth method;
  any error it leaves is common to every column.
  Calibration: every method's corners calibrated by OpenCV (5 coefficients) and by yawdepth's
  calibrateCamera; RMS reprojection error and leave-one-view-out error (each view predicted from a
  calibration without it, its pose from PnP on its own corners: px per coordinate).

  Usage: bench_corners [--franka DIR] [--renders N] [--csv]
*/
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <yawdepth/calibration/camera_calibration.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/render/renderer.h>
#include <array>
#include <Eigen/Dense>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>
#include <visp3/detection/vpDetectorAprilTag.h>
#include <random>
#include <cstdlib>

#include "corner_metrics.h"

using namespace yawdepth;
using namespace yawdepth::bench;

namespace {

struct ImageSet {
  std::string name;
  std::vector<std::string> names;
  std::vector<cv::Mat> images;
  int cols = 0, rows = 0;
  double square = 0;
  /*! renders only: the true (distorted) pixel of every corner, board row-major, per image */
  std::vector<std::vector<cv::Point2f>> truth;
  cv::Mat K, D; //!< renders only: the true camera (OpenCV form)
};


struct CornerMethod {
  std::string name;
  bool yawdepth = false;
  CornerRefinement refinement = CornerRefinement::Gradient;
  int window = 0;
};

/*! yawdepth's corners, put back in the board's row-major order (board ids are row-major). */
Corners yawdepthCorners(const cv::Mat &gray, const ImageSet &set, const CornerMethod &m) {
  DetectorOptions o;
  o.refinement = m.refinement;
  o.subpixel_window = m.window;
  PatternDetector det(PatternSpec::parse("chessboard:" + std::to_string(set.cols) + "x" + std::to_string(set.rows) +
                                         ":" + std::to_string(set.square)),
                      o);
  const FrameDetection d = det.detect(gray, 0);
  if (!d.found)
    return {};
  Corners c(static_cast<std::size_t>(set.cols) * set.rows, cv::Point2f(-1, -1));
  for (const auto &f : d.features)
    if (f.id >= 0 && f.id < static_cast<long>(c.size()))
      c[f.id] = cv::Point2f(static_cast<float>(f.u), static_cast<float>(f.v));
  return c;
}

/*! Board points (z = 0) in the same row-major order as `corners`: the order of the detected grid is
    the same for every method only up to the grid's symmetries, so each method's corners are
    matched to the reference by nearest pixel. */
std::vector<cv::Point3f> boardPoints(const ImageSet &s) {
  std::vector<cv::Point3f> b;
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.cols; ++c)
      b.emplace_back(static_cast<float>(c * s.square), static_cast<float>(r * s.square), 0.f);
  return b;
}

struct Calib {
  double rms = 0, loo = 0, fx = 0;
  bool ok = false;
};

/*! The views with the board (corners found): their board points and their corners. */
void boardViews(const std::vector<Corners> &views, const ImageSet &s, std::vector<std::vector<cv::Point3f>> &obj,
                std::vector<Corners> &img) {
  for (const auto &v : views)
    if (!v.empty()) {
      obj.push_back(boardPoints(s));
      img.push_back(v);
    }
}

/*! OpenCV calibration of one method's corners (k1 k2 p1 p2 k3) and its leave-one-view-out error. */
Calib opencvCalib(const std::vector<Corners> &views, const ImageSet &s, cv::Size size, int flags) {
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<Corners> img;
  boardViews(views, s, obj, img);
  Calib c;
  if (img.size() < 4)
    return c;
  cv::Mat K, D;
  std::vector<cv::Mat> rv, tv;
  c.rms = cv::calibrateCamera(obj, img, size, K, D, rv, tv, flags);
  c.fx = K.at<double>(0, 0);
  double sse = 0;
  long n = 0;
  for (std::size_t k = 0; k < img.size(); ++k) {
    std::vector<std::vector<cv::Point3f>> o2;
    std::vector<Corners> i2;
    for (std::size_t j = 0; j < img.size(); ++j)
      if (j != k) {
        o2.push_back(obj[j]);
        i2.push_back(img[j]);
      }
    cv::Mat K2, D2, r, t;
    std::vector<cv::Mat> rv2, tv2;
    cv::calibrateCamera(o2, i2, size, K2, D2, rv2, tv2, flags);
    cv::solvePnP(obj[k], img[k], K2, D2, r, t, false, cv::SOLVEPNP_ITERATIVE);
    Corners proj;
    cv::projectPoints(obj[k], r, t, K2, D2, proj);
    for (std::size_t i = 0; i < proj.size(); ++i) {
      const cv::Point2f e = proj[i] - img[k][i];
      sse += e.dot(e);
    }
    n += static_cast<long>(proj.size());
  }
  c.loo = std::sqrt(sse / n); // per point, as calibrateCamera's RMS
  c.ok = true;
  return c;
}

bool loadSet(ImageSet &s, const std::vector<std::string> &paths) {
  for (const auto &p : paths) {
    cv::Mat m = cv::imread(p, cv::IMREAD_GRAYSCALE);
    if (m.empty()) {
      std::fprintf(stderr, "bench_corners: cannot read %s\n", p.c_str());
      return false;
    }
    s.names.push_back(p.substr(p.find_last_of('/') + 1));
    s.images.push_back(m);
  }
  return true;
}

/*! One method's corners in one image (empty when not found), in the order the method gives them. */
Corners detectCorners(const cv::Mat &g, const ImageSet &s, const CornerMethod &me) {
  if (me.yawdepth)
    return yawdepthCorners(g, s, me);
  if (me.window > 0)
    return opencvSubPix(g, s.cols, s.rows, me.window);
  return opencvSB(g, s.cols, s.rows);
}

/*! DEBUG_CORNERS: each method's corner count, method 2's corners far from method 0's, and an image
    of both (/tmp/dbg_I.png). */
void debugCorners(const ImageSet &s, std::size_t i, const std::vector<CornerMethod> &methods,
                  const std::vector<std::vector<Corners>> &corners) {
  cv::Mat col;
  cv::cvtColor(s.images[i], col, cv::COLOR_GRAY2BGR);
  for (std::size_t m = 0; m < methods.size(); ++m) {
    std::printf("%s %s: %zu corners\n", s.names[i].c_str(), methods[m].name.c_str(), corners[m][i].size());
    if (m == 2)
      for (std::size_t k = 0; k < corners[m][i].size(); ++k) {
        double best = 1e9;
        for (const auto &q : corners[0][i])
          best = std::min(best, (double)cv::norm(q - corners[m][i][k]));
        if (best > 0.3)
          std::printf("   corner %zu at (%.1f %.1f) %.2f px from cornerSubPix\n", k, corners[m][i][k].x,
                      corners[m][i][k].y, best);
      }
  }
  for (const auto &q : corners[0][i])
    cv::circle(col, q, 3, cv::Scalar(0, 255, 0));
  for (const auto &q : corners[2][i])
    cv::drawMarker(col, q, cv::Scalar(0, 0, 255), cv::MARKER_CROSS, 8);
  cv::imwrite("/tmp/dbg_" + std::to_string(i) + ".png", col);
}

/*! Every method's corners in every image ([method][image]), in one order: the truth's (board
    row-major), else the reference method's (index 0); a method whose corners cannot be matched has none. */
std::vector<std::vector<Corners>> detectAll(const ImageSet &s, const std::vector<CornerMethod> &methods) {
  const std::size_t nm = methods.size();
  std::vector<std::vector<Corners>> corners(nm, std::vector<Corners>(s.images.size()));
  for (std::size_t i = 0; i < s.images.size(); ++i) {
    for (std::size_t m = 0; m < nm; ++m)
      corners[m][i] = detectCorners(s.images[i], s, methods[m]);
    if (getenv("DEBUG_CORNERS"))
      debugCorners(s, i, methods, corners);
    if (!s.truth.empty()) {
      for (std::size_t m = 0; m < nm; ++m)
        if (!matchOrder(s.truth[i], corners[m][i]))
          corners[m][i].clear();
    } else {
      for (std::size_t m = 1; m < nm; ++m)
        if (!corners[0][i].empty() && !matchOrder(corners[0][i], corners[m][i]))
          corners[m][i].clear();
    }
  }
  return corners;
}

/*! The set's reference camera K, D, printed: the true one (renders), else OpenCV's calibration (5
    coefficients) of `reference`'s corners, whose name is `method`. */
void referenceCamera(const ImageSet &s, const std::vector<Corners> &reference, const std::string &method,
                     cv::Mat &K, cv::Mat &D) {
  if (!s.K.empty()) {
    K = s.K;
    D = s.D;
    std::printf("reference camera: the true one, fx %.2f\n", K.at<double>(0, 0));
    return;
  }
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<Corners> img;
  boardViews(reference, s, obj, img);
  std::vector<cv::Mat> rv, tv;
  cv::calibrateCamera(obj, img, s.images[0].size(), K, D, rv, tv, 0);
  std::printf("reference camera (OpenCV, %s corners): fx %.2f fy %.2f u0 %.2f v0 %.2f k1 %.4f k2 %.4f\n",
              method.c_str(), K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2),
              D.at<double>(0), D.at<double>(1));
}

/*! One method's row: images found, homography RMS (median, max), straightness, smooth-field RMS,
    OpenCV calibration RMS and leave-one-out error, fx, and the RMS against the truth (renders). */
void printMethodRow(const ImageSet &s, const std::string &name, const std::vector<Corners> &corners,
                    const cv::Mat &K, const cv::Mat &D) {
  std::vector<double> h, st, sm;
  int found = 0;
  double tsse = 0;
  long tn = 0;
  for (std::size_t i = 0; i < s.images.size(); ++i) {
    if (corners[i].empty())
      continue;
    ++found;
    if (!s.truth.empty())
      for (std::size_t k = 0; k < s.truth[i].size(); ++k) {
        const cv::Point2f e = corners[i][k] - s.truth[i][k];
        tsse += e.dot(e);
        tn += 2;
      }
    const Fit f = planarFit(corners[i], s.cols, s.rows, K, D);
    h.push_back(f.h_rms);
    st.push_back(f.straight);
    sm.push_back(f.smooth_rms);
  }
  const Calib c = opencvCalib(corners, s, s.images[0].size(), 0);
  std::printf("%-26s %2d/%-2zu %10.4f %10.4f %10.4f %9.4f %9.4f %9.4f %9.2f %9.4f\n", name.c_str(), found,
              s.images.size(), median(h), h.empty() ? NAN : *std::max_element(h.begin(), h.end()), median(st), median(sm), c.rms,
              c.loo, c.fx, tn ? std::sqrt(tsse / tn) : NAN);
}

/*! yawdepth's own calibration (distortion model chosen on views left out) of its own corners: its row. */
void printYawdepthCalibration(const ImageSet &s, const std::vector<Corners> &corners) {
  BoardLayout board;
  board.pattern = PatternSpec::parse("chessboard:" + std::to_string(s.cols) + "x" + std::to_string(s.rows) + ":" +
                                     std::to_string(s.square));
  std::vector<CalibrationView> views;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Corners &c = corners[i];
    if (c.empty())
      continue;
    CalibrationView v;
    v.name = s.names[i];
    for (std::size_t k = 0; k < c.size(); ++k)
      v.features.push_back(FeatureObservation{static_cast<long>(k), c[k].x, c[k].y});
    views.push_back(v);
  }
  CameraCalibrationOptions o;
  o.fit_visp = false;
  try {
    const CameraCalibration cal = calibrateCamera(board, views, s.images[0].size().width, s.images[0].size().height, o);
    double heldout = 0;
    for (const auto &m : cal.models)
      if (m.chosen)
        heldout = m.heldout_rms_px;
    std::printf("%-26s %5s %10s %10s %10s %9s %9.4f %9.4f %9.2f   model %s\n", "yawdepth calibrate-camera", "", "", "",
                "", "", cal.rms_px, heldout, cal.camera.kx(), cal.model_reason.c_str());
  } catch (const std::exception &e) {
    std::printf("yawdepth calibrate-camera: %s\n", e.what());
  }
}

/*! One chessboard set: every method's corners, the reference camera, a row per method, then
    yawdepth's calibration of its gradient corners. */
void runChessboardSet(const ImageSet &s, const std::vector<CornerMethod> &methods) {
  if (s.images.empty())
    return;
  const std::vector<std::vector<Corners>> corners = detectAll(s, methods);
  const std::size_t with_board = static_cast<std::size_t>(
      std::count_if(corners[0].begin(), corners[0].end(), [](const Corners &c) { return !c.empty(); }));
  if (with_board < 4) {
    std::printf("%s: fewer than 4 images with the board, skipped\n", s.name.c_str());
    return;
  }
  const cv::Size size = s.images[0].size();
  std::printf("\n## %s: %zu images %dx%d, chessboard %dx%d\n", s.name.c_str(), s.images.size(), size.width,
              size.height, s.cols, s.rows);
  cv::Mat K, D;
  referenceCamera(s, corners[0], methods[0].name, K, D);
  std::printf("%-26s %5s %10s %10s %10s %9s %9s %9s %9s %9s\n", "method", "found", "H-rms med", "H-rms max", "straight",
              "H+smooth", "calib rms", "LOO", "fx", "truth rms");
  const std::vector<Corners> *yawdepth_calib_input = nullptr;
  for (std::size_t m = 0; m < methods.size(); ++m) {
    printMethodRow(s, methods[m].name, corners[m], K, D);
    if (methods[m].yawdepth && methods[m].refinement == CornerRefinement::Gradient && methods[m].window == 0)
      yawdepth_calib_input = &corners[m];
  }
  if (yawdepth_calib_input)
    printYawdepthCalibration(s, *yawdepth_calib_input);
}

/*! Photo-like renders of a 9x6 board (25 mm) through a wide lens with strong barrel distortion:
    seeded random poses, every corner inside the image, truth from the exact projection. */
ImageSet photoRenders(int count, std::uint64_t seed, bool photo) {
  ImageSet s;
  s.name = photo ? "photo-like renders (wide lens, JPEG 85, gamma, vignetting, Bayer, defocus, narrow outer squares)"
                 : "ideal renders (wide lens, blur 0.7, noise 2)";
  s.cols = 9;
  s.rows = 6;
  s.square = 0.025;
  const CameraModel cam = CameraModel::brown(600.0, 602.0, 322.5, 238.0, {-0.28, 0.09, 0.0005, -0.0003, -0.012}, 640, 480);
  s.K = (cv::Mat_<double>(3, 3) << 600.0, 0, 322.5, 0, 602.0, 238.0, 0, 0, 1);
  s.D = (cv::Mat_<double>(1, 5) << -0.28, 0.09, 0.0005, -0.0003, -0.012);
  BoardLayout board;
  board.pattern = PatternSpec::parse("chessboard:9x6:0.025");
  if (photo)
    board.outer_square = 0.45 * board.pattern.square; // narrow outer squares, as many printed boards
  const YawRig rig(Eigen::Vector3d::Zero());
  const MotionSample sample;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const Eigen::Vector4d e = board.extent();
  const Eigen::Vector3d centre(0.5 * (e[0] + e[2]), 0.5 * (e[1] + e[3]), 0.0);
  const double deg = M_PI / 180;
  int attempts = 0;
  while (static_cast<int>(s.images.size()) < count && attempts++ < 1000) {
    const double depth = 0.3 + 0.35 * U(rng);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd((U(rng) - 0.5) * 30 * deg, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd((U(rng) - 0.5) * 80 * deg, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd((U(rng) - 0.5) * 80 * deg, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    Eigen::Isometry3d cMb = Eigen::Isometry3d::Identity();
    cMb.linear() = R;
    cMb.translation() = Eigen::Vector3d((U(rng) - 0.5) * 0.3 * depth, (U(rng) - 0.5) * 0.2 * depth, depth) - R * centre;
    std::vector<cv::Point2f> t;
    bool inside = true;
    for (int r = 0; r < s.rows && inside; ++r)
      for (int c = 0; c < s.cols && inside; ++c) {
        const Eigen::Vector3d p = cMb * Eigen::Vector3d(c * s.square, r * s.square, 0);
        if (!(p.z() > 0)) {
          inside = false;
          break;
        }
        const Eigen::Vector2d uv = cam.project(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()));
        inside = uv.x() > 30 && uv.y() > 30 && uv.x() < 610 && uv.y() < 450;
        t.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
      }
    if (!inside)
      continue;
    RenderOptions o;
    if (photo) {
      o = photoLikeRenderOptions(depth);
      o.light_angle = U(rng) * 2 * M_PI;
    } else {
      o.blur_sigma_px = 0.7;
      o.noise_sigma = 2;
    }
    o.seed = seed * 1000 + s.images.size();
    // board ids are row-major from the board's origin; the board frame is wMb with the camera at
    // the world origin (rig without offset, zero motion sample)
    s.images.push_back(renderBoard(cam, rig, sample, board, cMb, o));
    s.names.push_back("render " + std::to_string(s.images.size()));
    s.truth.push_back(t);
  }
  return s;
}

/*!
  The corners of coplanar tags against one plane: unknowns the image-from-plane homography and
  each tag's position and turn on the plane (tag 0 fixes the plane's frame), the tag side known;
  Gauss-Newton on the 4 corners of every tag. Returns the RMS per coordinate
  sqrt(SSE / (2 * 4 * tags - 8 - 3 * (tags - 1))); NaN when it fails.
  `corners[t]` are tag t's 4 corners in the order of pattern.h (counter-clockwise from bottom-left
  in the tag's own frame: (-s/2, s/2), (s/2, s/2), (s/2, -s/2), (-s/2, -s/2) as libapriltag).
*/
double coplanarTagsRms(const std::vector<std::array<cv::Point2d, 4>> &corners) {
  const int T = static_cast<int>(corners.size());
  if (T < 2)
    return NAN;
  const double h = 0.5; // unit tag side: positions in tag sides
  const cv::Point2d local[4] = {{-h, h}, {h, h}, {h, -h}, {-h, -h}};
  // Initial H from tag 0's corners; other tags placed through H^-1 (Procrustes).
  std::vector<cv::Point2d> l0(local, local + 4), i0(corners[0].begin(), corners[0].end());
  cv::Mat H = cv::findHomography(l0, i0, 0);
  if (H.empty())
    return NAN;
  H /= H.at<double>(2, 2);
  const int np = 8 + 3 * (T - 1);
  Eigen::VectorXd x(np);
  for (int k = 0; k < 8; ++k)
    x[k] = H.at<double>(k / 3, k % 3);
  const cv::Mat Hi = H.inv();
  for (int t = 1; t < T; ++t) {
    std::vector<cv::Point2d> img(corners[t].begin(), corners[t].end()), pl;
    cv::perspectiveTransform(img, pl, Hi);
    cv::Point2d c(0, 0);
    for (const auto &p : pl)
      c += 0.25 * p;
    double sc = 0, ss = 0;
    for (int k = 0; k < 4; ++k) {
      const cv::Point2d q = pl[k] - c;
      sc += local[k].x * q.x + local[k].y * q.y;
      ss += local[k].x * q.y - local[k].y * q.x;
    }
    x[8 + 3 * (t - 1)] = c.x;
    x[8 + 3 * (t - 1) + 1] = c.y;
    x[8 + 3 * (t - 1) + 2] = std::atan2(ss, sc);
  }
  auto residuals = [&](const Eigen::VectorXd &p) {
    Eigen::VectorXd r(8 * T);
    for (int t = 0; t < T; ++t) {
      double cx = 0, cy = 0, a = 0;
      if (t > 0) {
        cx = p[8 + 3 * (t - 1)];
        cy = p[8 + 3 * (t - 1) + 1];
        a = p[8 + 3 * (t - 1) + 2];
      }
      for (int k = 0; k < 4; ++k) {
        const double X = cx + std::cos(a) * local[k].x - std::sin(a) * local[k].y;
        const double Y = cy + std::sin(a) * local[k].x + std::cos(a) * local[k].y;
        const double w = p[6] * X + p[7] * Y + 1;
        r[8 * t + 2 * k] = (p[0] * X + p[1] * Y + p[2]) / w - corners[t][k].x;
        r[8 * t + 2 * k + 1] = (p[3] * X + p[4] * Y + p[5]) / w - corners[t][k].y;
      }
    }
    return r;
  };
  for (int it = 0; it < 30; ++it) {
    const Eigen::VectorXd r = residuals(x);
    Eigen::MatrixXd J(r.size(), np);
    for (int k = 0; k < np; ++k) {
      const double d = 1e-7 * std::max(1.0, std::abs(x[k]));
      Eigen::VectorXd xp = x;
      xp[k] += d;
      J.col(k) = (residuals(xp) - r) / d;
    }
    const Eigen::VectorXd step = J.colPivHouseholderQr().solve(-r);
    x += step;
    if (step.norm() < 1e-12 * (1 + x.norm()))
      break;
  }
  const Eigen::VectorXd r = residuals(x);
  return std::sqrt(r.squaredNorm() / (8.0 * T - np));
}

/*! Tag poses' consistency: distance RMS of the tag centres to their best plane (mm) and the
    largest angle between a tag's normal and that plane's normal (deg). */
void posePlanarity(const std::vector<vpHomogeneousMatrix> &cMt, double &plane_rms_mm, double &normal_deg) {
  Eigen::MatrixXd P(static_cast<Eigen::Index>(cMt.size()), 3);
  for (std::size_t i = 0; i < cMt.size(); ++i)
    for (int k = 0; k < 3; ++k)
      P(static_cast<Eigen::Index>(i), k) = cMt[i][k][3];
  const Eigen::RowVector3d mean = P.colwise().mean();
  const Eigen::MatrixXd Q = P.rowwise() - mean;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Q, Eigen::ComputeThinV);
  Eigen::Vector3d n = svd.matrixV().col(2);
  plane_rms_mm = 1000 * std::sqrt((Q * n).squaredNorm() / std::max<Eigen::Index>(1, P.rows() - 3));
  normal_deg = 0;
  for (const auto &M : cMt) {
    const Eigen::Vector3d z(M[0][2], M[1][2], M[2][2]);
    normal_deg = std::max(normal_deg, std::acos(std::min(1.0, std::abs(z.dot(n)))) * 180 / M_PI);
  }
}

/*! One dot grid: cv::findCirclesGrid (symmetric grid) and yawdepth's refineDotGridCentres on its
    output; homography RMS of each (ho, hy) and, with a truth, RMS error per coordinate (eo, ey; NaN
    without). False when OpenCV finds no grid or the truth cannot be matched. */
bool dotGridFit(const cv::Mat &g, int cols, int rows, const std::vector<cv::Point2f> *truth, double &ho, double &hy,
                double &eo, double &ey) {
  Corners c;
  if (!cv::findCirclesGrid(g, cv::Size(cols, rows), c, cv::CALIB_CB_SYMMETRIC_GRID))
    return false;
  std::vector<cv::Point2d> d(c.begin(), c.end());
  refineDotGridCentres(g, d, cols, rows);
  Corners y;
  for (const auto &p : d)
    y.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  const cv::Mat K = cv::Mat::eye(3, 3, CV_64F), D;
  ho = planarFit(c, cols, rows, K, D).h_rms;
  hy = planarFit(y, cols, rows, K, D).h_rms;
  eo = ey = NAN;
  if (truth) {
    Corners tc = *truth;
    Corners c2 = c, y2 = y;
    if (!matchOrder(tc, c2) || !matchOrder(tc, y2))
      return false;
    double so = 0, sy = 0;
    for (std::size_t i = 0; i < tc.size(); ++i) {
      const cv::Point2f a = c2[i] - tc[i], b = y2[i] - tc[i];
      so += a.dot(a);
      sy += b.dot(b);
    }
    eo = std::sqrt(so / (2.0 * tc.size()));
    ey = std::sqrt(sy / (2.0 * tc.size()));
  }
  return true;
}

/*! The row of ViSP's grid36-0*.pgm (real photos, 6x6 dots), or a line saying they are not installed. */
void printRealDotGrids(const std::string &visp_images) {
  std::vector<double> ho, hy;
  int n = 0, found = 0;
  for (int k = 1; k <= 4; ++k) {
    const cv::Mat g = cv::imread(visp_images + "/calibration/grid36-0" + std::to_string(k) + ".pgm", cv::IMREAD_GRAYSCALE);
    if (g.empty())
      continue;
    ++n;
    double a, b, c, d;
    if (dotGridFit(g, 6, 6, nullptr, a, b, c, d)) {
      ++found;
      ho.push_back(a);
      hy.push_back(b);
    }
  }
  if (n)
    std::printf("%-44s %2d/%-2d %12.4f %12.4f %12s %12s\n", "ViSP grid36-0*.pgm (real, 6x6)", found, n, median(ho),
                median(hy), "-", "-");
  else
    std::printf("ViSP grid36-0*.pgm: not found (apt-get install visp-images-data)\n");
}

/*! The row of 10 rendered 6x6 dot grids (seeded random homographies, blur 0.8), against their truth. */
void printRenderedDotGrids() {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  std::vector<double> ho, hy, eo, ey;
  int found = 0;
  const int n = 10;
  for (int k = 0; k < n; ++k) {
    // a 6x6 grid, spacing ~60 px, dots 0.6 spacing, perspective from a random homography
    const double s = 55 + 10 * U(rng);
    cv::Matx33d H(s, 0.15 * s * U(rng), 170 + 20 * U(rng), 0.15 * s * U(rng), s, 90 + 20 * U(rng),
                  2e-3 * U(rng) * 60 / s, 2e-3 * U(rng) * 60 / s, 1);
    std::vector<cv::Point2f> truth;
    const cv::Mat g = dotGridImage(H, 6, 6, 0.6, cv::Size(640, 480), 0.8, 2.0, 100 + k, truth);
    double a, b, c, d;
    if (dotGridFit(g, 6, 6, &truth, a, b, c, d)) {
      ++found;
      ho.push_back(a);
      hy.push_back(b);
      eo.push_back(c);
      ey.push_back(d);
    }
  }
  std::printf("%-44s %2d/%-2d %12.4f %12.4f %12.4f %12.4f\n", "rendered 6x6 dot grids (perspective, blur 0.8)", found, n,
              median(ho), median(hy), median(eo), median(ey));
}

/*! Dot grids: ViSP's grid36-0*.pgm (real photos, 6x6 dots) and perspective renders with truth;
    cv::findCirclesGrid (symmetric grid) beside yawdepth's refineDotGridCentres on its output.
    No undistortion (the grid photos' camera is not given): the homography RMS includes the lens. */
void runDotGrids(const std::string &visp_images) {
  std::printf("\n## dot grids: homography RMS of the centres (px; no undistortion), renders also against the truth\n");
  std::printf("%-44s %5s %12s %12s %12s %12s\n", "set", "found", "OpenCV H", "yawdepth H", "OpenCV err", "yawdepth err");
  printRealDotGrids(visp_images);
  printRenderedDotGrids();
}

/*! The four corners of each tag, by tag id. */
using TagCorners = std::map<long, std::array<cv::Point2d, 4>>;

/*! ViSP's vpDetectorAprilTag as a ViSP user runs it (default options: quad decimation 1, pose from
    its homography): each tag's corners and pose. */
void vispTags(const cv::Mat &gray, double tag, const vpCameraParameters &cam, TagCorners &corners,
              std::vector<vpHomogeneousMatrix> &poses) {
  vpImage<unsigned char> I;
  vpImageConvert::convert(gray, I);
  vpDetectorAprilTag d(vpDetectorAprilTag::TAG_36h11);
  d.detect(I);
  for (std::size_t i = 0; i < d.getNbObjects(); ++i) {
    const std::vector<vpImagePoint> &poly = d.getPolygon(i);
    long id = -1;
    std::sscanf(d.getMessage(i).c_str(), "36h11 id: %ld", &id);
    if (poly.size() != 4 || id < 0)
      continue;
    for (int k = 0; k < 4; ++k)
      corners[id][static_cast<std::size_t>(k)] = cv::Point2d(poly[static_cast<std::size_t>(k)].get_u(), poly[static_cast<std::size_t>(k)].get_v());
    vpHomogeneousMatrix M;
    if (d.getPose(i, tag, cam, M))
      poses.push_back(M);
  }
}

/*! A tag's pose from its 4 corners by PnP (IPPE square, no distortion); false when PnP fails. */
bool ippePose(const std::array<cv::Point2d, 4> &c, double tag, const vpCameraParameters &cam, vpHomogeneousMatrix &M) {
  const std::vector<cv::Point3d> obj = {{-tag / 2, tag / 2, 0}, {tag / 2, tag / 2, 0}, {tag / 2, -tag / 2, 0}, {-tag / 2, -tag / 2, 0}};
  const std::vector<cv::Point2d> img(c.begin(), c.end());
  cv::Mat rv, tv;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.get_px(), 0, cam.get_u0(), 0, cam.get_py(), cam.get_v0(), 0, 0, 1);
  if (!cv::solvePnP(obj, img, K, cv::noArray(), rv, tv, false, cv::SOLVEPNP_IPPE_SQUARE))
    return false;
  cv::Mat R;
  cv::Rodrigues(rv, R);
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b)
      M[a][b] = R.at<double>(a, b);
    M[a][3] = tv.at<double>(a);
  }
  return true;
}

/*! yawdepth's detector (features by id, pattern.h): each tag's corners, its pose by ippePose(). */
void yawdepthTags(const cv::Mat &gray, const CameraModel &camera, double tag, const vpCameraParameters &cam,
                  TagCorners &corners, std::vector<vpHomogeneousMatrix> &poses) {
  PatternDetector det(PatternSpec::parse("apriltag:36h11:0.053"));
  det.setCamera(camera);
  const FrameDetection d = det.detect(gray, 0);
  std::map<long, std::map<int, cv::Point2d>> byTag;
  for (const auto &f : d.features) {
    const long t = f.id / 5, k = f.id % 5 - 1;
    if (k >= 0)
      byTag[t][static_cast<int>(k)] = cv::Point2d(f.u, f.v);
  }
  for (const auto &[t, m] : byTag)
    if (m.size() == 4) {
      std::array<cv::Point2d, 4> c;
      for (int k = 0; k < 4; ++k)
        c[static_cast<std::size_t>(k)] = m.at(k);
      corners[t] = c;
      vpHomogeneousMatrix M;
      if (ippePose(c, tag, cam, M))
        poses.push_back(M);
    }
}

/*! One detector's row: tags found, their coplanar homography RMS, the poses' planarity. */
void printTagRow(const char *name, const TagCorners &c, const std::vector<vpHomogeneousMatrix> &poses) {
  std::vector<std::array<cv::Point2d, 4>> v;
  for (const auto &kv : c)
    v.push_back(kv.second);
  double pr = NAN, nd = NAN;
  if (poses.size() >= 4)
    posePlanarity(poses, pr, nd);
  std::printf("%-34s %5zu %14.4f %16.3f %16.3f\n", name, v.size(), coplanarTagsRms(v), pr, nd);
}

/*! AprilTag.pgm (visp-images-data): 12 coplanar 36h11 tags, 53 mm, camera without distortion as
    ViSP's own test takes it; ViSP's vpDetectorAprilTag beside yawdepth's detector. */
void runAprilTagSet(const std::string &path) {
  const cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (gray.empty()) {
    std::printf("\n## AprilTag.pgm: %s not readable (apt-get install visp-images-data), skipped\n", path.c_str());
    return;
  }
  const double tag = 0.053;
  vpCameraParameters cam;
  cam.initPersProjWithoutDistortion(615.1674805, 615.1675415, 312.1889954, 243.4373779);
  const CameraModel camera(cam, static_cast<unsigned>(gray.cols), static_cast<unsigned>(gray.rows));
  std::printf("\n## AprilTag.pgm (real, visp-images-data): %dx%d, 36h11 tags of 53 mm, camera 615.17/615.17/312.19/243.44\n",
              gray.cols, gray.rows);
  std::printf("%-34s %5s %14s %16s %16s\n", "detector", "tags", "H-rms (px)", "pose plane (mm)", "normals (deg)");
  TagCorners visp_c, ours;
  std::vector<vpHomogeneousMatrix> visp_pose, our_pose;
  vispTags(gray, tag, cam, visp_c, visp_pose);
  yawdepthTags(gray, camera, tag, cam, ours, our_pose);
  printTagRow("ViSP vpDetectorAprilTag", visp_c, visp_pose);
  printTagRow("yawdepth (ViSP corners, IPPE pose)", ours, our_pose);
}

/*! An extra set from --set NAME:COLSxROWS:SQUARE:FILE[,FILE...], its images read into x: 0, or the
    exit code (2: a bad spec, 1: an image that cannot be read) after a message on stderr. */
int loadExtraSet(const std::string &spec, ImageSet &x) {
  std::vector<std::string> parts;
  std::size_t a = 0;
  for (int k = 0; k < 3; ++k) {
    const std::size_t b = spec.find(':', a);
    if (b == std::string::npos) {
      std::fprintf(stderr, "bench_corners: --set NAME:COLSxROWS:SQUARE:FILE,FILE,... expected\n");
      return 2;
    }
    parts.push_back(spec.substr(a, b - a));
    a = b + 1;
  }
  x.name = parts[0] + " (real)";
  if (std::sscanf(parts[1].c_str(), "%dx%d", &x.cols, &x.rows) != 2 || x.cols < 3 || x.rows < 3 ||
      !(std::atof(parts[2].c_str()) > 0)) {
    std::fprintf(stderr, "bench_corners: bad set '%s'\n", spec.c_str());
    return 2;
  }
  x.square = std::atof(parts[2].c_str());
  std::vector<std::string> files;
  std::string rest = spec.substr(a);
  for (std::size_t b; (b = rest.find(',')) != std::string::npos; rest = rest.substr(b + 1))
    files.push_back(rest.substr(0, b));
  files.push_back(rest);
  return loadSet(x, files) ? 0 : 1;
}

} // namespace

int main(int argc, char **argv) {
  std::string franka = YAWDEPTH_TEST_DATA_DIR "/franka-eye-in-hand"; // the real photos the tests use
  int renders = 12;
  std::string visp_images = "/usr/share/visp-images-data/ViSP-images";
  std::vector<std::string> extra;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--franka" && i + 1 < argc)
      franka = argv[++i];
    else if (a == "--visp-images" && i + 1 < argc)
      visp_images = argv[++i];
    else if (a == "--set" && i + 1 < argc)
      extra.push_back(argv[++i]);
    else if (a == "--renders" && i + 1 < argc)
      renders = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_corners [--franka DIR]\n");
      return 2;
    }
  }
  std::vector<CornerMethod> methods = {
      {"cornerSubPix 11x11", false, CornerRefinement::OpenCV, 5},
      {"SB+ACCURACY", false, CornerRefinement::None, 0},
      {"yawdepth gradient", true, CornerRefinement::Gradient, 0},
      {"yawdepth saddle", true, CornerRefinement::Saddle, 0},
      {"yawdepth cornerSubPix", true, CornerRefinement::OpenCV, 0},
  };
  if (getenv("SWEEP")) for (int w : {2, 3, 4, 6, 8, 10, 14, 20}) {
    methods.push_back({"gradient w" + std::to_string(w), true, CornerRefinement::Gradient, w});
    methods.push_back({"cornerSubPix w" + std::to_string(w), false, CornerRefinement::OpenCV, w});
  }
  for (const auto &spec : extra) {
    ImageSet x;
    if (const int code = loadExtraSet(spec, x))
      return code;
    runChessboardSet(x, methods);
  }
  ImageSet f;
  f.name = "franka-eye-in-hand (real)";
  f.cols = 9;
  f.rows = 6;
  f.square = 0.0236;
  std::vector<std::string> paths;
  for (int k = 1; k <= 8; ++k)
    paths.push_back(franka + "/franka_image-" + std::to_string(k) + ".png");
  if (!loadSet(f, paths))
    return 1;
  runChessboardSet(f, methods);
  runAprilTagSet(visp_images + "/AprilTag/AprilTag.pgm");
  runDotGrids(visp_images);
  runChessboardSet(photoRenders(renders, 11, true), methods);
  runChessboardSet(photoRenders(renders, 12, false), methods);
  return 0;
}
