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

} // namespace yawdepth
