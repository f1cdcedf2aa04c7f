#pragma once
/*
  refine's Ceres cost functors of the odometry increments (MotionNoise::Increment): the prior that
  ties consecutive motion-log rows. Private to yawdepth::refine (refine_ceres.cpp adds them;
  tests/test_refine_costs.cpp checks them); the residuals are the shared measurement model's
  (refine_model.h), automatic derivatives by Ceres.
*/
#include "refine_model.h"

#include <ceres/ceres.h>

namespace yawdepth {
namespace refine_detail {

/* Odometry increment prior, planar chain. Parameter blocks: frame_prev[5], frame_cur[5] = (x, y,
   z [m], heading [rad], yaw [rad], the yaw unused here). Residual[4]: (estimated - measured)
   increment, translation in the earlier vision frame over sigma_odom, heading change over
   sigma_heading (units of their sigmas). */
struct OdometryCost {
  explicit OdometryCost(const OdometryMeasurement &o) : o_(o) {}
  template <typename T> bool operator()(const T *const frame_prev, const T *const frame_cur, T *residual) const
  {
    odometryResidual(frame_prev, frame_cur, o_, residual);
    return true;
  }
  static ceres::CostFunction *Create(const OdometryMeasurement &o)
  {
    return new ceres::AutoDiffCostFunction<OdometryCost, 4, 5, 5>(new OdometryCost(o));
  }
  OdometryMeasurement o_;
};

/* Odometry increment prior, general chain. Parameter blocks: frame_prev[7], frame_cur[7] = (x, y,
   z [m], dx, dy, dz [rad], yaw [rad], the yaw unused). Residual[6]: (estimated - measured)
   increment, translation in the earlier vision frame over sigma_odom, rotation error over its
   sigma per axis (units of their sigmas). */
struct OdometryCostGeneral {
  explicit OdometryCostGeneral(const OdometryMeasurementGeneral &o) : o_(o) {}
  template <typename T> bool operator()(const T *const frame_prev, const T *const frame_cur, T *residual) const
  {
    odometryResidualGeneral(frame_prev, frame_cur, o_, residual);
    return true;
  }
  static ceres::CostFunction *Create(const OdometryMeasurementGeneral &o)
  {
    return new ceres::AutoDiffCostFunction<OdometryCostGeneral, 6, 7, 7>(new OdometryCostGeneral(o));
  }
  OdometryMeasurementGeneral o_;
};

} // namespace refine_detail
} // namespace yawdepth
