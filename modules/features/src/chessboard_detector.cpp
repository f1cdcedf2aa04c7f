/*!
  \file chessboard_detector.cpp
  \brief Chessboard corners: OpenCV's detection, the sub-pixel refinement (corner_refinement.cpp)
  and ids in the board's own grid (handedness, square colours, the previous frame).
*/
#include "detector_impl.h"
#include "grid_spacing.h"

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

/*! \brief The detected corners, row by row (detected (r, c) at r * cols + c), and the board's size. */
struct DetectedGrid {
  const std::vector<cv::Point2d> &det;
  int cols, rows;

  /*! \brief Detected (r, c) of board (R, C) under the labelling m. */
  void cellOf(const GridMap &m, int R, int C, int &r, int &c) const {
    int a = R, b = C; // in the (possibly transposed) detected grid
    if (m.transpose)
      std::swap(a, b);
    r = m.flip_r ? rows - 1 - a : a;
    c = m.flip_c ? cols - 1 - b : b;
  }
  /*! \brief The pixel of board corner (R, C) under the labelling m. */
  cv::Point2d boardPixel(const GridMap &m, int R, int C) const {
    int r = 0, c = 0;
    cellOf(m, R, C, r, c);
    return det[r * cols + c];
  }
};

/*!
  \brief Step 1, the detection. `None` reports the sector-based detector's own accurate estimate;
  otherwise the classic detector (fast) and then the sector-based one (robust) only locate the
  corners. `classic`: the classic detector found them. False when no detector found the board.
*/
bool locateChessboardCorners(const cv::Mat &gray, const cv::Size &size, const DetectorOptions &options,
                             std::vector<cv::Point2f> &found, bool &classic) {
  bool ok = false;
  classic = false;
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
  return ok;
}

/*!
  \brief Step 2, the sub-pixel refinement, each corner on its own. Returns, by detected grid index,
  whether each corner's refinement succeeded; empty: all refined (or no refinement asked).
*/
std::vector<bool> refineDetectedCorners(const cv::Mat &gray, std::vector<cv::Point2d> &det, double spacing, bool classic,
                                        const DetectorOptions &options) {
  std::vector<bool> refined;
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
  return refined;
}

/*! \brief The grid symmetries a labelling can be: 4, or 8 for a square board. */
std::vector<GridMap> gridSymmetries(int cols, int rows) {
  std::vector<GridMap> candidates;
  for (int t = 0; t < (cols == rows ? 2 : 1); ++t)
    for (int fr = 0; fr < 2; ++fr)
      for (int fc = 0; fc < 2; ++fc)
        candidates.push_back(GridMap{t == 1, fr == 1, fc == 1});
  return candidates;
}

/*! \brief Whether the labelling keeps the board's handedness: seen from the front, board X then Y
    turn clockwise in the image. */
bool keepsHandedness(const DetectedGrid &g, const GridMap &m) {
  double cross = 0;
  for (int R = 0; R + 1 < g.rows; ++R)
    for (int C = 0; C + 1 < g.cols; ++C) {
      const cv::Point2d p = g.boardPixel(m, R, C), ex = g.boardPixel(m, R, C + 1) - p, ey = g.boardPixel(m, R + 1, C) - p;
      cross += ex.x * ey.y - ex.y * ey.x;
    }
  return cross > 0;
}

/*! \brief Mean gray levels of the inner squares whose board (row + col) is even, and odd. */
struct SquareColours {
  double even = 0, odd = 0;
};

/*! \brief The inner squares' mean gray levels under the labelling m (each square sampled at its
    centre and 0.4 of the way to its four corners); `fgray` is the image as float. */
SquareColours squareColours(const DetectedGrid &g, const GridMap &m, const cv::Mat &fgray) {
  auto sample = [&](cv::Point2d p) {
    const int x = std::clamp(static_cast<int>(std::lround(p.x)), 0, fgray.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(p.y)), 0, fgray.rows - 1);
    return static_cast<double>(fgray.at<float>(y, x));
  };
  SquareColours s;
  int ne = 0, no = 0;
  for (int R = 0; R + 1 < g.rows; ++R)
    for (int C = 0; C + 1 < g.cols; ++C) {
      const cv::Point2d p00 = g.boardPixel(m, R, C), p01 = g.boardPixel(m, R, C + 1), p10 = g.boardPixel(m, R + 1, C),
                        p11 = g.boardPixel(m, R + 1, C + 1);
      const cv::Point2d ctr = 0.25 * (p00 + p01 + p10 + p11);
      double v = sample(ctr);
      for (const cv::Point2d &q : {p00, p01, p10, p11})
        v += sample(ctr + 0.4 * (q - ctr));
      v /= 5;
      if ((R + C) % 2 == 0) {
        s.even += v;
        ++ne;
      } else {
        s.odd += v;
        ++no;
      }
    }
  s.even /= std::max(ne, 1);
  s.odd /= std::max(no, 1);
  return s;
}

