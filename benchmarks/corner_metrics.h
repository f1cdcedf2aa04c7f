#pragma once
/*!
  \file corner_metrics.h
  \brief Corner accuracy without ground truth (homography fit and straightness of a planar board's
  corners in the undistorted image) and the stock-OpenCV peer pipelines; shared by bench_corners
  and the tests.
*/
#include <algorithm>
#include <cmath>
#include <vector>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_common.h" // median()

namespace yawdepth {
namespace bench {

/*! Corners of one image, row-major over the board's grid; empty when not found. */
using Corners = std::vector<cv::Point2f>;

/*! The peer pipelines: what a user of stock OpenCV would write. */
inline Corners opencvSubPix(const cv::Mat &gray, int cols, int rows, int half) {
  Corners c;
  if (!cv::findChessboardCorners(gray, cv::Size(cols, rows), c, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
    if (!cv::findChessboardCornersSB(gray, cv::Size(cols, rows), c, cv::CALIB_CB_NORMALIZE_IMAGE))
      return {};
  cv::cornerSubPix(gray, c, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  return c;
}

inline Corners opencvSB(const cv::Mat &gray, int cols, int rows) {
  Corners c;
  if (!cv::findChessboardCornersSB(gray, cv::Size(cols, rows), c, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY))
    return {};
  return c;
}


/*! \brief Homography RMS, the same less a smooth field, straightness (px). */
struct Fit {
  double h_rms = 0, straight = 0, smooth_rms = 0;
};

/*! Reorder `c` to the order of `ref` (nearest neighbour, each used once); false when it fails. */
inline bool matchOrder(const Corners &ref, Corners &c) {
  if (c.size() != ref.size())
    return false;
  Corners out(ref.size());
  std::vector<bool> used(c.size(), false);
  for (std::size_t i = 0; i < ref.size(); ++i) {
    double best = 1e30;
    std::size_t bj = 0;
    for (std::size_t j = 0; j < c.size(); ++j) {
      const double d = cv::norm(c[j] - ref[i]);
      if (!used[j] && d < best) {
        best = d;
        bj = j;
      }
    }
    if (best > 3.0)
      return false;
    used[bj] = true;
    out[i] = c[bj];
  }
  c = out;
  return true;
}



/*!
  The corners of a planar board (row-major, `cols` per row), undistorted with (K, dist), against
  one homography: homography RMS per coordinate sqrt(SSE / (2N - 8)), the same less a quadratic
  field per axis (what a bent sheet or a lens misfit leaves), and row/column straightness.
*/
inline Fit planarFit(const Corners &distorted, int cols, int rows, const cv::Mat &K, const cv::Mat &dist) {
  struct {
    int cols, rows;
  } s{cols, rows};
  Corners und;
  cv::undistortPoints(distorted, und, K, dist, cv::noArray(), K);
  std::vector<cv::Point2f> board;
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.cols; ++c)
      board.emplace_back(static_cast<float>(c), static_cast<float>(r));
  const cv::Mat H = cv::findHomography(board, und, 0);
  Fit f;
  std::vector<cv::Point2f> proj;
  cv::perspectiveTransform(board, proj, H);
  double sse = 0;
  for (std::size_t i = 0; i < und.size(); ++i) {
    const cv::Point2f e = proj[i] - und[i];
    sse += e.dot(e);
  }
  f.h_rms = std::sqrt(sse / (2.0 * und.size() - 8));
  // The same residuals less a smooth field (quadratic in the board coordinates, per axis): what
  // is left after a bent sheet or a lens model's misfit, i.e. the corners' own noise.
  {
    const int n = static_cast<int>(und.size());
    cv::Mat A(n, 6, CV_64F), bx(n, 1, CV_64F), by(n, 1, CV_64F);
    const double sc = 1.0 / std::max(s.cols, s.rows);
    for (int i = 0; i < n; ++i) {
      const double x = board[i].x * sc, y = board[i].y * sc;
      const double row[6] = {1, x, y, x * x, x * y, y * y};
      for (int k = 0; k < 6; ++k)
        A.at<double>(i, k) = row[k];
      bx.at<double>(i) = und[i].x - proj[i].x;
      by.at<double>(i) = und[i].y - proj[i].y;
    }
    cv::Mat cx, cy;
    cv::solve(A, bx, cx, cv::DECOMP_SVD);
    cv::solve(A, by, cy, cv::DECOMP_SVD);
    const cv::Mat rx = bx - A * cx, ry = by - A * cy;
    f.smooth_rms = std::sqrt((rx.dot(rx) + ry.dot(ry)) / (2.0 * n - 8 - 12));
  }
  // lines: rows and columns
  double lsse = 0;
  int ldof = 0;
  auto line = [&](std::vector<cv::Point2f> p) {
    cv::Vec4f l;
    cv::fitLine(p, l, cv::DIST_L2, 0, 1e-7, 1e-7);
    for (const auto &q : p) {
      const double d = (q.x - l[2]) * -l[1] + (q.y - l[3]) * l[0];
      lsse += d * d;
    }
    ldof += static_cast<int>(p.size()) - 2;
  };
  for (int r = 0; r < s.rows; ++r) {
    std::vector<cv::Point2f> p;
    for (int c = 0; c < s.cols; ++c)
      p.push_back(und[r * s.cols + c]);
    line(p);
  }
  for (int c = 0; c < s.cols; ++c) {
    std::vector<cv::Point2f> p;
    for (int r = 0; r < s.rows; ++r)
      p.push_back(und[r * s.cols + c]);
    line(p);
  }
  f.straight = std::sqrt(lsse / ldof);
  return f;
}


/*!
  \brief A synthetic photo of a cols x rows grid of dark dots (diameter `dot` in grid units of 1)
  seen through the board-to-image homography H (board (c, r) -> pixel): each dot's exact projected
  outline filled at 8x resolution and area-averaged, Gaussian blur `blur` px, noise `noise` gray
  levels (seeded). `truth` receives the exact image of each dot's centre (row-major).
*/
inline cv::Mat dotGridImage(const cv::Matx33d &H, int cols, int rows, double dot, cv::Size size, double blur,
                            double noise, unsigned seed, std::vector<cv::Point2f> &truth) {
  const int k = 8;
  cv::Mat big(size.height * k, size.width * k, CV_8UC1, cv::Scalar(215));
  truth.clear();
  auto map = [&](double x, double y) {
    const cv::Vec3d p = H * cv::Vec3d(x, y, 1);
    return cv::Point2d(p[0] / p[2], p[1] / p[2]);
  };
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      std::vector<cv::Point> poly;
      for (int a = 0; a < 720; ++a) {
        const double t = 2 * M_PI * a / 720;
        const cv::Point2d q = map(c + 0.5 * dot * std::cos(t), r + 0.5 * dot * std::sin(t));
        // pixel centres at integers: the big image's pixel (i) covers [i/k - 1/2, (i+1)/k - 1/2)
        poly.emplace_back(static_cast<int>(std::lround((q.x + 0.5) * k * 16 - 8)),
                          static_cast<int>(std::lround((q.y + 0.5) * k * 16 - 8)));
      }
      cv::fillPoly(big, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(35), cv::LINE_AA, 4);
      const cv::Point2d t = map(c, r);
      truth.emplace_back(static_cast<float>(t.x), static_cast<float>(t.y));
    }
  cv::Mat img;
  cv::resize(big, img, size, 0, 0, cv::INTER_AREA);
  img.convertTo(img, CV_32F);
  if (blur > 0)
    cv::GaussianBlur(img, img, cv::Size(0, 0), blur);
  if (noise > 0) {
    cv::Mat n(img.size(), CV_32F);
    cv::RNG rng(seed);
    rng.fill(n, cv::RNG::NORMAL, 0, noise);
    img += n;
  }
  cv::Mat out;
  img.convertTo(out, CV_8U);
  return out;
}

} // namespace bench
} // namespace yawdepth
