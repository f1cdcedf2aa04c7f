#pragma once
/*
  refine's Ceres cost functors of the tracker's correlated errors (NoiseModel::pixel_correlation
  phi). Private to yawdepth::refine (refine_ceres.cpp adds them; tests/test_refine_costs.cpp and
  tests/test_refine.cpp check them). Along a track the errors are an AR(1) process per pixel axis,
  so an observation after the first of its track's chain (inliers in frame order) enters as the
  innovation
      r~ = (r_k - a r_prev) / sqrt(1 - a^2),  a = phi^gap,
  r_k and r_prev the whitened residuals of this observation and of the chain's previous one
  (refine_model.h's reprojectionResidual / anchorResidual, or their general-chain forms), gap the
  motion-log rows between them; the chain's first observation enters as r_k (observation_costs.h:
  ReprojectionCost, AnchorCost). Ceres takes a parameter block once per residual block, so the
  functors differ by the blocks the pair touches:
  - the previous observation is the anchor's (its residual depends on the point only):
    frame_a, frame_k, point;
  - neither is: frame_a, frame_p (the previous observation's frame), frame_k, point.
  The current observation is never the anchor's: refine anchors a track at its first observation
  (TrackData::anchor_row = rows.front()), which comes first in any chain it is part of.
  Residual[2]: the whitened innovation (units of sigma_px); false (no residual) when the point is
  not in front of a camera. Frame blocks as in observation_costs.h: planar (x, y, z [m], heading
  [rad], yaw [rad]), general (x, y, z [m], dx, dy, dz [rad], yaw [rad]); point (alpha, beta [-],
  rho [1/m]).
*/
#include "refine_model.h"

#include <ceres/ceres.h>
#include <cmath>

