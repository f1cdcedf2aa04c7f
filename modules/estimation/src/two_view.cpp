#include <yawdepth/estimation/two_view.h>

#include "two_view_detail.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/AutoDiff>
#include <visp3/visual_features/vpFeaturePoint.h>

namespace yawdepth {

namespace {

constexpr int kInputs = kTwoViewInputs; // u_prev, v_prev, u_cur, v_cur, d(3), rotation(3), yaw_prev, yaw_cur
using VecIn = Eigen::Matrix<double, kInputs, 1>;
using AD = Eigen::AutoDiffScalar<VecIn>;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::Vector3d homog(const Eigen::Vector2d &m) { return Eigen::Vector3d(m.x(), m.y(), 1.0); }

/* Undistorted observations of one feature in two frames, with d(normalised)/d(pixel). */
struct Undistorted {
  Eigen::Vector2d m_prev, m_cur;
  Eigen::Matrix2d J_prev, J_cur;
};

bool undistortBoth(const CameraModel &camera, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv_cur,
                   Undistorted &out)
{
  return camera.undistort(uv_prev, out.m_prev, &out.J_prev) && camera.undistort(uv_cur, out.m_cur, &out.J_cur);
}

PointEstimate failed(Status s, long frame, double parallax = kNaN)
{
  PointEstimate e;
  e.status = s;
  e.frame = frame;
  e.parallax_px = parallax;
  return e;
}

/* Parallax in pixels in the current image: distance between the observed point and the image of
   the earlier bearing after the known rotation (the image of the point at infinity). */
double parallaxPx(const CameraModel &camera, const Eigen::Vector3d &r, const Eigen::Vector2d &m_cur)
{
  if (!(r.z() > 1e-12))
    return std::numeric_limits<double>::infinity();
  return std::hypot(camera.kx() * (m_cur.x() - r.x() / r.z()), camera.ky() * (m_cur.y() - r.y() / r.z()));
}

// The vision frame's travel (m) and rotation (rad) between two motion-log rows.
double travel(const MotionSample &prev, const MotionSample &cur) { return (cur.position() - prev.position()).norm(); }

double turn(const MotionSample &prev, const MotionSample &cur)
{
  return Eigen::AngleAxisd(prev.rotation().transpose() * cur.rotation()).angle();
}

} // namespace

Eigen::Matrix<double, kTwoViewInputs, 1> twoViewInputVariances(const NoiseModel &noise, int increments, bool six_dof,
                                                              double distance, double angle)
{
  // Per-pose noise: the two rows' errors, however many rows lie between them.
  const double n = noise.motion_noise == MotionNoise::Absolute ? 1 : std::max(1, increments);
  VecIn var;
  const double px2 = noise.sigma_px * noise.sigma_px;
  // n increments of equal length: n (sigma^2 + (k d / n)^2) = n sigma^2 + (k d)^2 / n.
  const double st = incrementTranslationSigma(noise, distance / n);
  const double od2 = n * st * st;
  const Eigen::Vector3d rot2 = n * incrementRotationSigma(noise, six_dof, distance / n, angle / n).cwiseAbs2();
  var << px2, px2, px2, px2, od2, od2, od2, rot2, noise.sigma_yaw * noise.sigma_yaw, noise.sigma_yaw * noise.sigma_yaw;
  return var;
}

double paperDepth(double x, double y, double du, double kx, const Eigen::Vector3d &c_d, const Eigen::Vector3d &c_omega)
{
  // The interaction matrix of the point at Z = 1: its translational part scales with 1/Z,
  // its rotational part does not depend on Z (eq. (2)).
  vpFeaturePoint s;
  s.buildFrom(x, y, 1.0);
  const vpMatrix L = s.interaction(vpFeaturePoint::selectX());
  double Lv_d = 0, Lw_w = 0;
  for (unsigned j = 0; j < 3; ++j) {
    Lv_d += L[0][j] * c_d(j);
    Lw_w += L[0][3 + j] * c_omega(j);
  }
  return kx * Lv_d / (du - kx * Lw_w);
}

namespace {

/* The exact rows a Z = b (u-row, v-row) as forward-mode scalars: values and derivatives with
   respect to every noisy input. Also the current normalised point (with its derivatives), the
   translation and the earlier bearing after the rotation (values). */
struct RowCoefficients {
  Eigen::Matrix<AD, 2, 1> m_cur;
  AD a_u, b_u, a_v, b_v;
  Eigen::Vector3d t_val, r_val;
};

/* One forward-mode pass gives the row coefficients a, b and their derivatives with respect to
   every noisy input (perturbations around the observed values, all zero here). */
RowCoefficients rowCoefficients(const YawRig &rig, const MotionSample &prev, const MotionSample &cur,
                                const Undistorted &und)
{
  IncrementPerturbation<AD> p;
  Eigen::Matrix<AD, 2, 1> duv_prev, duv_cur;
  for (int i = 0; i < 2; ++i) {
    duv_prev(i) = AD(0.0, kInputs, i);
    duv_cur(i) = AD(0.0, kInputs, 2 + i);
  }
  for (int i = 0; i < 3; ++i) {
    p.d_translation(i) = AD(0.0, kInputs, 4 + i);
    p.d_rotation(i) = AD(0.0, kInputs, 7 + i);
  }
  p.d_yaw_prev = AD(0.0, kInputs, 10);
  p.d_yaw_cur = AD(0.0, kInputs, 11);

  const Eigen::Matrix<AD, 2, 1> m_prev = und.m_prev.cast<AD>() + und.J_prev.cast<AD>() * duv_prev;
  const Eigen::Matrix<AD, 2, 1> m_cur = und.m_cur.cast<AD>() + und.J_cur.cast<AD>() * duv_cur;
  Eigen::Matrix<AD, 3, 3> R;
  Eigen::Matrix<AD, 3, 1> t;
  relativeMotion<AD>(rig, prev, cur, p, R, t);
  const DepthRows<AD> rows = depthRows<AD>(m_prev, m_cur, R, t);

  Eigen::Vector3d t_val, r_val;
  for (int i = 0; i < 3; ++i) {
    t_val(i) = t(i).value();
    r_val(i) = rows.r(i).value();
  }
  return RowCoefficients{m_cur, rows.a_u, rows.b_u, rows.a_v, rows.b_v, t_val, r_val};
}

/* The rows' values a, b and their Jacobians Da, Db with respect to the inputs. */
struct LinearizedRows {
  Eigen::Vector2d a, b;
  Eigen::Matrix<double, 2, kInputs> Da, Db;
};

LinearizedRows linearizeRows(const RowCoefficients &c)
{
  LinearizedRows l;
  l.a = Eigen::Vector2d(c.a_u.value(), c.a_v.value());
  l.b = Eigen::Vector2d(c.b_u.value(), c.b_v.value());
  l.Da.row(0) = c.a_u.derivatives().transpose();
  l.Da.row(1) = c.a_v.derivatives().transpose();
  l.Db.row(0) = c.b_u.derivatives().transpose();
  l.Db.row(1) = c.b_v.derivatives().transpose();
  return l;
}

/* Depth at the current frame from the two rows: pixel-scaled least squares, then generalised least
   squares with the residual covariance Sigma_e = (Z Da - Db) Sigma (Z Da - Db)^T evaluated at the
   current estimate. W: the last weights. */
double generalisedLeastSquaresDepth(const CameraModel &camera, const LinearizedRows &l, const VecIn &var,
                                    Eigen::Matrix2d &W)
{
  const Eigen::Vector2d &a = l.a, &b = l.b;
  W = Eigen::Vector2d(camera.kx() * camera.kx(), camera.ky() * camera.ky()).asDiagonal();
  double Z = a.dot(W * b) / a.dot(W * a);
  for (int iter = 0; iter < 2 && std::isfinite(Z); ++iter) {
    const Eigen::Matrix<double, 2, kInputs> Je = Z * l.Da - l.Db;
    const Eigen::Matrix2d Se = Je * var.asDiagonal() * Je.transpose();
    const double det = Se.determinant();
    if (!(det > 1e-30 * Se.trace() * Se.trace()) || !std::isfinite(det))
      break; // no noise information (e.g. all sigmas zero): keep the current weights
    W = Se.inverse();
    Z = a.dot(W * b) / a.dot(W * a);
  }
  return Z;
}

/* Covariance of the camera point Z (x_cur, y_cur, 1), with the weights W held fixed. */
Eigen::Matrix3d exactPointCovariance(const LinearizedRows &l, const Eigen::Matrix2d &W, double Z,
                                     const Undistorted &und, const Eigen::Matrix<AD, 2, 1> &m_cur, const VecIn &var)
{
  const Eigen::Vector2d &a = l.a, &b = l.b;
  // dZ with the weights held fixed: [a^T W (Db - Z Da) + (b - Z a)^T W Da] / (a^T W a).
  const double aWa = a.dot(W * a);
  const Eigen::Matrix<double, 1, kInputs> dZ =
      ((W * a).transpose() * (l.Db - Z * l.Da) + (W * (b - Z * a)).transpose() * l.Da) / aWa;
  Eigen::Matrix<double, 3, kInputs> J;
  J.row(0) = und.m_cur.x() * dZ;
  J.row(1) = und.m_cur.y() * dZ;
  J.row(2) = dZ;
  J.row(0) += Z * m_cur(0).derivatives().transpose();
  J.row(1) += Z * m_cur(1).derivatives().transpose();
  return J * var.asDiagonal() * J.transpose();
}

} // namespace

PointEstimate estimateExact(const CameraModel &camera, const YawRig &rig, const MotionSample &prev,
                            const MotionSample &cur, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv_cur,
                            const TwoViewOptions &options)
{
  Undistorted und;
  if (!undistortBoth(camera, uv_prev, uv_cur, und))
    return failed(Status::UndistortFailed, cur.frame);
  const RowCoefficients rows = rowCoefficients(rig, prev, cur, und);
  const Eigen::Vector3d &t_val = rows.t_val, &r_val = rows.r_val;

  // Gates on the geometry itself.
  if (!(t_val.norm() >= options.gates.min_baseline))
    return failed(Status::NoMotion, cur.frame);
  const double parallax = parallaxPx(camera, r_val, und.m_cur);
  if (!(parallax >= options.gates.min_parallax_px))
    return failed(Status::Degenerate, cur.frame, parallax);

  const LinearizedRows l = linearizeRows(rows);
  const bool six_dof = prev.six_dof || cur.six_dof;
  const VecIn var = twoViewInputVariances(options.noise, options.increments, six_dof, travel(prev, cur), turn(prev, cur));
  Eigen::Matrix2d W;
  const double Z = generalisedLeastSquaresDepth(camera, l, var, W);
  if (!std::isfinite(Z))
    return failed(Status::Degenerate, cur.frame, parallax);

  const Eigen::Vector3d m1h = homog(und.m_cur);
  const double Z_prev = r_val.dot(Z * m1h - t_val) / r_val.squaredNorm();
  if (!(Z > 0) || !(Z_prev > 0))
    return failed(Status::Behind, cur.frame, parallax);

  PointEstimate e;
  e.status = Status::Ok;
  e.frame = cur.frame;
  e.parallax_px = parallax;
  e.c_P = Z * m1h;
  e.v_P = rig.visionPoint(cur.yaw, e.c_P);
  if (options.compute_covariance)
    e.c_cov = exactPointCovariance(l, W, Z, und, rows.m_cur, var);
  return e;
}

namespace {

/* The paper's estimate for perturbed inputs (pixels in px, increment in m and rad). Returns false
   when a pixel cannot be undistorted. Also reports the translation norm and the u-row parallax. */
struct PaperEval {
  Eigen::Vector3d c_P;
  double baseline = 0, parallax_px = 0;
};

bool paperEval(const CameraModel &camera, const YawRig &rig, const MotionSample &prev, const MotionSample &cur,
               const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv_cur, const VecIn &delta, PaperEval &out)
{
  Eigen::Vector2d m_prev, m_cur;
  if (!camera.undistort(uv_prev + delta.segment<2>(0), m_prev) || !camera.undistort(uv_cur + delta.segment<2>(2), m_cur))
    return false;
  IncrementPerturbation<double> p;
  p.d_translation = delta.segment<3>(4);
  p.d_rotation = delta.segment<3>(7);
  p.d_yaw_prev = delta(10);
  p.d_yaw_cur = delta(11);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  relativeMotion<double>(rig, prev, cur, p, R, t);
  // Camera motion over the increment in the current camera frame: P_cur = R P_prev + t with
  // R ~ I - [omega]x and t ~ -c_d (eq. (4)).
  const Eigen::AngleAxisd aa(R);
  const Eigen::Vector3d c_omega = -aa.angle() * aa.axis();
  const Eigen::Vector3d c_d = -t;
  const double du = camera.kx() * (m_cur.x() - m_prev.x()); // undistorted pixels
  // Parallax left after removing the rotation's image motion (first order, as eq. (2)).
  vpFeaturePoint s;
  s.buildFrom(m_cur.x(), m_cur.y(), 1.0);
  const vpMatrix L = s.interaction(vpFeaturePoint::selectX());
  double Lw_w = 0;
  for (unsigned j = 0; j < 3; ++j)
    Lw_w += L[0][3 + j] * c_omega(j);
  out.parallax_px = std::abs(du - camera.kx() * Lw_w);
  out.baseline = t.norm();
  const double Z = paperDepth(m_cur.x(), m_cur.y(), du, camera.kx(), c_d, c_omega);
  out.c_P = Z * homog(m_cur); // eq. (6)
  return true;
}

} // namespace

PointEstimate estimatePaper(const CameraModel &camera, const YawRig &rig, const MotionSample &prev,
                            const MotionSample &cur, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv_cur,
                            const TwoViewOptions &options)
{
  PaperEval nominal;
  if (!paperEval(camera, rig, prev, cur, uv_prev, uv_cur, VecIn::Zero(), nominal))
    return failed(Status::UndistortFailed, cur.frame);
  if (!(nominal.baseline >= options.gates.min_baseline))
    return failed(Status::NoMotion, cur.frame);
  if (!(nominal.parallax_px >= options.gates.min_parallax_px))
    return failed(Status::Degenerate, cur.frame, nominal.parallax_px);
  if (!std::isfinite(nominal.c_P.z()))
    return failed(Status::Degenerate, cur.frame, nominal.parallax_px);
  if (!(nominal.c_P.z() > 0))
    return failed(Status::Behind, cur.frame, nominal.parallax_px);

  PointEstimate e;
  e.status = Status::Ok;
  e.frame = cur.frame;
  e.parallax_px = nominal.parallax_px;
  e.c_P = nominal.c_P;
  e.v_P = rig.visionPoint(cur.yaw, e.c_P);
  if (options.compute_covariance) {
    // Central differences: steps small against each input's noise, large against round-off.
    const double steps[kInputs] = {1e-3, 1e-3, 1e-3, 1e-3, 1e-6, 1e-6, 1e-6, 1e-7, 1e-7, 1e-7, 1e-7, 1e-7};
    Eigen::Matrix<double, 3, kInputs> J;
    for (int i = 0; i < kInputs; ++i) {
      VecIn d = VecIn::Zero();
      d(i) = steps[i];
      PaperEval plus, minus;
      if (!paperEval(camera, rig, prev, cur, uv_prev, uv_cur, d, plus) ||
          !paperEval(camera, rig, prev, cur, uv_prev, uv_cur, -d, minus)) {
        J.col(i).setConstant(kNaN);
        continue;
      }
      J.col(i) = (plus.c_P - minus.c_P) / (2 * steps[i]);
    }
    e.c_cov = J *
              twoViewInputVariances(options.noise, options.increments, prev.six_dof || cur.six_dof, travel(prev, cur),
                                    turn(prev, cur))
                  .asDiagonal() *
              J.transpose();
  }
  return e;
}

} // namespace yawdepth
