/*!
  \file corner_refinement.cpp
  \brief Sub-pixel refinement of chessboard corners (X-junctions): cv::cornerSubPix, iterated
  gradient orthogonality and the saddle fit, with the window chosen per corner.
*/
#include <yawdepth/features/detector.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>
#include <opencv2/imgproc.hpp>
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

} // namespace yawdepth
