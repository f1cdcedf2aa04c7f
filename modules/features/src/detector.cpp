/*!
  \file detector.cpp
  \brief Chessboard corners (OpenCV detection, own sub-pixel refinement, stable ids) and AprilTags
  (ViSP's vpDetectorAprilTag), with failure reasons.
*/
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <iterator>
#include <mutex>
#include <unistd.h>
#include <yawdepth/features/detector.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>
#include <visp3/detection/vpDetectorAprilTag.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {

// ---------------------------------------------------------------------------------------------
// Sub-pixel refinement of X-junctions
// ---------------------------------------------------------------------------------------------
namespace {

/*!
  The image of an X-junction (two straight edges through the corner q, diagonal quadrants of the
  same colour) blurred by any point-symmetric PSF is even about q: I(q + d) = I(q - d). Perspective
  keeps the edges straight, so this holds under any pose up to the neighbouring corners. The two
  iterative methods below use Gaussian weights centred on the current estimate over the pixel grid
  (no resampling, hence no interpolation bias): their fixed point satisfies a condition that is odd
  about q and vanishes at the true corner.
*/
struct RefineContext {
  cv::Mat f;      //!< image as float
  cv::Mat gx, gy; //!< gradients (Sobel 3x3 / 8), only for Gradient
};

/*!
  \brief Gaussian window sigma (px). Larger windows average the per-pixel errors (noise, the
  renderer's or sensor's sampling) better; the window (2.5 sigma) must stay clear of the
  neighbouring corners, where the X-junction's symmetry ends.
*/
double windowSigma(double spacing_px, int window) {
  if (window > 0)
    return std::max(0.8, window / 2.5);
  return std::clamp(0.25 * spacing_px, 1.0, 10.0);
}

/*! \brief Bilinear sample of a float image (callers keep (x, y) one pixel inside). */
double bilinear(const cv::Mat &f, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double ax = x - x0, ay = y - y0;
  const float *r0 = f.ptr<float>(y0), *r1 = f.ptr<float>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

/*! \brief One corner by iterated gradient orthogonality; false when it fails. */
bool refineGradient(const RefineContext &c, cv::Point2d &q, double sigma) {
  const int R = static_cast<int>(std::ceil(2.5 * sigma));
  const double inv2s2 = 1.0 / (2 * sigma * sigma);
  cv::Point2d p = q;
  for (int it = 0; it < 50; ++it) {
    const int cx = static_cast<int>(std::lround(p.x)), cy = static_cast<int>(std::lround(p.y));
    const int x0 = std::max(cx - R, 1), x1 = std::min(cx + R, c.f.cols - 2);
    const int y0 = std::max(cy - R, 1), y1 = std::min(cy + R, c.f.rows - 2);
    if (x0 > x1 || y0 > y1)
      return false;
    double a = 0, b = 0, d = 0, bx = 0, by = 0;
    for (int y = y0; y <= y1; ++y) {
      const float *gxr = c.gx.ptr<float>(y), *gyr = c.gy.ptr<float>(y);
      const double dy = y - p.y;
      for (int x = x0; x <= x1; ++x) {
        const double dx = x - p.x;
        const double w = std::exp(-(dx * dx + dy * dy) * inv2s2);
        const double gxx = gxr[x] * gxr[x] * w, gxy = gxr[x] * gyr[x] * w, gyy = gyr[x] * gyr[x] * w;
        a += gxx;
        b += gxy;
        d += gyy;
        // relative to p for conditioning
        bx += gxx * dx + gxy * dy;
        by += gxy * dx + gyy * dy;
      }
    }
    const double det = a * d - b * b;
    if (!(det > 1e-12 * (a + d) * (a + d)))
      return false;
    const double sx = (d * bx - b * by) / det, sy = (a * by - b * bx) / det;
    p.x += sx;
    p.y += sy;
    if (!std::isfinite(p.x) || !std::isfinite(p.y))
      return false;
    if (sx * sx + sy * sy < 1e-10)
      break;
  }
  q = p;
  return true;
}

bool refineSaddle(const RefineContext &c, cv::Point2d &q, double sigma);

/*!
  \brief How far the window around q departs from the X-junction's point symmetry: the RMS of
  I(x) - I(2q - x) over the Gaussian window (mirror by bilinear interpolation), divided by the
  window's weighted standard deviation of I (its contrast). Noise alone gives about
  sqrt(2) sigma_noise / contrast at any window size; anything else in the window (the board's outer
  edge, a narrow outer square, a highlight, an occluder, the image border) raises it. -1 when the
  window or its mirror leaves the image.
*/
double asymmetry(const RefineContext &c, cv::Point2d q, double sigma) {
  const int R = static_cast<int>(std::ceil(2.5 * sigma));
  const double inv2s2 = 1.0 / (2 * sigma * sigma);
  const int cx = static_cast<int>(std::lround(q.x)), cy = static_cast<int>(std::lround(q.y));
  if (cx - R - 1 < 0 || cy - R - 1 < 0 || cx + R + 2 > c.f.cols - 1 || cy + R + 2 > c.f.rows - 1)
    return -1;
  double sw = 0, sd2 = 0, si = 0, si2 = 0;
  for (int y = cy - R; y <= cy + R; ++y) {
    const float *fr = c.f.ptr<float>(y);
    const double dy = y - q.y;
    const double my = 2 * q.y - y;
    const int y0 = static_cast<int>(std::floor(my));
    const double ay = my - y0;
    const float *m0 = c.f.ptr<float>(y0), *m1 = c.f.ptr<float>(y0 + 1);
    for (int x = cx - R; x <= cx + R; ++x) {
      const double dx = x - q.x;
      const double w = std::exp(-(dx * dx + dy * dy) * inv2s2);
      const double mx = 2 * q.x - x;
      const int x0 = static_cast<int>(std::floor(mx));
      const double ax = mx - x0;
      const double mirror = (1 - ay) * ((1 - ax) * m0[x0] + ax * m0[x0 + 1]) + ay * ((1 - ax) * m1[x0] + ax * m1[x0 + 1]);
      const double d = fr[x] - mirror;
      sw += w;
      sd2 += w * d * d;
      si += w * fr[x];
      si2 += w * fr[x] * fr[x];
    }
  }
  const double var = si2 / sw - (si / sw) * (si / sw);
  if (!(var > 0))
    return -1;
  return std::sqrt(0.5 * sd2 / sw / var);
}

/*!
  \brief One corner by `refine` (gradient orthogonality or the saddle fit) with the window chosen
  per corner: Gaussian windows
  from sigma 1 px up to `sigma_max`, each started from the previous one's corner, the largest kept
  whose asymmetry() stays within 1.3x (+0.01) of the least seen so far. A large window averages
  noise and the sensor's or JPEG's per-pixel errors; it stops before anything that is not the
  X-junction (the board's outer edge beyond a narrow outer square, a highlight, the image border).
  False when even the smallest window fails.
*/
template <class Refine>
bool refineAdaptive(const RefineContext &c, cv::Point2d &q, double sigma_max, Refine refine) {
  std::vector<double> ladder;
  for (double s = sigma_max; s >= 1.0 - 1e-9; s /= std::sqrt(2.0))
    ladder.push_back(s);
  if (ladder.empty())
    ladder.push_back(sigma_max);
  std::reverse(ladder.begin(), ladder.end());
  cv::Point2d cur = q, best;
  bool have = false;
  double amin = std::numeric_limits<double>::infinity();
  for (double s : ladder) {
    cv::Point2d p = cur;
    if (!refine(c, p, s))
      break;
    const double a = asymmetry(c, p, s);
    if (a < 0)
      break;
    if (have && a > 1.3 * amin + 0.01)
      break;
    amin = std::min(amin, a);
    best = p;
    cur = p;
    have = true;
  }
  if (!have)
    return false;
  q = best;
  return true;
}

/*! \brief One corner by an iterated Gaussian-weighted quadratic (saddle) fit; false when it fails. */
bool refineSaddle(const RefineContext &c, cv::Point2d &q, double sigma) {
  const int R = static_cast<int>(std::ceil(2.5 * sigma));
  const double inv2s2 = 1.0 / (2 * sigma * sigma);
  cv::Point2d p = q;
  for (int it = 0; it < 50; ++it) {
    const int cx = static_cast<int>(std::lround(p.x)), cy = static_cast<int>(std::lround(p.y));
    const int x0 = std::max(cx - R, 0), x1 = std::min(cx + R, c.f.cols - 1);
    const int y0 = std::max(cy - R, 0), y1 = std::min(cy + R, c.f.rows - 1);
    if (x0 > x1 || y0 > y1)
      return false;
    cv::Matx<double, 6, 6> N = cv::Matx<double, 6, 6>::zeros();
    cv::Matx<double, 6, 1> rhs = cv::Matx<double, 6, 1>::zeros();
    for (int y = y0; y <= y1; ++y) {
      const float *fr = c.f.ptr<float>(y);
      const double dy = y - p.y;
      for (int x = x0; x <= x1; ++x) {
        const double dx = x - p.x;
        const double w = std::exp(-(dx * dx + dy * dy) * inv2s2);
        const double phi[6] = {1, dx, dy, dx * dx, dx * dy, dy * dy};
        for (int i = 0; i < 6; ++i) {
          rhs(i) += w * phi[i] * fr[x];
          for (int j = i; j < 6; ++j)
            N(i, j) += w * phi[i] * phi[j];
        }
      }
    }
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < i; ++j)
        N(i, j) = N(j, i);
    cv::Matx<double, 6, 1> a;
    if (!cv::solve(N, rhs, a, cv::DECOMP_CHOLESKY))
      return false;
    const double h00 = 2 * a(3), h01 = a(4), h11 = 2 * a(5);
    const double det = h00 * h11 - h01 * h01;
    if (!(det < 0)) // not a saddle
      return false;
    const double sx = -(h11 * a(1) - h01 * a(2)) / det, sy = -(h00 * a(2) - h01 * a(1)) / det;
    // Damp large steps: the quadratic model is only local.
    const double step = std::hypot(sx, sy), lim = 0.5 * sigma;
    const double k = step > lim ? lim / step : 1.0;
    p.x += k * sx;
    p.y += k * sy;
    if (!std::isfinite(p.x) || !std::isfinite(p.y))
      return false;
    if (step < 1e-5)
      break;
  }
  q = p;
  return true;
}

} // namespace

