#pragma once
/*
  Private to yawdepth::calibration: the pieces the yaw-rig and the hand-eye least-squares problems
  share (the views' board points and pixels and their residuals, central-difference Jacobians,
  the damped Levenberg–Marquardt step).
*/
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <yawdepth/camera/camera_model.h>

namespace yawdepth {
namespace calibration_detail {

/* The board points and observed pixels of each view, and the number of pixel residuals (two per
   point). */
struct BoardObservations {
  std::vector<std::vector<Eigen::Vector3d>> points; // board points per view
  std::vector<std::vector<Eigen::Vector2d>> pixels; // observed pixels per view
  std::size_t residuals = 0;

  void add(std::vector<Eigen::Vector3d> &&P, std::vector<Eigen::Vector2d> &&uv)
  {
    points.push_back(std::move(P));
    pixels.push_back(std::move(uv));
    residuals += 2 * points.back().size();
  }

  /* View i's pixel residuals (projected minus observed, times `scale`) with the board at cMb and its
     points times `board_scale`, into r from index k on (k advanced); a point behind the camera gives
     a large, smooth-enough 1e4. */
  void pixelResiduals(const CameraModel &camera, const Eigen::Isometry3d &cMb, std::size_t i, double scale,
                      Eigen::VectorXd &r, Eigen::Index &k, double board_scale = 1.0) const
  {
    for (std::size_t j = 0; j < points[i].size(); ++j) {
      const Eigen::Vector3d P = cMb * (board_scale * points[i][j]);
      if (!(P.z() > 1e-9)) {
        r[k++] = 1e4;
        r[k++] = 1e4;
        continue;
      }
      const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(P.x() / P.z(), P.y() / P.z()));
      r[k++] = (uv.x() - pixels[i][j].x()) * scale;
      r[k++] = (uv.y() - pixels[i][j].y()) * scale;
    }
  }
};

/* Central-difference Jacobian (step h) of residual(p), `rows` values, in the parameters `columns`. */
template <class Residual>
Eigen::MatrixXd centralJacobian(const Residual &residual, const Eigen::VectorXd &p, const std::vector<int> &columns,
                                double h, Eigen::Index rows)
{
  Eigen::MatrixXd J(rows, static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) {
    Eigen::VectorXd pp = p, pm = p;
    pp[columns[c]] += h;
    pm[columns[c]] -= h;
    J.col(static_cast<Eigen::Index>(c)) = (residual(pp) - residual(pm)) / (2 * h);
  }
  return J;
}

/* A Levenberg–Marquardt step: (H + lambda diag(max(H_kk, 1e-12))) dx = -g. */
inline Eigen::VectorXd dampedStep(const Eigen::MatrixXd &H, const Eigen::VectorXd &g, double lambda)
{
  Eigen::MatrixXd A = H;
  for (Eigen::Index k = 0; k < H.rows(); ++k)
    A(k, k) += lambda * std::max(H(k, k), 1e-12);
  return A.ldlt().solve(-g);
}

} // namespace calibration_detail
} // namespace yawdepth
