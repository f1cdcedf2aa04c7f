#pragma once
/*
  The measurement model of yawdepth's estimators (internal: modules/model, never installed),
  templated on the scalar type so that the same code runs with double, ceres::Jet (refine's cost
  functors, modules/refine/src/costs/: the solver's automatic derivatives) and
  Eigen::AutoDiffScalar (information.cpp: the information matrix, refine's sigma_zc and the
  Cramér–Rao bound, which must not need Ceres). yawdepth::window uses it too: window_model.h's
  analytic Jacobians are of these residuals (the general chain's), on the same whitened
  observations and odometry increments. Nothing here depends on Ceres.

  Parameter blocks and units:
  - pose[4]  = (x, y, z, heading): the vision frame in the world, wMv = [Ry(heading) | (x, y, z)]
               (m, m, m, rad);
  - yaw[1]   = camera yaw relative to the vision frame (rad); wMc = wMv [Ry(yaw) | Ry(yaw) t0],
               so the camera's world rotation is Ry(heading + yaw) and its centre
               p + Ry(heading + yaw) t0;
  - point[3] = (alpha, beta, rho): anchored inverse depth in the camera frame of the track's first
               observation, P_a = (alpha, beta, 1) / rho (-, -, 1/m).
  Residuals are whitened (dimensionless, in units of their sigma).

  The general chain (6-DoF logs, or any camera mount with a rotation, yawdepth::YawRig):
  - frame[7] = (x, y, z, dx, dy, dz, yaw): the vision frame at p = (x, y, z) with orientation
               Rref Exp(d), Rref the row's measured orientation (a constant of the model) and
               d = (dx, dy, dz) a rotation vector (rad); yaw as above. The camera's world rotation
               is Rref Exp(d) Ry(yaw) R0 and its centre p + Rref Exp(d) Ry(yaw) t0, with the
               mount (R0, t0) = vMc at yaw 0. For a planar log only dy (the heading) is free.
*/
#include <Eigen/Core>
#include <cmath>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {
namespace refine_detail {

/* out = Ry(a) v, with c = cos a, s = sin a. */
template <typename T> inline void rotateY(const T &c, const T &s, const T *v, T *out)
{
  out[0] = c * v[0] + s * v[2];
  out[1] = v[1];
  out[2] = c * v[2] - s * v[0];
}

/* out = Ry(a)^T v, with c = cos a, s = sin a. */
template <typename T> inline void rotateYT(const T &c, const T &s, const T *v, T *out)
{
  out[0] = c * v[0] - s * v[2];
  out[1] = v[1];
  out[2] = c * v[2] + s * v[0];
}

/*
  rho times the point in the camera frame of frame k, for a point anchored in frame a:
  \f[ q = R_k^T \left[ R_a \big((\alpha, \beta, 1) + \rho t_0\big) + \rho (p_a - p_k) \right] - \rho t_0,
      \quad R = R_y(\text{heading} + \text{yaw}) \f]
  (division-free, so a point at infinity, rho = 0, is regular). The projection is q_xy / q_z and
  the camera-frame point q / rho. With k = a it returns (alpha, beta, 1).
*/
template <typename T>
void anchoredPoint(const T *pose_a, const T *yaw_a, const T *pose_k, const T *yaw_k, const T *point,
                   const double *t0, T *q)
{
  using std::cos;
  using std::sin;
  const T phi_a = pose_a[3] + yaw_a[0];
  const T phi_k = pose_k[3] + yaw_k[0];
  const T ca = cos(phi_a), sa = sin(phi_a), ck = cos(phi_k), sk = sin(phi_k);
  const T rho = point[2];
  const T v[3] = {point[0] + rho * t0[0], point[1] + rho * t0[1], T(1) + rho * t0[2]};
  T w[3];
  rotateY(ca, sa, v, w);
  for (int i = 0; i < 3; ++i)
    w[i] += rho * (pose_a[i] - pose_k[i]);
  rotateYT(ck, sk, w, q);
  for (int i = 0; i < 3; ++i)
    q[i] -= rho * t0[i];
}

/*
  An observation prepared for the model: the undistorted normalised point m and the upper
  triangular square root S of its information, S^T S = (J diag(sigma_px^2) J^T)^-1 with
  J = d(x, y)/d(u, v) the undistortion Jacobian, so S (m_proj - m) is in units of sigma_px.
*/
struct WhitenedObservation {
  double m[2] = {0, 0};
  double s00 = 1, s01 = 0, s11 = 1;
};

template <typename T> inline void whiten(const WhitenedObservation &o, const T &ex, const T &ey, T *r)
{
  r[0] = o.s00 * ex + o.s01 * ey;
  r[1] = o.s11 * ey;
}

/*
  Reprojection residual of an observation in frame k of a point anchored in frame a != k.
  Returns false when the point is not in front of the camera (q_z <= 0).
*/
template <typename T>
bool reprojectionResidual(const T *pose_a, const T *yaw_a, const T *pose_k, const T *yaw_k, const T *point,
                          const double *t0, const WhitenedObservation &o, T *r)
{
  T q[3];
  anchoredPoint(pose_a, yaw_a, pose_k, yaw_k, point, t0, q);
  if (!(q[2] > T(0))) {
    r[0] = T(0);
    r[1] = T(0);
    return false;
  }
  const T ex = q[0] / q[2] - o.m[0];
  const T ey = q[1] / q[2] - o.m[1];
  whiten(o, ex, ey, r);
  return true;
}

/* Residual of the observation in the anchor frame itself: (alpha, beta) against m. */
template <typename T> void anchorResidual(const T *point, const WhitenedObservation &o, T *r)
{
  whiten(o, T(point[0] - o.m[0]), T(point[1] - o.m[1]), r);
}

/*
  A measured odometry increment between consecutive motion-log rows: d = Ry(h_prev)^T (p_cur -
  p_prev) (m, in the earlier vision frame) and dh = h_cur - h_prev (rad), with the inverse sigmas.
*/
struct OdometryMeasurement {
  double d[3] = {0, 0, 0};
  double dh = 0;
  double inv_sigma_t = 1, inv_sigma_h = 1;
};

/* Residual[4]: (estimated - measured) increment, whitened. */
template <typename T>
void odometryResidual(const T *pose_prev, const T *pose_cur, const OdometryMeasurement &o, T *r)
{
  using std::cos;
  using std::sin;
  const T c = cos(pose_prev[3]), s = sin(pose_prev[3]);
  const T dp[3] = {pose_cur[0] - pose_prev[0], pose_cur[1] - pose_prev[1], pose_cur[2] - pose_prev[2]};
  T d[3];
  rotateYT(c, s, dp, d);
  for (int i = 0; i < 3; ++i)
    r[i] = (d[i] - o.d[i]) * o.inv_sigma_t;
  r[3] = (pose_cur[3] - pose_prev[3] - o.dh) * o.inv_sigma_h;
}

/* Residual[1]: (estimated - measured) yaw, whitened. */
template <typename T> void yawResidual(const T *yaw, double measured, double inv_sigma, T *r)
{
  r[0] = (yaw[0] - measured) * inv_sigma;
}

// ---------------------------------------------------------------------------------------------
// The general chain.

/* The camera mount (R0, t0) and a row's reference orientation, as the general model needs them. */
struct Mount {
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t0 = Eigen::Vector3d::Zero();
};

/* The yawed vision frame's orientation Rref Exp(d) Ry(yaw) of a general frame block. */
template <typename T> Eigen::Matrix<T, 3, 3> yawedRotation(const Eigen::Matrix3d &Rref, const T *frame)
{
  return Rref.cast<T>() * expSO3<T>(Eigen::Matrix<T, 3, 1>(frame[3], frame[4], frame[5])) * rotY<T>(frame[6]);
}

/*
  rho times the point in the camera frame of frame k, for a point anchored in frame a (general chain):
  \f[ q = R_0^T \left( V_k^T \left[ V_a (R_0 (\alpha, \beta, 1) + \rho t_0) + \rho (p_a - p_k) \right] - \rho t_0 \right),
      \quad V = R_{ref} \exp(d) R_y(\text{yaw}) \f]
*/
template <typename T>
void anchoredPointGeneral(const T *frame_a, const Eigen::Matrix3d &Rref_a, const T *frame_k, const Eigen::Matrix3d &Rref_k,
                          const T *point, const Mount &mount, T *q)
{
  using V3 = Eigen::Matrix<T, 3, 1>;
  const Eigen::Matrix<T, 3, 3> Va = yawedRotation(Rref_a, frame_a), Vk = yawedRotation(Rref_k, frame_k);
  const T rho = point[2];
  const V3 t0 = mount.t0.cast<T>();
  const V3 a = mount.R0.cast<T>() * V3(point[0], point[1], T(1)) + rho * t0;
  const V3 w = Va * a + rho * V3(frame_a[0] - frame_k[0], frame_a[1] - frame_k[1], frame_a[2] - frame_k[2]);
  const V3 out = mount.R0.transpose().cast<T>() * (Vk.transpose() * w - rho * t0);
  q[0] = out(0);
  q[1] = out(1);
  q[2] = out(2);
}

/* Reprojection residual (general chain); false when the point is not in front of the camera. */
template <typename T>
bool reprojectionResidualGeneral(const T *frame_a, const Eigen::Matrix3d &Rref_a, const T *frame_k,
                                 const Eigen::Matrix3d &Rref_k, const T *point, const Mount &mount,
                                 const WhitenedObservation &o, T *r)
{
  T q[3];
  anchoredPointGeneral(frame_a, Rref_a, frame_k, Rref_k, point, mount, q);
  if (!(q[2] > T(0))) {
    r[0] = T(0);
    r[1] = T(0);
    return false;
  }
  whiten(o, T(q[0] / q[2] - o.m[0]), T(q[1] / q[2] - o.m[1]), r);
  return true;
}

/*
  A measured increment of the general chain: d = Rp^T (p_cur - p_prev) (m, in the earlier vision
  frame) and dR = Rp^T Rc, with the rows' reference orientations and the inverse sigmas per axis.
*/
struct OdometryMeasurementGeneral {
  double d[3] = {0, 0, 0};
  Eigen::Matrix3d dR = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d Rref_prev = Eigen::Matrix3d::Identity(), Rref_cur = Eigen::Matrix3d::Identity();
  double inv_sigma_t = 1;
  double inv_sigma_r[3] = {1, 1, 1};
};

/*
  Residual[6]: (estimated - measured) increment, whitened: the translation in the earlier vision
  frame, and the rotation error E = dR^T Rp^T Rc as vee((E - E^T) / 2) (its rotation vector to
  third order: the error is at noise level).
*/
template <typename T>
void odometryResidualGeneral(const T *frame_prev, const T *frame_cur, const OdometryMeasurementGeneral &o, T *r)
{
  using V3 = Eigen::Matrix<T, 3, 1>;
  const Eigen::Matrix<T, 3, 3> Rp = o.Rref_prev.cast<T>() * expSO3<T>(V3(frame_prev[3], frame_prev[4], frame_prev[5]));
  const Eigen::Matrix<T, 3, 3> Rc = o.Rref_cur.cast<T>() * expSO3<T>(V3(frame_cur[3], frame_cur[4], frame_cur[5]));
  const V3 d = Rp.transpose() * V3(frame_cur[0] - frame_prev[0], frame_cur[1] - frame_prev[1], frame_cur[2] - frame_prev[2]);
  for (int i = 0; i < 3; ++i)
    r[i] = (d(i) - o.d[i]) * o.inv_sigma_t;
  const Eigen::Matrix<T, 3, 3> E = o.dR.transpose().cast<T>() * Rp.transpose() * Rc;
  r[3] = T(0.5) * (E(2, 1) - E(1, 2)) * o.inv_sigma_r[0];
  r[4] = T(0.5) * (E(0, 2) - E(2, 0)) * o.inv_sigma_r[1];
  r[5] = T(0.5) * (E(1, 0) - E(0, 1)) * o.inv_sigma_r[2];
}

/*
  A measured pose, for per-pose motion noise (MotionNoise::Absolute): the prior on one row's pose
  block. Planar chain: value = (x, y, z, heading) of the row; general chain: value = (x, y, z, 0,
  0, 0), the rotation being the block's offset d from the row's reference (measured) orientation.
*/
struct PosePrior {
  double value[6] = {0, 0, 0, 0, 0, 0};
  double inv_sigma[6] = {1, 1, 1, 1, 1, 1};
};

/* Residual[PD]: (estimated - measured) pose, whitened (PD = 4 planar, 6 general). */
template <int PD, typename T> void posePriorResidual(const T *pose, const PosePrior &o, T *r)
{
  for (int i = 0; i < PD; ++i)
    r[i] = (pose[i] - o.value[i]) * o.inv_sigma[i];
}

} // namespace refine_detail
} // namespace yawdepth
