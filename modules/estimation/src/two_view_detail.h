#pragma once
/*
  two_view_detail.h: the pieces of the two-view estimators (two_view.h) that only they and their
  tests use: the exact depth rows and the input noise. Private to yawdepth::estimation (not
  installed); tests reach it through the module's src/ directory.
*/
#include <Eigen/Core>
#include <yawdepth/core/types.h>

namespace yawdepth {

/*
  The exact depth rows a Z_cur = b of one feature seen in two frames, for the relative motion
  (R, t) from the earlier camera frame to the current one, r = R (x_prev, y_prev, 1):
    u-row: a_u = x_cur r_3 - r_1,  b_u = t_1 r_3 - t_3 r_1
    v-row: a_v = y_cur r_3 - r_2,  b_v = t_2 r_3 - t_3 r_2
  For a pure translation (R = I, t = -(dX_c, dY_c, dZ_c)) b_u / a_u is docs/method.md's
  Z_k = (x_{k-1} dZ_c - dX_c)/(x_k - x_{k-1}), the finite-increment form of eq. (5). The exact
  estimator (rowCoefficients in two_view.cpp) evaluates them with forward-mode derivatives.
*/
template <typename T>
struct DepthRows {
  Eigen::Matrix<T, 3, 1> r; // the earlier bearing after the rotation
  T a_u, b_u, a_v, b_v;
};

template <typename T>
DepthRows<T> depthRows(const Eigen::Matrix<T, 2, 1> &m_prev, const Eigen::Matrix<T, 2, 1> &m_cur,
                       const Eigen::Matrix<T, 3, 3> &R, const Eigen::Matrix<T, 3, 1> &t)
{
  DepthRows<T> rows;
  rows.r = R * Eigen::Matrix<T, 3, 1>(m_prev(0), m_prev(1), T(1.0));
  const Eigen::Matrix<T, 3, 1> &r = rows.r;
  rows.a_u = m_cur(0) * r(2) - r(0);
  rows.b_u = t(0) * r(2) - t(2) * r(0);
  rows.a_v = m_cur(1) * r(2) - r(1);
  rows.b_v = t(1) * r(2) - t(2) * r(1);
  return rows;
}

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
