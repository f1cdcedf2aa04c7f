#pragma once
/*
  two_view_detail.h: the pieces of the two-view estimators (two_view.h) that only they and their
  tests use: the exact depth rows and the input noise. Private to yawdepth::estimation (not
  installed); tests reach it through the module's src/ directory.
*/
#include <Eigen/Core>
#include <yawdepth/core/types.h>

namespace yawdepth {

/*!
  \brief Exact depth at the current frame from the u-row, for known rotation and translation:
  \f[ Z_{cur} = \frac{t_1 r_3 - t_3 r_1}{x_{cur} r_3 - r_1} \f]
  For a pure translation (\f$ R = I,\ t = -(dX_c, dY_c, dZ_c) \f$) this is docs/method.md's
  \f$ Z_k = (x_{k-1} dZ_c - dX_c)/(x_k - x_{k-1}) \f$, the finite-increment form of eq. (5).
*/
double exactDepthURow(const Eigen::Vector2d &m_prev, const Eigen::Vector2d &m_cur, const Eigen::Matrix3d &R,
                      const Eigen::Vector3d &t);
/*! \brief Same from the v-row: \f$ Z_{cur} = (t_2 r_3 - t_3 r_2)/(y_{cur} r_3 - r_2) \f$. */
double exactDepthVRow(const Eigen::Vector2d &m_prev, const Eigen::Vector2d &m_cur, const Eigen::Matrix3d &R,
                      const Eigen::Vector3d &t);

/*! \brief Number of noisy inputs of the two-view estimators (see twoViewInputVariances()). */
constexpr int kTwoViewInputs = 12;

/*!
  \brief The diagonal input covariance used by the two-view estimators, in the order
  (u_prev, v_prev, u_cur, v_cur, d_x, d_y, d_z, rot_x, rot_y, rot_z, yaw_prev, yaw_cur) (the
  increment's perturbations of yawdepth::IncrementPerturbation; rot_y is a planar log's heading).
  \param noise The noise model. \param increments Motion-log rows between the two frames (the
  odometry's variances grow with it, unless the noise is per pose: MotionNoise::Absolute).
  \param six_dof whether the increment comes from a 6-DoF log (see incrementRotationSigma()).
  \param distance, angle the vision frame's travel (m) and rotation (rad) between the two frames,
  shared equally by the increments, for the noise model's per-metre and per-radian terms.
*/
Eigen::Matrix<double, kTwoViewInputs, 1> twoViewInputVariances(const NoiseModel &noise, int increments,
                                                              bool six_dof = false, double distance = 0.0,
                                                              double angle = 0.0);

} // namespace yawdepth
