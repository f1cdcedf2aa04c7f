/*!
  \file dot_grid.cpp
  \brief Centres of a planar grid of dark round dots: ellipse outlines, centres of darkness and
  the perspective pole (see refineDotGridCentres()).
*/
#include <yawdepth/features/detector.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <yawdepth/error.h>

#include "grid_spacing.h"

namespace yawdepth {

namespace {

/*! \brief Bilinear sample of a float image (callers keep (x, y) one pixel inside). */
double bilinear(const cv::Mat &f, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double ax = x - x0, ay = y - y0;
  const float *r0 = f.ptr<float>(y0), *r1 = f.ptr<float>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

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

constexpr int kOutlineRays = 64;       //!< rays on which a dot's outline is searched
constexpr double kOutlineStep = 0.25;  //!< sampling step along a ray (px)

/*!
  \brief The radius of the strongest dark-to-light edge on the ray from c0 along the unit vector d
  within [r0, r1] (px; the gradient's peak, refined by a parabola); NaN when the ray leaves the
  image or the peak is at an end of the ray.
*/
double edgeRadiusOnRay(const cv::Mat &f, cv::Point2d c0, cv::Point2d d, double r0, double r1) {
  const double none = std::numeric_limits<double>::quiet_NaN();
  const int n = static_cast<int>((r1 - r0) / kOutlineStep) + 3;
  std::vector<double> prof(static_cast<std::size_t>(n));
  bool inside = true;
  for (int j = 0; j < n && inside; ++j) {
    const cv::Point2d q = c0 + (r0 + (j - 1) * kOutlineStep) * d;
    inside = q.x >= 1 && q.y >= 1 && q.x < f.cols - 2 && q.y < f.rows - 2;
    if (inside)
      prof[static_cast<std::size_t>(j)] = bilinear(f, q.x, q.y);
  }
  if (!inside)
    return none;
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
    return none;
  const std::size_t b = static_cast<std::size_t>(best);
  const double gm = g[b - 1], g0 = g[b], gp = g[b + 1];
  const double den = gm - 2 * g0 + gp;
  const double off = den < 0 ? 0.5 * (gm - gp) / den : 0.0;
  return r0 + (best - 1 + off) * kOutlineStep;
}

/*! \brief The outline of one dot: the strongest dark-to-light edge on each of kOutlineRays rays
    from c0 within [r0, r1]: the edge points and their radii (rays without an edge left out). */
void dotOutline(const cv::Mat &f, cv::Point2d c0, double r0, double r1, std::vector<cv::Point2f> &pts,
                std::vector<double> &radii) {
  pts.clear();
  radii.clear();
  for (int k = 0; k < kOutlineRays; ++k) {
    const double a = 2 * M_PI * k / kOutlineRays;
    const cv::Point2d d(std::cos(a), std::sin(a));
    const double r = edgeRadiusOnRay(f, c0, d, r0, r1);
    if (std::isnan(r))
      continue;
    radii.push_back(r);
    pts.emplace_back(static_cast<float>(c0.x + r * d.x), static_cast<float>(c0.y + r * d.y));
  }
}

/*!
  \brief The ellipse of one dot from its rough centre: the outline within half the spacing, then
  again around its median radius only (marks inside the dot, a neighbour's edge), the edges far
  from the median dropped. `conic` receives it as a 3x3 conic C (x^T C x = 0 on the outline),
  `ellipse_centre` its centre. False when too few rays found the edge, the ellipse is degenerate or
  its centre is more than a quarter of the spacing from the rough one.
*/
bool fitDotEllipse(const cv::Mat &f, cv::Point2d centre, double spacing, cv::Mat &conic, cv::Point2d &ellipse_centre) {
  std::vector<cv::Point2f> pts;
  std::vector<double> radii;
  dotOutline(f, centre, 1.0, 0.5 * spacing, pts, radii);
  if (pts.size() < kOutlineRays / 2)
    return false;
  std::vector<double> sorted = radii;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double rm = sorted[sorted.size() / 2];
  dotOutline(f, centre, std::max(1.0, 0.7 * rm), std::min(0.5 * spacing, 1.3 * rm), pts, radii);
  std::vector<cv::Point2f> kept;
  for (std::size_t k = 0; k < pts.size(); ++k)
    if (std::abs(radii[k] - rm) < 0.2 * rm + 1.0)
      kept.push_back(pts[k]);
  if (kept.size() < kOutlineRays / 2)
    return false;
  const cv::RotatedRect e = cv::fitEllipse(kept);
  const double a = 0.5 * e.size.width, b = 0.5 * e.size.height;
  if (!(a > 0.5 && b > 0.5) || cv::norm(cv::Point2d(e.center) - centre) > 0.25 * spacing)
    return false;
  const double t = e.angle * M_PI / 180;
  const cv::Matx22d R(std::cos(t), -std::sin(t), std::sin(t), std::cos(t));
  const cv::Matx22d M = R * cv::Matx22d(1 / (a * a), 0, 0, 1 / (b * b)) * R.t();
  const cv::Vec2d c(e.center.x, e.center.y);
  const cv::Vec2d Mc = M * c;
  conic = (cv::Mat_<double>(3, 3) << M(0, 0), M(0, 1), -Mc[0], M(1, 0), M(1, 1), -Mc[1], -Mc[0], -Mc[1], c.dot(Mc) - 1);
  ellipse_centre = cv::Point2d(e.center.x, e.center.y);
  return true;
}

/*!
  \brief The image of the grid plane's line at infinity, H^-T (0, 0, 1)^T, H the board-to-image
  homography from the centres of the dots that have an ellipse (`conics` not empty); empty when
  fewer than 4 dots have one or no homography is found.
*/
cv::Mat imageOfLineAtInfinity(const std::vector<cv::Mat> &conics, const std::vector<cv::Point2d> &ellipse_centres,
                              int cols, int rows) {
  std::vector<cv::Point2d> board, img;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      if (!conics[static_cast<std::size_t>(r) * cols + c].empty()) {
        board.emplace_back(c, r);
        img.push_back(ellipse_centres[static_cast<std::size_t>(r) * cols + c]);
      }
  if (board.size() < 4)
    return cv::Mat();
  const cv::Mat H = cv::findHomography(board, img, 0);
  if (H.empty())
    return cv::Mat();
  return H.inv().t() * (cv::Mat_<double>(3, 1) << 0, 0, 1);
}

/*!
  \brief One dot's refined centre: its centre of darkness (darknessCentroid()) moved by the
  perspective offset of the pole of `linf` with respect to its ellipse `conic` from the ellipse's
  centre. False when the pole or the centroid fails or either strays more than a tenth of the
  spacing from the ellipse's centre.
*/
bool perspectiveCentre(const cv::Mat &f, const cv::Mat &conic, const cv::Mat &linf, cv::Point2d ellipse_centre,
                       double spacing, cv::Point2d &centre) {
  cv::Mat x;
  if (!cv::solve(conic, linf, x, cv::DECOMP_LU))
    return false;
  const double w = x.at<double>(2);
  if (!(std::abs(w) > 1e-12))
    return false;
  const cv::Point2d p(x.at<double>(0) / w, x.at<double>(1) / w);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || cv::norm(p - ellipse_centre) > 0.1 * spacing)
    return false;
  // The dot's centre of darkness: blur moves no first moment, so the weighted centroid of
  // w = (ground - I) / (ground - dot), clipped to 0..1, over the dot and a ring around it is
  // its outline's centroid, i.e. the ellipse's centre; inside 0.8 of the outline w = 1 (marks
  // printed in the dot do not count). Then the perspective offset from the pole.
  const cv::Point2d m = darknessCentroid(f, conic, ellipse_centre, spacing);
  if (!std::isfinite(m.x) || cv::norm(m - ellipse_centre) > 0.1 * spacing)
    return false;
  centre = m + (p - ellipse_centre);
  return true;
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
  const double spacing = smallestNeighbourDistance(centres, cols, rows);
  if (!(spacing > 6))
    return 0;
  std::vector<cv::Mat> conics(centres.size()); // 3x3, empty when the outline failed
  std::vector<cv::Point2d> ellipse_centres = centres;
  for (std::size_t i = 0; i < centres.size(); ++i)
    fitDotEllipse(f, centres[i], spacing, conics[i], ellipse_centres[i]);
  // Board-to-image homography from the ellipse centres, then each centre as the pole of the
  // image of the line at infinity.
  const cv::Mat linf = imageOfLineAtInfinity(conics, ellipse_centres, cols, rows);
  if (linf.empty())
    return 0;
  int refined = 0;
  for (std::size_t i = 0; i < centres.size(); ++i)
    if (!conics[i].empty() && perspectiveCentre(f, conics[i], linf, ellipse_centres[i], spacing, centres[i]))
      ++refined;
  return refined;
}

} // namespace yawdepth
