#pragma once
/*
  The measurement model of the sliding-window estimator (yawdepth::window's WindowEstimator; internal:
  modules/model, never installed): refine_model.h's general-chain residuals with analytic Jacobians
  (the estimator runs every frame, so no automatic differentiation here; tests/test_window.cpp checks
  every Jacobian against finite differences and the residuals against refine_model.h's).

  Parameter blocks and units:
  - frame x[7] = (x, y, z, dx, dy, dz, yaw): the vision frame at p = (x, y, z) (m) with orientation
    Rv = Rref Exp(d) (d a rotation vector, rad, about the row's measured orientation Rref, a constant)
    and the camera yaw (rad). The camera: R = Rv Ry(yaw) R0, c = p + Rv Ry(yaw) t0 (mount (R0, t0)).
  - point p[3] = (alpha, beta, rho): inverse depth anchored in a fixed world frame (Ra, ca) (constants):
    P = ca + Ra (alpha, beta, 1) / rho (-, -, 1/m).
  Residuals are whitened (units of their sigma).
*/
#include "refine_model.h"

#include <Eigen/Core>
#include <cmath>

namespace yawdepth {
namespace window_detail {

using refine_detail::Mount;
using refine_detail::OdometryMeasurementGeneral;
using refine_detail::WhitenedObservation;

constexpr int kFrameDim = 7;


/* Right Jacobian of SO(3): Exp(w + e) = Exp(w) Exp(Jr(w) e) to first order in e. */
inline Eigen::Matrix3d rightJacobianSO3(const Eigen::Vector3d &w)
{
  const double t2 = w.squaredNorm();
  const Eigen::Matrix3d W = skew(w);
  if (t2 < 1e-10)
    return Eigen::Matrix3d::Identity() - 0.5 * W + W * W / 6.0;
  const double t = std::sqrt(t2);
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(t)) / t2 * W + (t - std::sin(t)) / (t2 * t) * W * W;
}

/* A frame's camera and vision-frame rotation with their derivatives by the 7 frame parameters. */
struct CameraPose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity(); // camera rotation in the world
  Eigen::Vector3d c = Eigen::Vector3d::Zero();     // camera centre in the world
  Eigen::Matrix3d dR[kFrameDim];                   // dR / dx_j
  Eigen::Vector3d dc[kFrameDim];                   // dc / dx_j
  Eigen::Matrix3d Rv = Eigen::Matrix3d::Identity(); // vision frame rotation Rref Exp(d)
  Eigen::Matrix3d dRv[3];                          // dRv / dd_j
  // For the observations' Jacobians: dR_j = R [w_j]x (a rotation's derivative, in the camera frame),
  // so d(R' u)/dx_j = (R' u) x w_j - rho R' dc_j.
  Eigen::Vector3d w[kFrameDim];                    // vee(R' dR_j)
  Eigen::Vector3d Rt_dc[kFrameDim];                // R' dc_j
};

/* The camera of frame x (see the file comment) and its derivatives. */
inline void cameraPose(const double *x, const Eigen::Matrix3d &Rref, const Mount &mount, CameraPose &out)
{
  const Eigen::Vector3d d(x[3], x[4], x[5]);
  out.Rv = Rref * expSO3<double>(d);
  const Eigen::Matrix3d Jr = rightJacobianSO3(d);
  const double cy = std::cos(x[6]), sy = std::sin(x[6]);
  Eigen::Matrix3d Ry, dRy;
  Ry << cy, 0, sy, 0, 1, 0, -sy, 0, cy;
  dRy << -sy, 0, cy, 0, 0, 0, -cy, 0, -sy;
  const Eigen::Matrix3d VRy = out.Rv * Ry;
  out.R = VRy * mount.R0;
  out.c = Eigen::Vector3d(x[0], x[1], x[2]) + VRy * mount.t0;
  for (int j = 0; j < 3; ++j) {
    out.dR[j].setZero();
    out.dc[j] = Eigen::Vector3d::Unit(j);
    out.dRv[j] = out.Rv * skew(Jr.col(j));
    const Eigen::Matrix3d dV = out.dRv[j] * Ry;
    out.dR[3 + j] = dV * mount.R0;
    out.dc[3 + j] = dV * mount.t0;
  }
  const Eigen::Matrix3d dV = out.Rv * dRy;
  out.dR[6] = dV * mount.R0;
  out.dc[6] = dV * mount.t0;
  for (int j = 0; j < kFrameDim; ++j) {
    const Eigen::Matrix3d W = out.R.transpose() * out.dR[j];
    out.w[j] = Eigen::Vector3d(0.5 * (W(2, 1) - W(1, 2)), 0.5 * (W(0, 2) - W(2, 0)), 0.5 * (W(1, 0) - W(0, 1)));
    out.Rt_dc[j] = out.R.transpose() * out.dc[j];
  }
}