void refineChessboardCorners(const cv::Mat &gray, std::vector<cv::Point2d> &corners, double spacing_px,
                             CornerRefinement method, int window, std::vector<bool> *refined) {
  if (refined)
    refined->assign(corners.size(), true);
  if (method == CornerRefinement::None || corners.empty())
    return;
  if (gray.empty() || gray.type() != CV_8UC1)
    throw Error("refineChessboardCorners: an 8-bit grayscale image is needed");
  if (!(spacing_px > 0) || !std::isfinite(spacing_px))
    throw Error("refineChessboardCorners: the corner spacing must be > 0");
  const double max_move = 0.25 * spacing_px;
  if (method == CornerRefinement::OpenCV) {
    // At most 11 x 11: a window past half the spacing reaches beyond the narrow outer squares many
    // printed boards have, and drags the outer corners by pixels.
    const int half = window > 0 ? window : std::clamp(static_cast<int>(std::lround(0.2 * spacing_px)), 2, 5);
    std::vector<cv::Point2f> pts;
    pts.reserve(corners.size());
    for (const auto &p : corners)
      pts.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    cv::cornerSubPix(gray, pts, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const bool ok = std::isfinite(pts[i].x) && std::isfinite(pts[i].y) &&
                      std::hypot(pts[i].x - corners[i].x, pts[i].y - corners[i].y) <= max_move;
      if (ok)
        corners[i] = cv::Point2d(pts[i].x, pts[i].y);
      else if (refined)
        (*refined)[i] = false;
    }
    return;
  }
  RefineContext c;
  gray.convertTo(c.f, CV_32F);
  const double sigma = windowSigma(spacing_px, window);
  if (method == CornerRefinement::Gradient) {
    // Sobel 3x3 (Scharr and plain central differences measured the same).
    cv::Sobel(c.f, c.gx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(c.f, c.gy, CV_32F, 0, 1, 3, 1.0 / 8);
  }
  for (std::size_t i = 0; i < corners.size(); ++i) {
    cv::Point2d &p = corners[i];
    cv::Point2d q = p;
    const auto one = method == CornerRefinement::Gradient ? refineGradient : refineSaddle;
    const bool ok = window > 0 ? one(c, q, sigma) : refineAdaptive(c, q, sigma, one);
    if (ok && std::hypot(q.x - p.x, q.y - p.y) <= max_move)
      p = q;
    else if (refined)
      (*refined)[i] = false;
  }
}

// ---------------------------------------------------------------------------------------------
// Detector
// ---------------------------------------------------------------------------------------------
namespace {

vpDetectorAprilTag::vpAprilTagFamily vispFamily(const std::string &family) {
  const std::string f = normalizeAprilTagFamily(family);
  if (f == "36h11")
    return vpDetectorAprilTag::TAG_36h11;
  if (f == "25h9")
    return vpDetectorAprilTag::TAG_25h9;
  if (f == "16h5")
    return vpDetectorAprilTag::TAG_16h5;
  if (f == "circle21h7")
    return vpDetectorAprilTag::TAG_CIRCLE21h7;
#if defined(VISP_HAVE_APRILTAG_BIG_FAMILY)
  if (f == "circle49h12")
    return vpDetectorAprilTag::TAG_CIRCLE49h12;
  if (f == "custom48h12")
    return vpDetectorAprilTag::TAG_CUSTOM48h12;
  if (f == "standard41h12")
    return vpDetectorAprilTag::TAG_STANDARD41h12;
  if (f == "standard52h13")
    return vpDetectorAprilTag::TAG_STANDARD52h13;
#else
  if (f == "circle49h12" || f == "custom48h12" || f == "standard41h12" || f == "standard52h13")
    throw Error("apriltag: family '" + family +
                "' needs ViSP built with the big AprilTag families (VISP_HAVE_APRILTAG_BIG_FAMILY); "
                "this ViSP has 36h11, 25h9, 16h5 and circle21h7");
#endif
  throw Error("apriltag: family '" + family + "' is not supported by ViSP's detector");
}

/*! \brief Tag id from ViSP's message, e.g. "36h11 id: 7"; -1 when absent. */
long tagIdFromMessage(const std::string &msg) {
  const std::size_t k = msg.find("id:");
  if (k == std::string::npos)
    return -1;
  std::istringstream s(msg.substr(k + 3));
  long id = -1;
  if (!(s >> id) || id < 0)
    return -1;
  return id;
}

/*! \brief A labelling of the detected grid: board (row, col) of detected (r, c). */
struct GridMap {
  bool transpose = false, flip_r = false, flip_c = false;
};

} // namespace

struct PatternDetector::Impl {
  PatternSpec pattern;
  DetectorOptions options;
  std::unique_ptr<vpDetectorAprilTag> apriltag;
  std::map<long, cv::Point2d> previous; //!< last chessboard detection, id -> pixel
  CameraModel camera;                   //!< for the AprilTag centre (diagonals on undistorted corners)
  bool camera_ok = false;

  FrameDetection detectChessboard(const cv::Mat &gray, long frame);
  FrameDetection detectAprilTag(const cv::Mat &gray, long frame);
};

PatternDetector::PatternDetector(const PatternSpec &pattern, const DetectorOptions &options)
    : impl_(std::make_unique<Impl>()) {
  impl_->pattern = pattern;
  impl_->options = options;
  if (!(options.apriltag_decimate >= 1) || !std::isfinite(options.apriltag_decimate))
    throw Error("detector: the AprilTag decimation must be >= 1");
  if (options.threads < 1)
    throw Error("detector: threads must be >= 1");
  if (options.subpixel_window < 0)
    throw Error("detector: the sub-pixel window must be >= 0");
  if (pattern.kind == PatternSpec::Kind::Chessboard) {
    if (pattern.cols < 3 || pattern.rows < 3 || !(pattern.square > 0))
      throw Error("detector: invalid chessboard pattern " + pattern.toString());
  } else {
    impl_->apriltag = std::make_unique<vpDetectorAprilTag>(vispFamily(pattern.family));
    impl_->apriltag->setAprilTagQuadDecimate(static_cast<float>(options.apriltag_decimate));
    impl_->apriltag->setAprilTagNbThreads(options.threads);
    impl_->apriltag->setAprilTagRefineEdges(true);
  }
}

void PatternDetector::setCamera(const CameraModel &camera) {
  impl_->camera = camera;
  impl_->camera_ok = true;
}

PatternDetector::~PatternDetector() = default;
PatternDetector::PatternDetector(PatternDetector &&) noexcept = default;
PatternDetector &PatternDetector::operator=(PatternDetector &&) noexcept = default;

FrameDetection PatternDetector::detect(const cv::Mat &image, long frame) {
  FrameDetection out;
  out.frame = frame;
  try {
    if (image.empty()) {
      out.reason = "empty image";
      return out;
    }
    if (image.depth() != CV_8U) {
      out.reason = "unsupported image type (8-bit grayscale or colour expected)";
      return out;
    }
    cv::Mat gray;
    if (image.channels() == 1)
      gray = image;
    else if (image.channels() == 3)
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
    else if (image.channels() == 4)
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
    else {
      out.reason = "unsupported number of channels (" + std::to_string(image.channels()) + ")";
      return out;
    }
    if (gray.cols < 8 || gray.rows < 8) {
      out.reason = "image too small (" + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) + ")";
      return out;
    }
    if (impl_->pattern.kind == PatternSpec::Kind::Chessboard)
      return impl_->detectChessboard(gray, frame);
    return impl_->detectAprilTag(gray, frame);
  } catch (const cv::Exception &e) {
    out.found = false;
    out.features.clear();
    out.reason = std::string("OpenCV error: ") + e.err;
  } catch (const std::exception &e) {
    out.found = false;
    out.features.clear();
    out.reason = std::string("detection error: ") + e.what();
  } catch (...) {
    out.found = false;
    out.features.clear();
    out.reason = "detection error";
  }
  return out;
}

