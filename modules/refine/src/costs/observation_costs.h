#pragma once
/*
  refine's Ceres cost functors of one observation, with independent pixel errors (the chain's
  first observation when the errors are correlated: innovation_costs.h has the others). Private to
  yawdepth::refine (refine_ceres.cpp adds them; tests/test_refine_costs.cpp checks them); the
  residuals themselves are the shared measurement model's (refine_model.h), automatic derivatives
  by Ceres.

  Frame blocks: planar (x, y, z [m], heading [rad], yaw [rad]), general (x, y, z [m], dx, dy,
  dz [rad], yaw [rad]) about the row's reference orientation; point (alpha, beta [-], rho [1/m])
  anchored in the camera frame of the track's first observation. Residuals are whitened
  normalised reprojection errors (units of sigma_px).
*/
#include "refine_model.h"

#include <Eigen/Core>
#include <ceres/ceres.h>

namespace yawdepth {
namespace refine_detail {

/* Reprojection of a point anchored in another frame, planar chain.
   Parameter blocks: frame_a[5] of the anchor frame (the track's first observation), frame_k[5] of
   the observing frame, point[3]. Stored: the observation and the mount's offset t0 (m).
   Residual[2]: whitened normalised reprojection error (units of sigma_px); false (no residual)
   when the point is not in front of the camera. */
struct ReprojectionCost {
  ReprojectionCost(const WhitenedObservation &w, const double *t0) : w_(w), t0_{t0[0], t0[1], t0[2]} {}
  template <typename T>
  bool operator()(const T *const frame_a, const T *const frame_k, const T *const point, T *residual) const
  {
    return reprojectionResidual(frame_a, frame_a + 4, frame_k, frame_k + 4, point, t0_, w_, residual);
  }
  static ceres::CostFunction *Create(const WhitenedObservation &w, const double *t0)
  {
    return new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 5, 5, 3>(new ReprojectionCost(w, t0));
  }
  WhitenedObservation w_;
  double t0_[3];
};

/* The observation in the anchor frame itself (either chain). Parameter block: point[3].
   Residual[2]: whitened (alpha, beta) - m (units of sigma_px). */
struct AnchorCost {
  explicit AnchorCost(const WhitenedObservation &w) : w_(w) {}
  template <typename T> bool operator()(const T *const point, T *residual) const
  {
    anchorResidual(point, w_, residual);
    return true;
  }
  static ceres::CostFunction *Create(const WhitenedObservation &w)
  {
    return new ceres::AutoDiffCostFunction<AnchorCost, 2, 3>(new AnchorCost(w));
  }
  WhitenedObservation w_;
};

/* Reprojection of an anchored point, general chain.
   Parameter blocks: frame_a[7] of the anchor frame, the vision frame's orientation being
   Rref_a Exp(d); frame_k[7] the same for the observing frame; point[3]. Stored by value: the two
   rows' reference orientations and the camera mount. Residual[2]: whitened normalised
   reprojection error (units of sigma_px); false when the point is not in front of the camera. */
struct ReprojectionCostGeneral {
  ReprojectionCostGeneral(const WhitenedObservation &w, const Eigen::Matrix3d &Rref_a, const Eigen::Matrix3d &Rref_k,
                          const Mount &mount)
      : w_(w), Rref_a_(Rref_a), Rref_k_(Rref_k), mount_(mount)
  {
  }
  template <typename T>
  bool operator()(const T *const frame_a, const T *const frame_k, const T *const point, T *residual) const
  {
    return reprojectionResidualGeneral(frame_a, Rref_a_, frame_k, Rref_k_, point, mount_, w_, residual);
  }
  static ceres::CostFunction *Create(const WhitenedObservation &w, const Eigen::Matrix3d &Rref_a,
                                     const Eigen::Matrix3d &Rref_k, const Mount &mount)
  {
    return new ceres::AutoDiffCostFunction<ReprojectionCostGeneral, 2, 7, 7, 3>(
        new ReprojectionCostGeneral(w, Rref_a, Rref_k, mount));
  }
  WhitenedObservation w_;
  Eigen::Matrix3d Rref_a_, Rref_k_;
  Mount mount_;
};

} // namespace refine_detail
} // namespace yawdepth