/*
  Whitened reprojection residual of an observation in the camera `f` of a point p anchored in
  (Ra, ca), and if J is given its Jacobian (2 x 10: the frame's 7 parameters, then alpha, beta,
  rho). Returns false (r = 0) when the point is not in front of the camera.
  \f[ q = R^T \left( R_a (\alpha, \beta, 1)^T + \rho (c_a - c) \right), \quad
      r = S \left( q_{xy} / q_z - m \right) \f]
*/
inline bool observationResidual(const Eigen::Matrix3d &Ra, const Eigen::Vector3d &ca, const double *p,
                                const CameraPose &f, const WhitenedObservation &w, Eigen::Vector2d &r,
                                Eigen::Matrix<double, 2, 10> *J)
{
  const Eigen::Vector3d m(p[0], p[1], 1.0);
  const double rho = p[2];
  const Eigen::Vector3d dca = ca - f.c;
  const Eigen::Vector3d u = Ra * m + rho * dca;
  const Eigen::Vector3d q = f.R.transpose() * u;
  if (!(q.z() > 1e-12 * u.norm()) || !q.allFinite()) {
    r.setZero();
    if (J)
      J->setZero();
    return false;
  }
  const double iz = 1.0 / q.z();
  const double ex = q.x() * iz - w.m[0], ey = q.y() * iz - w.m[1];
  r << w.s00 * ex + w.s01 * ey, w.s11 * ey;
  if (J) {
    Eigen::Matrix<double, 2, 3> P; // d(whitened residual) / dq
    P << iz, 0, -q.x() * iz * iz, 0, iz, -q.y() * iz * iz;
    Eigen::Matrix2d S;
    S << w.s00, w.s01, 0, w.s11;
    const Eigen::Matrix<double, 2, 3> SP = S * P;
    for (int j = 0; j < kFrameDim; ++j)
      J->col(j) = SP * (q.cross(f.w[j]) - rho * f.Rt_dc[j]);
    J->col(7) = SP * (f.R.transpose() * Ra.col(0));
    J->col(8) = SP * (f.R.transpose() * Ra.col(1));
    J->col(9) = SP * (f.R.transpose() * dca);
  }
  return true;
}

/*
  The increment residual of refine_detail::odometryResidualGeneral between frames xp and xn (whose
  vision rotations and derivatives are in cp, cn), and its Jacobian (6 x 14: xp's 7, then xn's 7).
*/
inline void odometryResidual(const double *xp, const CameraPose &cp, const double *xn, const CameraPose &cn,
                             const OdometryMeasurementGeneral &o, Eigen::Matrix<double, 6, 1> &r,
                             Eigen::Matrix<double, 6, 14> *J)
{
  const Eigen::Vector3d dp(xn[0] - xp[0], xn[1] - xp[1], xn[2] - xp[2]);
  const Eigen::Vector3d t = cp.Rv.transpose() * dp;
  const Eigen::Matrix3d A = o.dR.transpose();
  const Eigen::Matrix3d E = A * cp.Rv.transpose() * cn.Rv;
  auto veeSkew = [](const Eigen::Matrix3d &M) {
    return Eigen::Vector3d(0.5 * (M(2, 1) - M(1, 2)), 0.5 * (M(0, 2) - M(2, 0)), 0.5 * (M(1, 0) - M(0, 1)));
  };
  const Eigen::Vector3d e = veeSkew(E);
  const Eigen::Vector3d ist(o.inv_sigma_t, o.inv_sigma_t, o.inv_sigma_t);
  const Eigen::Vector3d isr(o.inv_sigma_r[0], o.inv_sigma_r[1], o.inv_sigma_r[2]);
  for (int i = 0; i < 3; ++i) {
    r(i) = (t(i) - o.d[i]) * ist(i);
    r(3 + i) = e(i) * isr(i);
  }
  if (!J)
    return;
  J->setZero();
  const Eigen::Matrix3d RpT = cp.Rv.transpose();
  for (int j = 0; j < 3; ++j) {
    J->block<3, 1>(0, j) = -RpT.col(j).cwiseProduct(ist);
    J->block<3, 1>(0, 7 + j) = RpT.col(j).cwiseProduct(ist);
    J->block<3, 1>(0, 3 + j) = (cp.dRv[j].transpose() * dp).cwiseProduct(ist);
    J->block<3, 1>(3, 3 + j) = veeSkew(A * cp.dRv[j].transpose() * cn.Rv).cwiseProduct(isr);
    J->block<3, 1>(3, 10 + j) = veeSkew(A * RpT * cn.dRv[j]).cwiseProduct(isr);
  }
}

} // namespace window_detail
} // namespace yawdepth