FrameDetection PatternDetector::Impl::detectChessboard(const cv::Mat &gray, long frame) {
  FrameDetection out;
  out.frame = frame;
  const int cols = pattern.cols, rows = pattern.rows;
  const std::string name = "chessboard " + std::to_string(cols) + "x" + std::to_string(rows);

  // 1. Detection. `None` reports the sector-based detector's own accurate estimate; otherwise the
  // classic detector (fast) and then the sector-based one (robust) only locate the corners.
  std::vector<cv::Point2f> found;
  const cv::Size size(cols, rows);
  bool ok = false, classic = false;
  if (options.subpixel && options.refinement != CornerRefinement::None) {
    ok = cv::findChessboardCorners(gray, size, found, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    classic = ok;
    if (!ok)
      ok = cv::findChessboardCornersSB(gray, size, found, cv::CALIB_CB_NORMALIZE_IMAGE);
  } else {
    ok = cv::findChessboardCornersSB(gray, size, found, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY);
  }
  if (!ok)
    ok = cv::findChessboardCornersSB(gray, size, found,
                                     cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY);
  if (!ok || found.size() != static_cast<std::size_t>(cols) * rows) {
    out.reason = name + " not found";
    return out;
  }
  std::vector<cv::Point2d> det(found.begin(), found.end()); // detected grid, r * cols + c

  // Corner spacing (px): smallest neighbour distance.
  double spacing = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const cv::Point2d p = det[r * cols + c];
      if (c + 1 < cols)
        spacing = std::min(spacing, cv::norm(det[r * cols + c + 1] - p));
      if (r + 1 < rows)
        spacing = std::min(spacing, cv::norm(det[(r + 1) * cols + c] - p));
    }
  if (!(spacing > 2.0)) {
    out.reason = name + ": corners closer than 2 px";
    return out;
  }

  // 2. Sub-pixel refinement, each corner on its own.
  std::vector<bool> refined; // by detected grid index; empty: all refined (or no refinement asked)
  if (options.subpixel) {
    const CornerRefinement method = options.refinement;
    // The iterative methods need a start within about a pixel: cornerSubPix first.
    if (classic || method == CornerRefinement::Gradient || method == CornerRefinement::Saddle)
      refineChessboardCorners(gray, det, spacing, CornerRefinement::OpenCV, options.subpixel_window);
    std::vector<bool> ok_final;
    if (method != CornerRefinement::OpenCV)
      refineChessboardCorners(gray, det, spacing, method, options.subpixel_window, &ok_final);
    refined = ok_final;
  }

  // 3. Ids in the board's own grid. Candidates: the grid symmetries (4, or 8 for a square board)
  // that keep the board's handedness (seen from the front, board X then Y turn clockwise in the
  // image), then the square colours: board square (a, b) is black iff a + b is even.
  auto detAt = [&](int r, int c) { return det[r * cols + c]; };
  std::vector<GridMap> candidates;
  for (int t = 0; t < (cols == rows ? 2 : 1); ++t)
    for (int fr = 0; fr < 2; ++fr)
      for (int fc = 0; fc < 2; ++fc)
        candidates.push_back(GridMap{t == 1, fr == 1, fc == 1});
  // detected (r, c) of board (R, C) under a map
  auto detOf = [&](const GridMap &m, int R, int C, int &r, int &c) {
    int a = R, b = C; // in the (possibly transposed) detected grid
    if (m.transpose)
      std::swap(a, b);
    r = m.flip_r ? rows - 1 - a : a;
    c = m.flip_c ? cols - 1 - b : b;
  };
  auto boardPixel = [&](const GridMap &m, int R, int C) {
    int r = 0, c = 0;
    detOf(m, R, C, r, c);
    return detAt(r, c);
  };
  cv::Mat fgray;
  gray.convertTo(fgray, CV_32F);
  auto sample = [&](cv::Point2d p) {
    const int x = std::clamp(static_cast<int>(std::lround(p.x)), 0, gray.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(p.y)), 0, gray.rows - 1);
    return static_cast<double>(fgray.at<float>(y, x));
  };
  std::vector<GridMap> ok_maps;
  double contrast = 0;
  for (const GridMap &m : candidates) {
    // handedness
    double cross = 0;
    for (int R = 0; R + 1 < rows; ++R)
      for (int C = 0; C + 1 < cols; ++C) {
        const cv::Point2d p = boardPixel(m, R, C), ex = boardPixel(m, R, C + 1) - p, ey = boardPixel(m, R + 1, C) - p;
        cross += ex.x * ey.y - ex.y * ey.x;
      }
    if (!(cross > 0))
      continue;
    // colours of the inner squares
    double even = 0, odd = 0;
    int ne = 0, no = 0;
    for (int R = 0; R + 1 < rows; ++R)
      for (int C = 0; C + 1 < cols; ++C) {
        const cv::Point2d p00 = boardPixel(m, R, C), p01 = boardPixel(m, R, C + 1), p10 = boardPixel(m, R + 1, C),
                          p11 = boardPixel(m, R + 1, C + 1);
        const cv::Point2d ctr = 0.25 * (p00 + p01 + p10 + p11);
        double v = sample(ctr);
        for (const cv::Point2d &q : {p00, p01, p10, p11})
          v += sample(ctr + 0.4 * (q - ctr));
        v /= 5;
        if ((R + C) % 2 == 0) {
          even += v;
          ++ne;
        } else {
          odd += v;
          ++no;
        }
      }
    even /= std::max(ne, 1);
    odd /= std::max(no, 1);
    contrast = std::max(contrast, std::abs(odd - even));
    if (even < odd)
      ok_maps.push_back(m);
  }
  if (ok_maps.empty()) {
    out.reason = name + ": cannot tell the board's orientation (square colours)";
    return out;
  }
  if (contrast < 5) {
    out.reason = name + ": too little contrast between black and white squares";
    return out;
  }
  std::size_t best = 0;
  if (ok_maps.size() > 1) {
    // Symmetric board: consistent with the previous frame (nearest assignment), else id 0
    // nearest the image's top-left.
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < ok_maps.size(); ++i) {
      double cost = 0;
      int common = 0;
      if (!previous.empty()) {
        for (int R = 0; R < rows; ++R)
          for (int C = 0; C < cols; ++C) {
            auto it = previous.find(static_cast<long>(R) * cols + C);
            if (it == previous.end())
              continue;
            const cv::Point2d d = boardPixel(ok_maps[i], R, C) - it->second;
            cost += d.dot(d);
            ++common;
          }
      }
      if (common == 0) {
        const cv::Point2d p0 = boardPixel(ok_maps[i], 0, 0);
        cost = p0.dot(p0);
      }
      if (cost < best_cost) {
        best_cost = cost;
        best = i;
      }
    }
  }
  const GridMap &m = ok_maps[best];
  std::map<long, cv::Point2d> current;
  for (int R = 0; R < rows; ++R)
    for (int C = 0; C < cols; ++C) {
      const cv::Point2d p = boardPixel(m, R, C);
      const long id = static_cast<long>(R) * cols + C;
      out.features.push_back(FeatureObservation{id, p.x, p.y});
      current[id] = p;
      int r = 0, c = 0;
      detOf(m, R, C, r, c);
      if (!refined.empty() && !refined[static_cast<std::size_t>(r) * cols + c])
        out.warnings.push_back("corner " + std::to_string(id) +
                               ": sub-pixel refinement failed, the detector's estimate kept");
    }
  previous = std::move(current);
  out.found = true;
  return out;
}

