#include "information.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <limits>
#include <numeric>
#include <unsupported/Eigen/AutoDiff>

namespace yawdepth {
namespace refine_detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Local parameter layout of an observation: point(3), pose_a(4), yaw_a(1), pose_k(4), yaw_k(1).
constexpr int kLocal = 13;
using AD13 = Eigen::AutoDiffScalar<Eigen::Matrix<double, kLocal, 1>>;
using AD8 = Eigen::AutoDiffScalar<Eigen::Matrix<double, 8, 1>>;

struct Local {
  AD13 x[kLocal];
  Local(const double *point, const double *pose_a, double yaw_a, const double *pose_k, double yaw_k)
  {
    double v[kLocal];
    std::copy(point, point + 3, v);
    std::copy(pose_a, pose_a + 4, v + 3);
    v[7] = yaw_a;
    std::copy(pose_k, pose_k + 4, v + 8);
    v[12] = yaw_k;
    for (int i = 0; i < kLocal; ++i)
      x[i] = AD13(v[i], kLocal, i);
  }
};

/* Global motion index of each local column (-1: a point column or a known parameter). */
std::array<int, kLocal> motionColumns(const Model &m, int row_a, int row_k)
{
  std::array<int, kLocal> c;
  c.fill(-1);
  for (int j = 0; j < 4; ++j) {
    const int pa = m.poseIndex(row_a), pk = m.poseIndex(row_k);
    c[3 + j] = pa >= 0 ? pa + j : -1;
    c[8 + j] = pk >= 0 ? pk + j : -1;
  }
  c[7] = m.yawIndex(row_a);
  c[12] = m.yawIndex(row_k);
  return c;
}

} // namespace

WhitenedObservation whitenObservation(const Eigen::Vector2d &m, const Eigen::Matrix2d &J, double sigma_px)
{
  const double s = std::max(sigma_px, kMinSigmaPx);
  const Eigen::Matrix2d cov = s * s * J * J.transpose();
  const Eigen::Matrix2d info = cov.inverse();
  // info = L L^T (L lower triangular); S = L^T is upper triangular with S^T S = info.
  const Eigen::Matrix2d L = info.llt().matrixL();
  WhitenedObservation w;
  w.m[0] = m.x();
  w.m[1] = m.y();
  w.s00 = L(0, 0);
  w.s01 = L(1, 0);
  w.s11 = L(1, 1);
  return w;
}

void cameraInWorld(const double *pose, double yaw, const Eigen::Vector3d &t0, Eigen::Matrix3d &R, Eigen::Vector3d &c)
{
  R = rotY(pose[3] + yaw);
  c = Eigen::Vector3d(pose[0], pose[1], pose[2]) + R * t0;
}

OdometryMeasurement measuredIncrement(const MotionSample &prev, const MotionSample &cur, const NoiseModel &noise)
{
  OdometryMeasurement o;
  const Eigen::Vector3d d = rotY(prev.heading).transpose() * Eigen::Vector3d(cur.x - prev.x, cur.y - prev.y, cur.z - prev.z);
  o.d[0] = d.x();
  o.d[1] = d.y();
  o.d[2] = d.z();
  o.dh = cur.heading - prev.heading;
  o.inv_sigma_t = 1.0 / std::max(noise.sigma_odom, kMinSigmaLength);
  o.inv_sigma_h = 1.0 / std::max(noise.sigma_heading, kMinSigmaAngle);
  return o;
}