namespace yawdepth {
namespace refine_detail {

/* The AR(1) link of an observation to the previous one of its chain: a = phi^gap, scale = 1 / sqrt(1 - a^2). */
struct ChainCoefficient {
  ChainCoefficient() = default;
  explicit ChainCoefficient(double a_) : a(a_), scale(1.0 / std::sqrt(1.0 - a_ * a_)) {}
  double a = 0, scale = 1;
};

/* r~ = scale (r - a r_prev). */
template <typename T> inline void innovation(const ChainCoefficient &c, const T *r, const T *r_prev, T *out)
{
  for (int i = 0; i < 2; ++i)
    out[i] = c.scale * (r[i] - c.a * r_prev[i]);
}

/* Planar chain, the previous observation the anchor's. Blocks: frame_a[5], frame_k[5], point[3]. */
struct InnovationAfterAnchorCost {
  InnovationAfterAnchorCost(const WhitenedObservation &prev, const WhitenedObservation &cur, const double *t0,
                            const ChainCoefficient &c)
      : prev_(prev), cur_(cur), t0_{t0[0], t0[1], t0[2]}, c_(c)
  {
  }
  template <typename T>
  bool operator()(const T *const frame_a, const T *const frame_k, const T *const point, T *residual) const
  {
    T rp[2], rk[2];
    anchorResidual(point, prev_, rp);
    if (!reprojectionResidual(frame_a, frame_a + 4, frame_k, frame_k + 4, point, t0_, cur_, rk))
      return false;
    innovation(c_, rk, rp, residual);
    return true;
  }
  static ceres::CostFunction *Create(const WhitenedObservation &prev, const WhitenedObservation &cur, const double *t0,
                                     const ChainCoefficient &c)
  {
    return new ceres::AutoDiffCostFunction<InnovationAfterAnchorCost, 2, 5, 5, 3>(
        new InnovationAfterAnchorCost(prev, cur, t0, c));
  }
  WhitenedObservation prev_, cur_;
  double t0_[3];
  ChainCoefficient c_;
};

/* Planar chain, neither observation the anchor's. Blocks: frame_a[5], frame_p[5], frame_k[5], point[3]. */
struct InnovationCost {
  InnovationCost(const WhitenedObservation &prev, const WhitenedObservation &cur, const double *t0,
                 const ChainCoefficient &c)
      : prev_(prev), cur_(cur), t0_{t0[0], t0[1], t0[2]}, c_(c)
  {
  }
  template <typename T>
  bool operator()(const T *const frame_a, const T *const frame_p, const T *const frame_k, const T *const point,
                  T *residual) const
  {
    T rp[2], rk[2];
    if (!reprojectionResidual(frame_a, frame_a + 4, frame_p, frame_p + 4, point, t0_, prev_, rp) ||
        !reprojectionResidual(frame_a, frame_a + 4, frame_k, frame_k + 4, point, t0_, cur_, rk))
      return false;
    innovation(c_, rk, rp, residual);
    return true;
  }
  static ceres::CostFunction *Create(const WhitenedObservation &prev, const WhitenedObservation &cur, const double *t0,
                                     const ChainCoefficient &c)
  {
    return new ceres::AutoDiffCostFunction<InnovationCost, 2, 5, 5, 5, 3>(new InnovationCost(prev, cur, t0, c));
  }
  WhitenedObservation prev_, cur_;
  double t0_[3];
  ChainCoefficient c_;
};

/* General chain, the previous observation the anchor's. Blocks: frame_a[7], frame_k[7], point[3]. */
struct InnovationAfterAnchorCostGeneral {
  InnovationAfterAnchorCostGeneral(const WhitenedObservation &prev, const WhitenedObservation &cur,
                                   const Eigen::Matrix3d &Rref_a, const Eigen::Matrix3d &Rref_k, const Mount &mount,
                                   const ChainCoefficient &c)
      : prev_(prev), cur_(cur), Rref_a_(Rref_a), Rref_k_(Rref_k), mount_(mount), c_(c)
  {
  }
  template <typename T>
  bool operator()(const T *const frame_a, const T *const frame_k, const T *const point, T *residual) const
  {
    T rp[2], rk[2];
    anchorResidual(point, prev_, rp);
    if (!reprojectionResidualGeneral(frame_a, Rref_a_, frame_k, Rref_k_, point, mount_, cur_, rk))
      return false;
    innovation(c_, rk, rp, residual);
    return true;
  }
  static ceres::CostFunction *Create(const WhitenedObservation &prev, const WhitenedObservation &cur,
                                     const Eigen::Matrix3d &Rref_a, const Eigen::Matrix3d &Rref_k, const Mount &mount,
                                     const ChainCoefficient &c)
  {
    return new ceres::AutoDiffCostFunction<InnovationAfterAnchorCostGeneral, 2, 7, 7, 3>(
        new InnovationAfterAnchorCostGeneral(prev, cur, Rref_a, Rref_k, mount, c));
  }
  WhitenedObservation prev_, cur_;
  Eigen::Matrix3d Rref_a_, Rref_k_;
  Mount mount_;
  ChainCoefficient c_;
};

/* General chain, neither observation the anchor's. Blocks: frame_a[7], frame_p[7], frame_k[7], point[3]. */
struct InnovationCostGeneral {
  InnovationCostGeneral(const WhitenedObservation &prev, const WhitenedObservation &cur, const Eigen::Matrix3d &Rref_a,
                        const Eigen::Matrix3d &Rref_p, const Eigen::Matrix3d &Rref_k, const Mount &mount,
                        const ChainCoefficient &c)
      : prev_(prev), cur_(cur), Rref_a_(Rref_a), Rref_p_(Rref_p), Rref_k_(Rref_k), mount_(mount), c_(c)
  {
  }
  template <typename T>
  bool operator()(const T *const frame_a, const T *const frame_p, const T *const frame_k, const T *const point,
                  T *residual) const
  {
    T rp[2], rk[2];
    if (!reprojectionResidualGeneral(frame_a, Rref_a_, frame_p, Rref_p_, point, mount_, prev_, rp) ||
        !reprojectionResidualGeneral(frame_a, Rref_a_, frame_k, Rref_k_, point, mount_, cur_, rk))
      return false;
    innovation(c_, rk, rp, residual);
    return true;
  }
  static ceres::CostFunction *Create(const WhitenedObservation &prev, const WhitenedObservation &cur,
                                     const Eigen::Matrix3d &Rref_a, const Eigen::Matrix3d &Rref_p,
                                     const Eigen::Matrix3d &Rref_k, const Mount &mount, const ChainCoefficient &c)
  {
    return new ceres::AutoDiffCostFunction<InnovationCostGeneral, 2, 7, 7, 7, 3>(
        new InnovationCostGeneral(prev, cur, Rref_a, Rref_p, Rref_k, mount, c));
  }
  WhitenedObservation prev_, cur_;
  Eigen::Matrix3d Rref_a_, Rref_p_, Rref_k_;
  Mount mount_;
  ChainCoefficient c_;
};

} // namespace refine_detail
} // namespace yawdepth