FrameDetection PatternDetector::Impl::detectAprilTag(const cv::Mat &gray, long frame) {
  FrameDetection out;
  out.frame = frame;
  vpImage<unsigned char> I;
  cv::Mat cont = gray.isContinuous() ? gray : gray.clone();
  vpImageConvert::convert(cont, I);
  if (!apriltag->detect(I)) {
    out.reason = "no AprilTag of family " + pattern.family + " found";
    return out;
  }
  std::map<long, int> count;
  std::vector<long> ids(apriltag->getNbObjects(), -1);
  for (std::size_t i = 0; i < apriltag->getNbObjects(); ++i) {
    ids[i] = tagIdFromMessage(apriltag->getMessage(i));
    if (ids[i] >= 0)
      ++count[ids[i]];
  }
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] >= 0 && count[ids[i]] > 1) {
      const std::string w = "tag " + std::to_string(ids[i]) + " seen " + std::to_string(count[ids[i]]) +
                             " times in the image: dropped (ambiguous)";
      if (std::find(out.warnings.begin(), out.warnings.end(), w) == out.warnings.end())
        out.warnings.push_back(w);
    }
    if (ids[i] < 0 || count[ids[i]] != 1 || ids[i] > std::numeric_limits<int>::max() / 5 - 1)
      continue; // unreadable or ambiguous (the same tag twice)
    const std::vector<vpImagePoint> &poly = apriltag->getPolygon(i);
    if (poly.size() != 4)
      continue;
    const int tag = static_cast<int>(ids[i]);
    // libapriltag (hence ViSP's polygon) puts pixel centres at half-integers (a pixel's top-left
    // corner is its origin); yawdepth, OpenCV and the camera model put them at integers.
    Eigen::Vector2d c[4];
    for (int k = 0; k < 4; ++k)
      c[k] = Eigen::Vector2d(poly[k].get_u() - 0.5, poly[k].get_v() - 0.5);
    // Centre: the image of the tag's centre, the intersection of the diagonals (exact for a planar
    // square under perspective; done on undistorted points, then distorted back). ViSP's getCog()
    // is the mean of the corners, which perspective biases.
    Eigen::Vector2d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    Eigen::Vector2d m[4];
    bool und = true;
    for (int k = 0; k < 4 && und; ++k)
      und = camera_ok && camera.undistort(c[k], m[k]);
    const auto diagonals = [](const Eigen::Vector2d *p, Eigen::Vector2d &x) {
      const Eigen::Vector2d d1 = p[2] - p[0], d2 = p[3] - p[1], r = p[1] - p[0];
      const double den = d1.x() * d2.y() - d1.y() * d2.x();
      if (!(std::abs(den) > 1e-12 * d1.squaredNorm() * d2.squaredNorm()))
        return false;
      const double t = (r.x() * d2.y() - r.y() * d2.x()) / den;
      x = p[0] + t * d1;
      return x.allFinite();
    };
    Eigen::Vector2d x;
    if (und && diagonals(m, x))
      centre = camera.project(x);
    else if (diagonals(c, x))
      centre = x;
    out.features.push_back(FeatureObservation{aprilTagFeatureId(tag), centre.x(), centre.y()});
    for (int k = 0; k < 4; ++k)
      out.features.push_back(FeatureObservation{aprilTagFeatureId(tag, k), c[k].x(), c[k].y()});
  }
  if (out.features.empty()) {
    out.reason = "AprilTags of family " + pattern.family + " found but none usable (duplicate or unreadable ids)";
    return out;
  }
  std::sort(out.features.begin(), out.features.end(),
            [](const FeatureObservation &a, const FeatureObservation &b) { return a.id < b.id; });
  out.found = true;
  return out;
}

