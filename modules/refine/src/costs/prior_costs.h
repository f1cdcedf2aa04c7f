#pragma once
/*
  refine's Ceres cost functors of the priors on one row: the yaw reading, and the measured pose
  under per-pose motion noise (MotionNoise::Absolute). Private to yawdepth::refine
  (refine_ceres.cpp adds them; tests/test_refine_costs.cpp checks them); the residuals are the
  shared measurement model's (refine_model.h), automatic derivatives by Ceres.
*/
#include "refine_model.h"

#include <ceres/ceres.h>

namespace yawdepth {
namespace refine_detail {

/* Yaw reading prior. Parameter block: frame[N] = (pose..., yaw) (N = 5 planar, 7 general), only
   the yaw [rad], the last value, used. Residual[1]: (yaw - reading) / sigma_yaw. */
template <int N> struct YawCost {
  YawCost(double measured, double inv_sigma) : measured_(measured), inv_sigma_(inv_sigma) {}
  template <typename T> bool operator()(const T *const frame, T *residual) const
  {
    yawResidual(frame + N - 1, measured_, inv_sigma_, residual);
    return true;
  }
  static ceres::CostFunction *Create(double measured, double inv_sigma)
  {
    return new ceres::AutoDiffCostFunction<YawCost, 1, N>(new YawCost(measured, inv_sigma));
  }
  double measured_, inv_sigma_;
};

/* Per-pose prior (MotionNoise::Absolute). Parameter block: frame[B] (B = 5 planar, 7 general; the
   yaw, last, unused). Residual[PD]: (estimated - measured) pose over its sigma, PD = 4 planar (x,
   y, z [m], heading [rad]), 6 general (x, y, z [m], rotation offset d [rad]). */
template <int PD, int B> struct PosePriorCost {
  explicit PosePriorCost(const PosePrior &o) : o_(o) {}
  template <typename T> bool operator()(const T *const frame, T *residual) const
  {
    posePriorResidual<PD>(frame, o_, residual);
    return true;
  }
  static ceres::CostFunction *Create(const PosePrior &o)
  {
    return new ceres::AutoDiffCostFunction<PosePriorCost, PD, B>(new PosePriorCost(o));
  }
  PosePrior o_;
};

} // namespace refine_detail
} // namespace yawdepth