void pointCovariances(const Model &m, bool joint, std::vector<Eigen::Matrix3d> &cov, std::vector<char> &ok)
{
  const int np = static_cast<int>(m.points.size());
  const int nl = m.motionParameters();
  cov.assign(np, Eigen::Matrix3d::Constant(kNaN));
  ok.assign(np, 0);

  // Motion-only information: the odometry and yaw priors.
  Eigen::MatrixXd Hprior = Eigen::MatrixXd::Zero(nl, nl);
  if (m.poses_free) {
    for (int row = 1; row < m.rows(); ++row) {
      AD8 x[8];
      for (int j = 0; j < 4; ++j) {
        x[j] = AD8(m.poses[row - 1][j], 8, j);
        x[4 + j] = AD8(m.poses[row][j], 8, 4 + j);
      }
      AD8 r[4];
      odometryResidual(x, x + 4, m.odometry[row - 1], r);
      Eigen::Matrix<double, 4, 8> J;
      for (int i = 0; i < 4; ++i)
        J.row(i) = r[i].derivatives().transpose();
      int idx[8];
      for (int j = 0; j < 4; ++j) {
        idx[j] = m.poseIndex(row - 1) >= 0 ? m.poseIndex(row - 1) + j : -1;
        idx[4 + j] = m.poseIndex(row) + j;
      }
      const Eigen::Matrix<double, 8, 8> JtJ = J.transpose() * J;
      for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b)
          if (idx[a] >= 0 && idx[b] >= 0)
            Hprior(idx[a], idx[b]) += JtJ(a, b);
    }
  }
  if (m.yaws_free)
    for (int row = 0; row < m.rows(); ++row)
      Hprior(m.yawIndex(row), m.yawIndex(row)) += m.inv_sigma_yaw * m.inv_sigma_yaw;

  // Observations grouped by point.
  std::vector<std::vector<int>> by_point(np);
  for (int i = 0; i < static_cast<int>(m.observations.size()); ++i)
    by_point[m.observations[i].point].push_back(i);

  std::vector<Eigen::Matrix3d> Hpp(np, Eigen::Matrix3d::Zero());
  std::vector<Eigen::MatrixXd> Hpl(np);
  std::vector<Eigen::Matrix3d> Hpp_inv(np, Eigen::Matrix3d::Constant(kNaN));
  Eigen::MatrixXd Hll = Hprior;          // joint: every observation's motion information
  Eigen::MatrixXd Hll_i(nl, nl);         // per point: that point's only
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(nl, nl);
  std::vector<Eigen::MatrixXd> Sigma_ll_point(joint ? 0 : np);

  for (int p = 0; p < np; ++p) {
    Hpl[p] = Eigen::MatrixXd::Zero(3, nl);
    Hll_i.setZero();
    const int ra = m.anchor_row[p];
    for (int oi : by_point[p]) {
      const ModelObservation &o = m.observations[oi];
      Eigen::Matrix<double, 2, kLocal> J = Eigen::Matrix<double, 2, kLocal>::Zero();
      if (o.row == ra) {
        // (alpha, beta) against the observation: d r / d point = S [I2 0].
        J(0, 0) = o.w.s00;
        J(0, 1) = o.w.s01;
        J(1, 1) = o.w.s11;
      } else {
        Local x(m.points[p].data(), m.poses[ra].data(), m.yaws[ra], m.poses[o.row].data(), m.yaws[o.row]);
        AD13 r[2];
        reprojectionResidual(x.x + 3, x.x + 7, x.x + 8, x.x + 12, x.x, m.t0, o.w, r);
        J.row(0) = r[0].derivatives().transpose();
        J.row(1) = r[1].derivatives().transpose();
      }
      const std::array<int, kLocal> col = motionColumns(m, ra, o.row);
      const Eigen::Matrix<double, kLocal, kLocal> JtJ = J.transpose() * J;
      Hpp[p] += JtJ.topLeftCorner<3, 3>();
      for (int b = 3; b < kLocal; ++b) {
        if (col[b] < 0)
          continue;
        Hpl[p].col(col[b]) += JtJ.block<3, 1>(0, b);
        for (int a = 3; a < kLocal; ++a)
          if (col[a] >= 0)
            Hll_i(col[a], col[b]) += JtJ(a, b);
      }
    }
    // A numerically singular point information: no estimate for that point.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Hpp[p]);
    const Eigen::Vector3d &ev = es.eigenvalues();
    if (!(ev(0) > 1e-12 * std::max(ev(2), 1e-300)) || !ev.allFinite())
      continue;
    ok[p] = 1;
    Hpp_inv[p] = es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    const Eigen::MatrixXd schur = Hpl[p].transpose() * Hpp_inv[p] * Hpl[p];
    if (joint) {
      Hll += Hll_i;
      S -= schur;
    } else if (nl > 0) {
      Eigen::MatrixXd Si = Hprior + Hll_i - schur;
      Si = 0.5 * (Si + Si.transpose());
      Sigma_ll_point[p] = Si.llt().solve(Eigen::MatrixXd::Identity(nl, nl));
    }
  }
  Eigen::MatrixXd Sigma_ll;
  if (joint && nl > 0) {
    S += Hll;
    S = 0.5 * (S + S.transpose());
    Eigen::LLT<Eigen::MatrixXd> llt(S);
    if (llt.info() == Eigen::Success)
      Sigma_ll = llt.solve(Eigen::MatrixXd::Identity(nl, nl));
    else
      Sigma_ll = S.completeOrthogonalDecomposition().pseudoInverse();
  }

  // Each point's camera-frame position at its report row, c_P = q / rho, and its covariance
  // G_p Hpp^-1 G_p^T + B Sigma_ll B^T with B = G_l - G_p Hpp^-1 Hpl.
  for (int p = 0; p < np; ++p) {
    if (!ok[p])
      continue;
    const int ra = m.anchor_row[p], rk = m.report_row[p];
    Local x(m.points[p].data(), m.poses[ra].data(), m.yaws[ra], m.poses[rk].data(), m.yaws[rk]);
    AD13 q[3];
    anchoredPoint(x.x + 3, x.x + 7, x.x + 8, x.x + 12, x.x, m.t0, q);
    Eigen::Matrix<double, 3, kLocal> G;
    for (int i = 0; i < 3; ++i) {
      const AD13 c = q[i] / x.x[2];
      G.row(i) = c.derivatives().transpose();
    }
    const std::array<int, kLocal> col = motionColumns(m, ra, rk);
    const Eigen::Matrix3d Gp = G.leftCols<3>();
    Eigen::Matrix3d C = Gp * Hpp_inv[p] * Gp.transpose();
    if (nl > 0) {
      Eigen::MatrixXd B = -(Gp * Hpp_inv[p]) * Hpl[p];
      for (int b = 3; b < kLocal; ++b)
        if (col[b] >= 0)
          B.col(col[b]) += G.col(b);
      const Eigen::MatrixXd &Sll = joint ? Sigma_ll : Sigma_ll_point[p];
      C += B * Sll * B.transpose();
    }
    cov[p] = 0.5 * (C + C.transpose());
    if (!cov[p].allFinite())
      ok[p] = 0;
  }
}

} // namespace refine_detail
} // namespace yawdepth