std::vector<Track> PatternDetector::toTracks(const std::vector<FrameDetection> &frames) {
  std::map<long, Track> by_id;
  for (const FrameDetection &f : frames) {
    if (!f.found)
      continue;
    for (const FeatureObservation &d : f.features) {
      Track &t = by_id[d.id];
      t.id = d.id;
      t.observations.push_back(Observation{f.frame, d.u, d.v});
    }
  }
  std::vector<Track> out;
  out.reserve(by_id.size());
  for (auto &kv : by_id) {
    std::stable_sort(kv.second.observations.begin(), kv.second.observations.end(),
                     [](const Observation &a, const Observation &b) { return a.frame < b.frame; });
    out.push_back(std::move(kv.second));
  }
  return out;
}

namespace {

/* An image's size from its header (PNG, JPEG, PGM/PPM/PBM, BMP), without decoding it; false for
   other formats or a header too damaged to tell (the decoder then has the last word). */
bool headerSize(const std::vector<unsigned char> &b, std::uint64_t &w, std::uint64_t &h) {
  const std::size_t n = b.size();
  auto be32 = [&](std::size_t i) {
    return (std::uint64_t(b[i]) << 24) | (std::uint64_t(b[i + 1]) << 16) | (std::uint64_t(b[i + 2]) << 8) | b[i + 3];
  };
  auto le32 = [&](std::size_t i) {
    return std::uint64_t(std::uint32_t(b[i]) | (std::uint32_t(b[i + 1]) << 8) | (std::uint32_t(b[i + 2]) << 16) |
                         (std::uint32_t(b[i + 3]) << 24));
  };
  if (n >= 24 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') {
    w = be32(16);
    h = be32(20);
    return true;
  }
  if (n >= 4 && b[0] == 0xFF && b[1] == 0xD8) { // JPEG: the first start-of-frame marker
    std::size_t i = 2;
    while (i + 9 < n) {
      if (b[i] != 0xFF) {
        ++i;
        continue;
      }
      const unsigned char m = b[i + 1];
      if (m == 0xFF || m == 0x01 || (m >= 0xD0 && m <= 0xD9)) {
        i += (m == 0xFF) ? 1 : 2;
        continue;
      }
      const std::size_t len = (std::size_t(b[i + 2]) << 8) | b[i + 3];
      if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC) {
        h = (std::uint64_t(b[i + 5]) << 8) | b[i + 6];
        w = (std::uint64_t(b[i + 7]) << 8) | b[i + 8];
        return true;
      }
      i += 2 + len;
    }
    return false;
  }
  if (n >= 26 && b[0] == 'B' && b[1] == 'M') {
    w = le32(18);
    const std::uint32_t hh = static_cast<std::uint32_t>(le32(22));
    h = static_cast<std::uint64_t>(std::abs(static_cast<std::int64_t>(static_cast<std::int32_t>(hh))));
    return true;
  }
  if (n >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6') { // PNM: two numbers after comments
    std::size_t i = 2;
    std::uint64_t v[2] = {0, 0};
    for (std::uint64_t &value : v) {
      for (;;) {
        while (i < n && std::isspace(b[i]))
          ++i;
        if (i < n && b[i] == '#') {
          while (i < n && b[i] != '\n')
            ++i;
          continue;
        }
        break;
      }
      if (i >= n || !std::isdigit(b[i]))
        return false;
      while (i < n && std::isdigit(b[i]) && value < (std::uint64_t(1) << 40))
        value = value * 10 + (b[i++] - '0');
    }
    w = v[0];
    h = v[1];
    return true;
  }
  return false;
}

} // namespace

