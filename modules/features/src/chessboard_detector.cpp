/*!
  \file chessboard_detector.cpp
  \brief Chessboard corners: OpenCV's detection, the sub-pixel refinement (corner_refinement.cpp)
  and ids in the board's own grid (handedness, square colours, the previous frame).
*/
#include "detector_impl.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace yawdepth {

namespace {

/*! \brief A labelling of the detected grid: board (row, col) of detected (r, c). */
struct GridMap {
  bool transpose = false, flip_r = false, flip_c = false;
};

} // namespace

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

} // namespace yawdepth