/*!
  \brief The labellings that keep the board's handedness and match its square colours (board
  square (a, b) is black iff a + b is even). `contrast` receives the largest difference between
  the two colours' mean gray levels over the labellings of the right handedness.
*/
std::vector<GridMap> labellingsMatchingBoard(const DetectedGrid &g, const cv::Mat &gray, double &contrast) {
  cv::Mat fgray;
  gray.convertTo(fgray, CV_32F);
  std::vector<GridMap> ok_maps;
  contrast = 0;
  for (const GridMap &m : gridSymmetries(g.cols, g.rows)) {
    if (!keepsHandedness(g, m))
      continue;
    const SquareColours s = squareColours(g, m, fgray);
    contrast = std::max(contrast, std::abs(s.odd - s.even));
    if (s.even < s.odd)
      ok_maps.push_back(m);
  }
  return ok_maps;
}

/*!
  \brief Of several labellings (a symmetric board), the one consistent with the previous frame
  (nearest assignment), else the one with id 0 nearest the image's top-left. The index in `maps`.
*/
std::size_t nearestLabelling(const DetectedGrid &g, const std::vector<GridMap> &maps,
                             const std::map<long, cv::Point2d> &previous) {
  std::size_t best = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < maps.size(); ++i) {
    double cost = 0;
    int common = 0;
    if (!previous.empty()) {
      for (int R = 0; R < g.rows; ++R)
        for (int C = 0; C < g.cols; ++C) {
          auto it = previous.find(static_cast<long>(R) * g.cols + C);
          if (it == previous.end())
            continue;
          const cv::Point2d d = g.boardPixel(maps[i], R, C) - it->second;
          cost += d.dot(d);
          ++common;
        }
    }
    if (common == 0) {
      const cv::Point2d p0 = g.boardPixel(maps[i], 0, 0);
      cost = p0.dot(p0);
    }
    if (cost < best_cost) {
      best_cost = cost;
      best = i;
    }
  }
  return best;
}

/*!
  \brief The corners under the labelling m into `out` (ids R * cols + C, row by row), a warning for
  each corner whose refinement failed (`refined` by detected grid index, empty: all refined);
  `current` receives id -> pixel.
*/
void labelCorners(const DetectedGrid &g, const GridMap &m, const std::vector<bool> &refined, FrameDetection &out,
                  std::map<long, cv::Point2d> &current) {
  for (int R = 0; R < g.rows; ++R)
    for (int C = 0; C < g.cols; ++C) {
      const cv::Point2d p = g.boardPixel(m, R, C);
      const long id = static_cast<long>(R) * g.cols + C;
      out.features.push_back(FeatureObservation{id, p.x, p.y});
      current[id] = p;
      int r = 0, c = 0;
      g.cellOf(m, R, C, r, c);
      if (!refined.empty() && !refined[static_cast<std::size_t>(r) * g.cols + c])
        out.warnings.push_back("corner " + std::to_string(id) +
                               ": sub-pixel refinement failed, the detector's estimate kept");
    }
}

} // namespace

FrameDetection PatternDetector::Impl::detectChessboard(const cv::Mat &gray, long frame) {
  FrameDetection out;
  out.frame = frame;
  const int cols = pattern.cols, rows = pattern.rows;
  const std::string name = "chessboard " + std::to_string(cols) + "x" + std::to_string(rows);

  // 1. Detection.
  std::vector<cv::Point2f> found;
  bool classic = false;
  const bool ok = locateChessboardCorners(gray, cv::Size(cols, rows), options, found, classic);
  if (!ok || found.size() != static_cast<std::size_t>(cols) * rows) {
    out.reason = name + " not found";
    return out;
  }
  std::vector<cv::Point2d> det(found.begin(), found.end()); // detected grid, r * cols + c

  // Corner spacing (px): smallest neighbour distance.
  const double spacing = smallestNeighbourDistance(det, cols, rows);
  if (!(spacing > 2.0)) {
    out.reason = name + ": corners closer than 2 px";
    return out;
  }

  // 2. Sub-pixel refinement, each corner on its own.
  const std::vector<bool> refined = refineDetectedCorners(gray, det, spacing, classic, options);

  // 3. Ids in the board's own grid. Candidates: the grid symmetries (4, or 8 for a square board)
  // that keep the board's handedness, then the square colours.
  const DetectedGrid grid{det, cols, rows};
  double contrast = 0;
  const std::vector<GridMap> ok_maps = labellingsMatchingBoard(grid, gray, contrast);
  if (ok_maps.empty()) {
    out.reason = name + ": cannot tell the board's orientation (square colours)";
    return out;
  }
  if (contrast < 5) {
    out.reason = name + ": too little contrast between black and white squares";
    return out;
  }
  const std::size_t best = ok_maps.size() > 1 ? nearestLabelling(grid, ok_maps, previous) : 0;
  std::map<long, cv::Point2d> current;
  labelCorners(grid, ok_maps[best], refined, out, current);
  previous = std::move(current);
  out.found = true;
  return out;
}

} // namespace yawdepth
