#pragma once
/*!
  \file grid_spacing.h
  \brief The spacing of a detected grid of points (private to the features module).
*/
#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>
#include <opencv2/core.hpp>

namespace yawdepth {

/*! \brief The smallest distance (px) between row or column neighbours of a cols x rows grid of
    points stored row by row (point (r, c) at r * cols + c); infinity for a single point. */
inline double smallestNeighbourDistance(const std::vector<cv::Point2d> &grid, int cols, int rows) {
  double spacing = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const cv::Point2d p = grid[static_cast<std::size_t>(r) * cols + c];
      if (c + 1 < cols)
        spacing = std::min(spacing, cv::norm(grid[static_cast<std::size_t>(r) * cols + c + 1] - p));
      if (r + 1 < rows)
        spacing = std::min(spacing, cv::norm(grid[static_cast<std::size_t>(r + 1) * cols + c] - p));
    }
  return spacing;
}

} // namespace yawdepth