namespace {

/*! \brief See refineDotGridCentres(): the centroid of a dot's darkness; NaN when it fails. */
cv::Point2d darknessCentroid(const cv::Mat &f, const cv::Mat &C, cv::Point2d ce, double spacing) {
  const cv::Point2d bad(std::nan(""), std::nan(""));
  const cv::Matx22d M(C.at<double>(0, 0), C.at<double>(0, 1), C.at<double>(1, 0), C.at<double>(1, 1));
  // rho(x): the ellipse-normalised radius (1 on the outline)
  auto rho = [&](double x, double y) {
    const cv::Vec2d d(x - ce.x, y - ce.y);
    return std::sqrt(std::max(0.0, d.dot(M * d)));
  };
  const double det = M(0, 0) * M(1, 1) - M(0, 1) * M(0, 1);
  if (!(det > 0))
    return bad;
  const double rmax = std::sqrt(std::max(M(0, 0), M(1, 1)) / det); // the longest semi-axis (px)
  const double outer = std::min(1.4, 0.5 * spacing / rmax);
  if (!(outer > 1.15))
    return bad;
  const int R = static_cast<int>(std::ceil(outer * rmax)) + 1;
  const int x0 = static_cast<int>(std::floor(ce.x)) - R, x1 = static_cast<int>(std::ceil(ce.x)) + R;
  const int y0 = static_cast<int>(std::floor(ce.y)) - R, y1 = static_cast<int>(std::ceil(ce.y)) + R;
  if (x0 < 0 || y0 < 0 || x1 >= f.cols || y1 >= f.rows)
    return bad;
  std::vector<float> in, ring;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double r = rho(x, y);
      if (r < 0.6)
        in.push_back(f.at<float>(y, x));
      else if (r > 1.15 && r < outer)
        ring.push_back(f.at<float>(y, x));
    }
  if (in.size() < 5 || ring.size() < 8)
    return bad;
  auto med = [](std::vector<float> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return static_cast<double>(v[v.size() / 2]);
  };
  const double dark = med(in), ground = med(ring);
  if (!(ground - dark > 5))
    return bad;
  double sw = 0, sx = 0, sy = 0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double r = rho(x, y);
      if (r >= outer)
        continue;
      const double w = r < 0.8 ? 1.0 : std::clamp((ground - f.at<float>(y, x)) / (ground - dark), 0.0, 1.0);
      sw += w;
      sx += w * x;
      sy += w * y;
    }
  if (!(sw > 0))
    return bad;
  return cv::Point2d(sx / sw, sy / sw);
}

} // namespace

int refineDotGridCentres(const cv::Mat &gray, std::vector<cv::Point2d> &centres, int cols, int rows) {
  if (gray.empty() || gray.type() != CV_8UC1)
    throw Error("refineDotGridCentres: an 8-bit grayscale image is needed");
  if (cols < 2 || rows < 2 || centres.size() != static_cast<std::size_t>(cols) * rows)
    throw Error("refineDotGridCentres: " + std::to_string(centres.size()) + " centres for a " + std::to_string(cols) +
                "x" + std::to_string(rows) + " grid");
  cv::Mat f;
  gray.convertTo(f, CV_32F);
  double spacing = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const cv::Point2d p = centres[static_cast<std::size_t>(r) * cols + c];
      if (c + 1 < cols)
        spacing = std::min(spacing, cv::norm(centres[static_cast<std::size_t>(r) * cols + c + 1] - p));
      if (r + 1 < rows)
        spacing = std::min(spacing, cv::norm(centres[static_cast<std::size_t>(r + 1) * cols + c] - p));
    }
  if (!(spacing > 6))
    return 0;
  constexpr int kRays = 64;
  const double step = 0.25;
  std::vector<cv::Mat> conics(centres.size()); // 3x3, empty when the outline failed
  // The outline of one dot: the strongest dark-to-light edge on each ray within [r0, r1].
  auto outline = [&](cv::Point2d c0, double r0, double r1, std::vector<cv::Point2f> &pts, std::vector<double> &radii) {
    pts.clear();
    radii.clear();
    for (int k = 0; k < kRays; ++k) {
      const double a = 2 * M_PI * k / kRays;
      const cv::Point2d d(std::cos(a), std::sin(a));
      const int n = static_cast<int>((r1 - r0) / step) + 3;
      std::vector<double> prof(static_cast<std::size_t>(n));
      bool inside = true;
      for (int j = 0; j < n && inside; ++j) {
        const cv::Point2d q = c0 + (r0 + (j - 1) * step) * d;
        inside = q.x >= 1 && q.y >= 1 && q.x < f.cols - 2 && q.y < f.rows - 2;
        if (inside)
          prof[static_cast<std::size_t>(j)] = bilinear(f, q.x, q.y);
      }
      if (!inside)
        continue;
      int best = -1;
      double gbest = 0;
      std::vector<double> g(prof.size(), 0.0);
      for (std::size_t j = 1; j + 1 < prof.size(); ++j) {
        g[j] = prof[j + 1] - prof[j - 1]; // outward: dark dot to light ground is positive
        if (g[j] > gbest) {
          gbest = g[j];
          best = static_cast<int>(j);
        }
      }
      if (best < 2 || best > n - 3)
        continue;
      const std::size_t b = static_cast<std::size_t>(best);
      const double gm = g[b - 1], g0 = g[b], gp = g[b + 1];
      const double den = gm - 2 * g0 + gp;
      const double off = den < 0 ? 0.5 * (gm - gp) / den : 0.0;
      const double r = r0 + (best - 1 + off) * step;
      radii.push_back(r);
      pts.emplace_back(static_cast<float>(c0.x + r * d.x), static_cast<float>(c0.y + r * d.y));
    }
  };
  std::vector<cv::Point2d> ellipse_centres = centres;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    std::vector<cv::Point2f> pts;
    std::vector<double> radii;
    outline(centres[i], 1.0, 0.5 * spacing, pts, radii);
    if (pts.size() < kRays / 2)
      continue;
    std::vector<double> sorted = radii;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double rm = sorted[sorted.size() / 2];
    // second pass: around the median radius only (marks inside the dot, a neighbour's edge)
    outline(centres[i], std::max(1.0, 0.7 * rm), std::min(0.5 * spacing, 1.3 * rm), pts, radii);
    std::vector<cv::Point2f> kept;
    for (std::size_t k = 0; k < pts.size(); ++k)
      if (std::abs(radii[k] - rm) < 0.2 * rm + 1.0)
        kept.push_back(pts[k]);
    if (kept.size() < kRays / 2)
      continue;
    const cv::RotatedRect e = cv::fitEllipse(kept);
    const double a = 0.5 * e.size.width, b = 0.5 * e.size.height;
    if (!(a > 0.5 && b > 0.5) || cv::norm(cv::Point2d(e.center) - centres[i]) > 0.25 * spacing)
      continue;
    const double t = e.angle * M_PI / 180;
    const cv::Matx22d R(std::cos(t), -std::sin(t), std::sin(t), std::cos(t));
    const cv::Matx22d M = R * cv::Matx22d(1 / (a * a), 0, 0, 1 / (b * b)) * R.t();
    const cv::Vec2d c(e.center.x, e.center.y);
    const cv::Vec2d Mc = M * c;
    cv::Mat C = (cv::Mat_<double>(3, 3) << M(0, 0), M(0, 1), -Mc[0], M(1, 0), M(1, 1), -Mc[1], -Mc[0], -Mc[1],
                 c.dot(Mc) - 1);
    conics[i] = C;
    ellipse_centres[i] = cv::Point2d(e.center.x, e.center.y);
  }
  // Board-to-image homography from the ellipse centres, then each centre as the pole of the
  // image of the line at infinity.
  std::vector<cv::Point2d> board, img;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      if (!conics[static_cast<std::size_t>(r) * cols + c].empty()) {
        board.emplace_back(c, r);
        img.push_back(ellipse_centres[static_cast<std::size_t>(r) * cols + c]);
      }
  if (board.size() < 4)
    return 0;
  const cv::Mat H = cv::findHomography(board, img, 0);
  if (H.empty())
    return 0;
  const cv::Mat linf = H.inv().t() * (cv::Mat_<double>(3, 1) << 0, 0, 1);
  int refined = 0;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    if (conics[i].empty())
      continue;
    cv::Mat x;
    if (!cv::solve(conics[i], linf, x, cv::DECOMP_LU))
      continue;
    const double w = x.at<double>(2);
    if (!(std::abs(w) > 1e-12))
      continue;
    const cv::Point2d p(x.at<double>(0) / w, x.at<double>(1) / w);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || cv::norm(p - ellipse_centres[i]) > 0.1 * spacing)
      continue;
    // The dot's centre of darkness: blur moves no first moment, so the weighted centroid of
    // w = (ground - I) / (ground - dot), clipped to 0..1, over the dot and a ring around it is
    // its outline's centroid, i.e. the ellipse's centre; inside 0.8 of the outline w = 1 (marks
    // printed in the dot do not count). Then the perspective offset from the pole.
    const cv::Point2d m = darknessCentroid(f, conics[i], ellipse_centres[i], spacing);
    if (!std::isfinite(m.x) || cv::norm(m - ellipse_centres[i]) > 0.1 * spacing)
      continue;
    centres[i] = m + (p - ellipse_centres[i]);
    ++refined;
  }
  return refined;
}

cv::Mat drawDetection(const cv::Mat &image, const FrameDetection &d) {
  // A gray canvas for what cannot be shown (empty, not 8-bit, odd channel count).
  cv::Mat out(image.empty() ? 480 : image.rows, image.empty() ? 640 : image.cols, CV_8UC3, cv::Scalar(60, 60, 60));
  if (!image.empty() && image.depth() == CV_8U) {
    if (image.channels() == 1)
      cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
    else if (image.channels() == 4)
      cv::cvtColor(image, out, cv::COLOR_BGRA2BGR);
    else if (image.channels() == 3)
      image.copyTo(out);
  }
  const double scale = std::max(0.35, out.cols / 1800.0);
  const int r = std::max(3, out.cols / 200);
  std::map<long, cv::Point2d> at;
  for (const auto &f : d.features)
    at[f.id] = cv::Point2d(f.u, f.v);
  // chessboard: the first row's direction from corner 0 to corner 1
  if (at.count(0) && at.count(1))
    cv::arrowedLine(out, at[0], at[1], cv::Scalar(0, 200, 0), 1, cv::LINE_AA, 0, 0.2);
  for (const auto &f : d.features) {
    const cv::Point p(static_cast<int>(std::lround(f.u)), static_cast<int>(std::lround(f.v)));
    const cv::Scalar col = f.id == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 80, 0);
    cv::drawMarker(out, p, col, cv::MARKER_CROSS, 2 * r, 1, cv::LINE_AA);
    cv::putText(out, std::to_string(f.id), p + cv::Point(3, -3), cv::FONT_HERSHEY_SIMPLEX, scale, col, 1, cv::LINE_AA);
  }
  for (const std::string &w : d.warnings) {
    long id = -1;
    if (std::sscanf(w.c_str(), "corner %ld", &id) == 1 && at.count(id))
      cv::circle(out, at[id], 3 * r, cv::Scalar(0, 140, 255), 2, cv::LINE_AA);
  }
  const std::string title = "frame " + std::to_string(d.frame) + ": " +
                            (d.found ? std::to_string(d.features.size()) + " features" : "NOT FOUND: " + d.reason) +
                            (d.warnings.empty() ? std::string() : ", " + std::to_string(d.warnings.size()) + " warning(s)");
  cv::putText(out, title, cv::Point(6, static_cast<int>(18 * scale / 0.35)), cv::FONT_HERSHEY_SIMPLEX, scale * 1.2,
              cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(out, title, cv::Point(6, static_cast<int>(18 * scale / 0.35)), cv::FONT_HERSHEY_SIMPLEX, scale * 1.2,
              d.found ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255), 1, cv::LINE_AA);
  return out;
}

cv::Mat readGrayImage(const std::string &path, const CameraModel &camera)
{
  cv::Mat image = readGrayImage(path);
  if (camera.width() > 0 &&
      (image.cols != static_cast<int>(camera.width()) || image.rows != static_cast<int>(camera.height())))
    throw Error(path + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                " but the camera is " + std::to_string(camera.width()) + "x" + std::to_string(camera.height()));
  return image;
}

cv::Mat readGrayImage(const std::string &path) {
  // Read the bytes ourselves (clear messages for missing, empty, endless or huge files; only a
  // regular file or a pipe), check the size its header declares, then decode in memory.
  // The decoders of OpenCV and libpng/libjpeg print their own complaints on stderr for damaged
  // files; the library must not print, so stderr is silenced while decoding.
  constexpr std::size_t kMaxImageBytes = std::size_t(512) << 20;
  constexpr std::uint64_t kMaxImagePixels = std::uint64_t(1) << 28; // 268 Mpx: 16384 x 16384
  std::vector<unsigned char> bytes;
  try {
    bytes = readBinaryFile(path, kMaxImageBytes);
  } catch (const Error &e) {
    const std::string what = e.what();
    const std::string rest = what.compare(0, path.size() + 2, path + ": ") == 0 ? what.substr(path.size() + 2) : what;
    throw Error(path + ": cannot read image (" + rest + ")");
  }
  std::uint64_t w = 0, h = 0;
  if (headerSize(bytes, w, h) && (w == 0 || h == 0 || w > kMaxImagePixels || h > kMaxImagePixels ||
                                  w * h > kMaxImagePixels)) // (each side first: the product must not overflow)
    throw Error(path + ": cannot read image (its header declares " + std::to_string(w) + " x " + std::to_string(h) +
                " pixels; at most " + std::to_string(kMaxImagePixels) + " pixels are read)");
  cv::Mat img;
  {
    static std::mutex stderr_mutex;
    std::lock_guard<std::mutex> lock(stderr_mutex);
    std::fflush(stderr);
    const int saved = dup(STDERR_FILENO);
    const int null_fd = open("/dev/null", O_WRONLY);
    if (saved >= 0 && null_fd >= 0)
      dup2(null_fd, STDERR_FILENO);
    std::string failure;
    try {
      img = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception &e) {
      failure = e.err;
    }
    std::fflush(stderr);
    if (saved >= 0) {
      dup2(saved, STDERR_FILENO);
      close(saved);
    }
    if (null_fd >= 0)
      close(null_fd);
    if (!failure.empty())
      throw Error(path + ": cannot read image (" + failure + ")");
  }
  if (img.empty())
    throw Error(path + ": cannot read image (truncated, damaged or not an image)");
  if (img.depth() != CV_8U) {
    cv::Mat eight;
    img.convertTo(eight, CV_8U, img.depth() == CV_16U ? 1.0 / 256 : 1.0);
    img = eight;
  }
  return img;
}

} // namespace yawdepth
