#include "information.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unsupported/Eigen/AutoDiff>

namespace yawdepth {
namespace refine_detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/* Local parameter layout of an observation: point(3), frame_a(PD + 1), frame_k(PD + 1), a frame
   being the pose (PD values) then the yaw. */
template <int PD> struct Layout {
  static constexpr int kFrame = PD + 1;
  static constexpr int kLocal = 3 + 2 * kFrame;
  using AD = Eigen::AutoDiffScalar<Eigen::Matrix<double, kLocal, 1>>;
  using ADPrior = Eigen::AutoDiffScalar<Eigen::Matrix<double, 2 * PD, 1>>;
};

template <int PD> struct Local {
  using AD = typename Layout<PD>::AD;
  static constexpr int kLocal = Layout<PD>::kLocal;
  AD x[kLocal];
  Local(const double *point, const double *pose_a, double yaw_a, const double *pose_k, double yaw_k)
  {
    double v[kLocal];
    std::copy(point, point + 3, v);
    std::copy(pose_a, pose_a + PD, v + 3);
    v[3 + PD] = yaw_a;
    std::copy(pose_k, pose_k + PD, v + 4 + PD);
    v[4 + 2 * PD] = yaw_k;
    for (int i = 0; i < kLocal; ++i)
      x[i] = AD(v[i], kLocal, i);
  }
  const AD *point() const { return x; }
  const AD *frameA() const { return x + 3; }
  const AD *frameK() const { return x + 4 + PD; }
};

/* rho times the camera-frame point at row k (anchoredPoint of the model's chain). */
template <int PD, typename T>
void modelAnchoredPoint(const Model &m, int ra, int rk, const T *frame_a, const T *frame_k, const T *point, T *q)
{
  if constexpr (PD == 6)
    anchoredPointGeneral(frame_a, m.Rref[ra], frame_k, m.Rref[rk], point, m.mount, q);
  else
    anchoredPoint(frame_a, frame_a + 4, frame_k, frame_k + 4, point, m.t0, q);
}

/* Global motion index of each local column (-1: a point column or a known parameter). */
template <int PD> std::array<int, Layout<PD>::kLocal> motionColumns(const Model &m, int row_a, int row_k)
{
  std::array<int, Layout<PD>::kLocal> c;
  c.fill(-1);
  for (int j = 0; j < PD; ++j) {
    c[3 + j] = m.poseIndex(row_a, j);
    c[4 + PD + j] = m.poseIndex(row_k, j);
  }
  c[3 + PD] = m.yawIndex(row_a);
  c[4 + 2 * PD] = m.yawIndex(row_k);
  return c;
}

} // namespace

void Model::setChainLink(std::size_t obs, std::size_t prev, double a)
{
  if (chain_prev.size() <= obs) {
    chain_prev.resize(obs + 1, -1);
    chain_a.resize(obs + 1, 0.0);
  }
  chain_prev[obs] = static_cast<int>(prev);
  chain_a[obs] = a;
}

int Model::freePoseComponents() const
{
  int n = 0;
  for (int j = 0; j < poseDim(); ++j)
    n += componentFree(j) ? 1 : 0;
  return n;
}

int Model::poseIndex(int row, int j) const
{
  if (!poses_free || row < firstFreeRow() || !componentFree(j))
    return -1;
  int k = 0;
  for (int i = 0; i < j; ++i)
    k += componentFree(i) ? 1 : 0;
  return freePoseComponents() * (row - firstFreeRow()) + k;
}

int Model::yawIndex(int row) const
{
  return yaws_free ? (poses_free ? freePoseComponents() * (rows() - firstFreeRow()) : 0) + row : -1;
}

int Model::motionParameters() const
{
  return (poses_free ? freePoseComponents() * (rows() - firstFreeRow()) : 0) + (yaws_free ? rows() : 0);
}

bool needsGeneralChain(const YawRig &rig, const std::vector<MotionSample> &motion)
{
  if (!rig.cameraRotation().isIdentity(0.0))
    return true;
  return std::any_of(motion.begin(), motion.end(), [](const MotionSample &s) { return s.six_dof; });
}

void cameraInWorldGeneral(const double *frame, const Eigen::Matrix3d &Rref, const Mount &mount, Eigen::Matrix3d &R,
                          Eigen::Vector3d &c)
{
  const Eigen::Matrix3d V = yawedRotation<double>(Rref, frame);
  R = V * mount.R0;
  c = Eigen::Vector3d(frame[0], frame[1], frame[2]) + V * mount.t0;
}

void setModelMotion(Model &m, const YawRig &rig, const std::vector<MotionSample> &measured, const NoiseModel &noise)
{
  m.general = needsGeneralChain(rig, measured);
  const Eigen::Vector3d &t0 = rig.cameraOffset();
  std::copy(t0.data(), t0.data() + 3, m.t0);
  m.mount.R0 = rig.cameraRotation();
  m.mount.t0 = t0;
  const bool six_dof = std::any_of(measured.begin(), measured.end(), [](const MotionSample &s) { return s.six_dof; });
  const Eigen::Vector3d sr = incrementRotationSigma(noise, six_dof, 1.0, 1.0);
  for (int i = 0; i < 3; ++i)
    m.rotation_free[i] = six_dof || i == 1;
  m.poses_free = incrementTranslationSigma(noise, 1.0) > 0 || sr.maxCoeff() > 0;
  m.yaws_free = noise.sigma_yaw > 0;
  m.inv_sigma_yaw = m.yaws_free ? 1.0 / noise.sigma_yaw : 0.0;
  m.Rref.clear();
  m.odometry.clear();
  m.odometry_general.clear();
  m.pose_priors.clear();
  m.absolute = noise.motion_noise == MotionNoise::Absolute;
  for (const MotionSample &s : measured)
    m.Rref.push_back(s.rotation());
  if (m.absolute) {
    const double inv_t = 1.0 / std::max(noise.sigma_odom, kMinSigmaLength);
    const Eigen::Vector3d sr = poseRotationSigma(noise, six_dof);
    for (const MotionSample &s : measured) {
      PosePrior p;
      p.value[0] = s.x;
      p.value[1] = s.y;
      p.value[2] = s.z;
      for (int i = 0; i < 3; ++i)
        p.inv_sigma[i] = inv_t;
      if (m.general) // the offset from the reference (measured) orientation, per axis
        for (int i = 0; i < 3; ++i)
          p.inv_sigma[3 + i] = 1.0 / std::max(sr(i), kMinSigmaAngle);
      else {
        p.value[3] = s.heading;
        p.inv_sigma[3] = 1.0 / std::max(sr(1), kMinSigmaAngle);
      }
      m.pose_priors.push_back(p);
    }
    return;
  }
  for (std::size_t r = 1; r < measured.size(); ++r) {
    if (m.general)
      m.odometry_general.push_back(measuredIncrementGeneral(measured[r - 1], measured[r], noise));
    else
      m.odometry.push_back(measuredIncrement(measured[r - 1], measured[r], noise));
  }
}

OdometryMeasurementGeneral measuredIncrementGeneral(const MotionSample &prev, const MotionSample &cur,
                                                    const NoiseModel &noise)
{
  OdometryMeasurementGeneral o;
  o.Rref_prev = prev.rotation();
  o.Rref_cur = cur.rotation();
  const Eigen::Vector3d d = o.Rref_prev.transpose() * (cur.position() - prev.position());
  std::copy(d.data(), d.data() + 3, o.d);
  o.dR = o.Rref_prev.transpose() * o.Rref_cur;
  const double distance = d.norm(), angle = Eigen::AngleAxisd(o.dR).angle();
  o.inv_sigma_t = 1.0 / std::max(incrementTranslationSigma(noise, distance), kMinSigmaLength);
  const Eigen::Vector3d sr = incrementRotationSigma(noise, prev.six_dof || cur.six_dof, distance, angle);
  for (int i = 0; i < 3; ++i)
    o.inv_sigma_r[i] = 1.0 / std::max(sr(i), kMinSigmaAngle);
  return o;
}

WhitenedObservation whitenObservation(const Eigen::Vector2d &m, const Eigen::Matrix2d &J, double sigma_px)
{
  const double s = std::max(sigma_px, kMinWeightPx);
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
  const double distance = d.norm();
  o.inv_sigma_t = 1.0 / std::max(incrementTranslationSigma(noise, distance), kMinSigmaLength);
  o.inv_sigma_h = 1.0 / std::max(incrementRotationSigma(noise, false, distance, std::fabs(o.dh)).y(), kMinSigmaAngle);
  return o;
}

namespace {

/* The motion's information S (symmetric, n x n) as it is summed: dense, or only its lower band
   (S(i, j) for 0 <= i - j <= band) when every coupling is that near the diagonal, as in a long log
   whose points each see a few frames (the motion columns are in frame order). Entries are added
   for both (i, j) and (j, i); the band keeps the lower one. */
class MotionInformation {
public:
  MotionInformation(int n, int band) : band_(band)
  {
    if (band_ < 0)
      dense_ = Eigen::MatrixXd::Zero(n, n);
    else
      lower_ = Eigen::MatrixXd::Zero(band_ + 1, n);
  }
  bool banded() const { return band_ >= 0; }
  void add(int i, int j, double v)
  {
    if (band_ < 0)
      dense_(i, j) += v;
    else if (i >= j)
      lower_(i - j, j) += v;
  }
  /* The dense matrix (banded: filled from the band). Leaves this object empty. */
  Eigen::MatrixXd takeDense()
  {
    if (band_ >= 0) {
      const Eigen::Index n = lower_.cols();
      dense_ = Eigen::MatrixXd::Zero(n, n);
      for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index d = 0; d <= band_ && j + d < n; ++d)
          dense_(j + d, j) = dense_(j, j + d) = lower_(d, j);
      lower_.resize(0, 0);
    }
    return std::move(dense_);
  }
  /* The lower triangle as a sparse matrix (banded only). */
  Eigen::SparseMatrix<double> lowerSparse() const
  {
    const Eigen::Index n = lower_.cols();
    Eigen::SparseMatrix<double> L(n, n);
    L.reserve(Eigen::VectorXi::Constant(n, band_ + 1));
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index d = 0; d <= band_ && j + d < n; ++d)
        if (lower_(d, j) != 0.0)
          L.insert(j + d, j) = lower_(d, j);
    L.makeCompressed();
    return L;
  }

private:
  int band_;
  Eigen::MatrixXd dense_, lower_;
};

/* The banded form from this many motion parameters on (about 60 frames), when the widest coupling
   spans under half of them: its factorisation then costs at most what the dense one does, and its
   memory grows with frames x band instead of frames^2. */
constexpr int kBandedMinParameters = 300;

/* The motion's own information, from the odometry (per increment, or per pose for absolute noise)
   and the yaw readings, as (i, j, value) triplets over the model's motion parameters, summed. */
template <int PD> std::vector<Eigen::Triplet<double>> motionPrior(const Model &m)
{
  using ADPrior = typename Layout<PD>::ADPrior;
  constexpr int kR = PD == 6 ? 6 : 4; // odometry residuals
  std::vector<Eigen::Triplet<double>> prior;
  if (m.poses_free && m.absolute) {
    for (int row = 0; row < m.rows(); ++row)
      for (int j = 0; j < PD; ++j) {
        const int i = m.poseIndex(row, j);
        if (i >= 0)
          prior.emplace_back(i, i, m.pose_priors[row].inv_sigma[j] * m.pose_priors[row].inv_sigma[j]);
      }
  } else if (m.poses_free) {
    for (int row = 1; row < m.rows(); ++row) {
      ADPrior x[2 * PD];
      for (int j = 0; j < PD; ++j) {
        x[j] = ADPrior(m.poses[row - 1][j], 2 * PD, j);
        x[PD + j] = ADPrior(m.poses[row][j], 2 * PD, PD + j);
      }
      ADPrior r[kR];
      if constexpr (PD == 6)
        odometryResidualGeneral(x, x + PD, m.odometry_general[row - 1], r);
      else
        odometryResidual(x, x + PD, m.odometry[row - 1], r);
      Eigen::Matrix<double, kR, 2 * PD> J;
      for (int i = 0; i < kR; ++i)
        J.row(i) = r[i].derivatives().transpose();
      int idx[2 * PD];
      for (int j = 0; j < PD; ++j) {
        idx[j] = m.poseIndex(row - 1, j);
        idx[PD + j] = m.poseIndex(row, j);
      }
      const Eigen::Matrix<double, 2 * PD, 2 * PD> JtJ = J.transpose() * J;
      for (int a = 0; a < 2 * PD; ++a)
        for (int b = 0; b < 2 * PD; ++b)
          if (idx[a] >= 0 && idx[b] >= 0)
            prior.emplace_back(idx[a], idx[b], JtJ(a, b));
    }
  }
  if (m.yaws_free)
    for (int row = 0; row < m.rows(); ++row)
      prior.emplace_back(m.yawIndex(row), m.yawIndex(row), m.inv_sigma_yaw * m.inv_sigma_yaw);
  return prior;
}

/* The motion columns in frame order (each row's pose, then its yaw): S's order, in which a point
   couples only the columns of the frames it sees and the priors only neighbouring frames. pos[c] is
   column c's place in that order (the identity when the model's columns do not fit it). */
template <int PD> std::vector<int> frameOrder(const Model &m, int nl)
{
  std::vector<int> pos(static_cast<std::size_t>(nl), -1);
  int next = 0;
  for (int row = 0; row < m.rows(); ++row) {
    for (int j = 0; j < PD; ++j)
      if (const int c = m.poseIndex(row, j); c >= 0)
        pos[static_cast<std::size_t>(c)] = next++;
    if (const int c = m.yawIndex(row); c >= 0)
      pos[static_cast<std::size_t>(c)] = next++;
  }
  if (next != nl || std::count(pos.begin(), pos.end(), -1) > 0)
    std::iota(pos.begin(), pos.end(), 0);
  return pos;
}

/* Each point's motion columns (cols[p], sorted), and the widest coupling between two motion columns
   in frame order, over the priors and the points. */
template <int PD>
int pointColumns(const Model &m, const std::vector<std::vector<int>> &by_point, const std::vector<int> &pos,
                 const std::vector<Eigen::Triplet<double>> &prior, std::vector<std::vector<int>> &cols)
{
  const int nl = static_cast<int>(pos.size());
  int band = 0;
  for (const auto &t : prior)
    band = std::max(band, std::abs(pos[static_cast<std::size_t>(t.row())] - pos[static_cast<std::size_t>(t.col())]));
  cols.assign(by_point.size(), {});
  for (std::size_t p = 0; p < by_point.size(); ++p) {
    std::vector<int> &cp = cols[p];
    for (int oi : by_point[p])
      for (int c : motionColumns<PD>(m, m.anchor_row[p], m.observations[oi].row))
        if (c >= 0)
          cp.push_back(c);
    std::sort(cp.begin(), cp.end());
    cp.erase(std::unique(cp.begin(), cp.end()), cp.end());
    int lo = nl, hi = -1;
    for (int c : cp) {
      lo = std::min(lo, pos[static_cast<std::size_t>(c)]);
      hi = std::max(hi, pos[static_cast<std::size_t>(c)]);
    }
    band = std::max(band, hi - lo);
  }
  return band;
}

/* Observation o's whitened residual's Jacobian over its local parameters (Layout: point, frame_a,
   frame_k) for point p. */
template <int PD>
Eigen::Matrix<double, 2, Layout<PD>::kLocal> observationJacobian(const Model &m, int p, const ModelObservation &o)
{
  using AD = typename Layout<PD>::AD;
  constexpr int kLocal = Layout<PD>::kLocal;
  const int ra = m.anchor_row[p];
  Eigen::Matrix<double, 2, kLocal> J = Eigen::Matrix<double, 2, kLocal>::Zero();
  if (o.row == ra) {
    // (alpha, beta) against the observation: d r / d point = S [I2 0].
    J(0, 0) = o.w.s00;
    J(0, 1) = o.w.s01;
    J(1, 1) = o.w.s11;
  } else {
    const Local<PD> x(m.points[p].data(), m.poses[ra].data(), m.yaws[ra], m.poses[o.row].data(), m.yaws[o.row]);
    AD q[3];
    modelAnchoredPoint<PD>(m, ra, o.row, x.frameA(), x.frameK(), x.point(), q);
    AD r[2];
    whiten(o.w, AD(q[0] / q[2] - o.w.m[0]), AD(q[1] / q[2] - o.w.m[1]), r);
    J.row(0) = r[0].derivatives().transpose();
    J.row(1) = r[1].derivatives().transpose();
  }
  return J;
}

/* J^T J of a residual into a point's information (pointInformation): J's column b is point
   component pt[b] (0..2) or -1, and motion column loc[b] (a place in the point's columns) or -1.
   Columns that name the same parameter add up. */
template <int N>
void accumulateInformation(const Eigen::Matrix<double, 2, N> &J, const std::array<int, N> &pt,
                           const std::array<int, N> &loc, Eigen::Matrix3d &Hpp, Eigen::MatrixXd &Hpl,
                           Eigen::MatrixXd &Hll)
{
  const Eigen::Matrix<double, N, N> JtJ = J.transpose() * J;
  for (int b = 0; b < N; ++b)
    for (int a = 0; a < N; ++a) {
      if (pt[a] >= 0 && pt[b] >= 0)
        Hpp(pt[a], pt[b]) += JtJ(a, b);
      if (pt[a] >= 0 && loc[b] >= 0)
        Hpl(pt[a], loc[b]) += JtJ(a, b);
      if (loc[a] >= 0 && loc[b] >= 0)
        Hll(loc[a], loc[b]) += JtJ(a, b);
    }
}

/* One point's information from its observations: Hpp (3x3), Hpl (3 x its motion columns cp) and
   Hll (over cp). `where` maps a global motion column to its place in cp; it is all -1 on entry and
   on return. An observation linked to its chain's previous (Model::chain_prev) enters as the AR(1)
   innovation, whose Jacobian is scale (J_k - a J_prev) over both observations' parameters. */
template <int PD>
void pointInformation(const Model &m, int p, const std::vector<int> &observations, const std::vector<int> &cp,
                      std::vector<int> &where, Eigen::Matrix3d &Hpp, Eigen::MatrixXd &Hpl, Eigen::MatrixXd &Hll)
{
  constexpr int kLocal = Layout<PD>::kLocal;
  const int ra = m.anchor_row[p];
  const int k = static_cast<int>(cp.size());
  for (int i = 0; i < k; ++i)
    where[static_cast<std::size_t>(cp[i])] = i;
  Hpl = Eigen::MatrixXd::Zero(3, k);
  Hll = Eigen::MatrixXd::Zero(k, k);
  // Local column b's point component and place in cp, for an observation at row.
  auto slots = [&](int row, std::array<int, kLocal> &pt, std::array<int, kLocal> &loc) {
    const std::array<int, kLocal> col = motionColumns<PD>(m, ra, row);
    for (int b = 0; b < kLocal; ++b) {
      pt[b] = b < 3 ? b : -1;
      loc[b] = b >= 3 && col[b] >= 0 ? where[static_cast<std::size_t>(col[b])] : -1;
    }
  };
  for (int oi : observations) {
    const ModelObservation &o = m.observations[oi];
    const Eigen::Matrix<double, 2, kLocal> J = observationJacobian<PD>(m, p, o);
    std::array<int, kLocal> pt, loc;
    slots(o.row, pt, loc);
    const int prev = m.chainPrevious(static_cast<std::size_t>(oi));
    if (prev < 0) {
      accumulateInformation<kLocal>(J, pt, loc, Hpp, Hpl, Hll);
      continue;
    }
    const ModelObservation &op = m.observations[prev];
    const double a = m.chain_a[oi], scale = 1.0 / std::sqrt(1.0 - a * a);
    Eigen::Matrix<double, 2, 2 * kLocal> Jl;
    Jl << scale * J, -scale * a * observationJacobian<PD>(m, p, op);
    std::array<int, kLocal> pt_prev, loc_prev;
    slots(op.row, pt_prev, loc_prev);
    std::array<int, 2 * kLocal> pt2, loc2;
    std::copy(pt.begin(), pt.end(), pt2.begin());
    std::copy(pt_prev.begin(), pt_prev.end(), pt2.begin() + kLocal);
    std::copy(loc.begin(), loc.end(), loc2.begin());
    std::copy(loc_prev.begin(), loc_prev.end(), loc2.begin() + kLocal);
    accumulateInformation<2 * kLocal>(Jl, pt2, loc2, Hpp, Hpl, Hll);
  }
  for (int c : cp)
    where[static_cast<std::size_t>(c)] = -1;
}

/* The motion's covariance from its information S (frame order): dense, S^-1 whole; banded, S's
   sparse Cholesky factor L (natural order: the band has no fill outside itself), with which each
   point's B S^-1 B^T is |L^-1 B^T|^2. */
struct MotionCovariance {
  Eigen::MatrixXd dense;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> sparse_llt;
  bool use_sparse = false;
  /* The information is numerically singular: the motion's covariance (and every point's through
     it) cannot be computed, e.g. motion sigmas so large that the data alone must fix the scale,
     which one camera cannot. */
  bool failed = false;

  void compute(MotionInformation &S, int nl)
  {
    if (S.banded()) {
      sparse_llt.compute(S.lowerSparse());
      use_sparse = sparse_llt.info() == Eigen::Success;
      if (use_sparse) {
        failed = !wellConditioned(sparse_llt.matrixL().toDense().diagonal());
        return;
      }
    }
    Eigen::MatrixXd Sd = S.takeDense();
    Sd = 0.5 * (Sd + Sd.transpose());
    Eigen::LLT<Eigen::MatrixXd> llt(Sd);
    failed = llt.info() != Eigen::Success || !wellConditioned(Eigen::MatrixXd(llt.matrixL()).diagonal());
    if (failed)
      return;
    dense = Eigen::MatrixXd::Identity(nl, nl);
    llt.solveInPlace(dense);
  }

  /* Cholesky pivots (L's diagonal squared) all finite and none below kMinPivotRatio of the largest:
     below it, rounding (1e-16 of the largest) is a sizeable part of the smallest, and the inverse
     in that direction is noise (the covariance would collapse where it should be huge). */
  static constexpr double kMinPivotRatio = 1e-13;
  static bool wellConditioned(const Eigen::VectorXd &l_diagonal)
  {
    if (l_diagonal.size() == 0)
      return true;
    const Eigen::VectorXd d = l_diagonal.cwiseAbs2();
    return d.allFinite() && d.minCoeff() > kMinPivotRatio * d.maxCoeff();
  }
};

/* Point p's camera-frame covariance at its report row: G_p Hpp^-1 G_p^T + B Sigma_ll B^T with
   B = G_l - G_p Hpp^-1 Hpl, over the point's motion columns and its report row's. `joint`: the
   motion's covariance is `motion` (frame order, `pos`); otherwise the point's own Sigma_ll_point
   (the motion's order). */
template <int PD>
Eigen::Matrix3d pointCovariance(const Model &m, int p, bool joint, const Eigen::Matrix3d &Hpp_inv,
                                const Eigen::MatrixXd &Hpl, const std::vector<int> &cp, const std::vector<int> &pos,
                                MotionCovariance &motion, const Eigen::MatrixXd &Sigma_ll_point)
{
  using AD = typename Layout<PD>::AD;
  constexpr int kLocal = Layout<PD>::kLocal;
  const int nl = static_cast<int>(pos.size());
  const int ra = m.anchor_row[p], rk = m.report_row[p];
  const Local<PD> x(m.points[p].data(), m.poses[ra].data(), m.yaws[ra], m.poses[rk].data(), m.yaws[rk]);
  AD q[3];
  modelAnchoredPoint<PD>(m, ra, rk, x.frameA(), x.frameK(), x.point(), q);
  Eigen::Matrix<double, 3, kLocal> G;
  for (int i = 0; i < 3; ++i) {
    const AD c = q[i] / x.x[2];
    G.row(i) = c.derivatives().transpose();
  }
  const Eigen::Matrix3d Gp = G.template leftCols<3>();
  Eigen::Matrix3d C = Gp * Hpp_inv * Gp.transpose();
  if (nl > 0) {
    // B's columns: the point's own, then its report row's that it does not already touch.
    const std::array<int, kLocal> col = motionColumns<PD>(m, ra, rk);
    std::vector<int> cb = cp;
    for (int b = 3; b < kLocal; ++b)
      if (col[b] >= 0 && !std::binary_search(cp.begin(), cp.end(), col[b]))
        cb.push_back(col[b]);
    const int kb = static_cast<int>(cb.size());
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3, kb);
    B.leftCols(static_cast<Eigen::Index>(cp.size())) = -(Gp * Hpp_inv) * Hpl;
    for (int b = 3; b < kLocal; ++b)
      if (col[b] >= 0)
        B.col(std::find(cb.begin(), cb.end(), col[b]) - cb.begin()) += G.col(b);
    if (joint && motion.use_sparse) {
      Eigen::MatrixXd Bt = Eigen::MatrixXd::Zero(nl, 3);
      for (int i = 0; i < kb; ++i)
        Bt.row(pos[static_cast<std::size_t>(cb[i])]) = B.col(i).transpose();
      if (motion.sparse_llt.permutationP().size() > 0) // none with the natural order; kept general
        Bt = motion.sparse_llt.permutationP() * Bt;
      motion.sparse_llt.matrixL().solveInPlace(Bt);
      C += Bt.transpose() * Bt;
    } else {
      // joint: in S's (frame) order; per point: in the motion's own.
      const Eigen::MatrixXd &Sll = joint ? motion.dense : Sigma_ll_point;
      auto at = [&](int c) { return joint ? pos[static_cast<std::size_t>(c)] : c; };
      Eigen::MatrixXd Ssub(kb, kb);
      for (int j = 0; j < kb; ++j)
        for (int i = 0; i < kb; ++i)
          Ssub(i, j) = Sll(at(cb[i]), at(cb[j]));
      C += B * Ssub * B.transpose();
    }
  }
  return 0.5 * (C + C.transpose());
}

template <int PD>
void pointCovariancesT(const Model &m, bool joint, std::vector<Eigen::Matrix3d> &cov, std::vector<char> &ok)
{
  const int np = static_cast<int>(m.points.size());
  const int nl = m.motionParameters();
  cov.assign(np, Eigen::Matrix3d::Constant(kNaN));
  ok.assign(np, 0);

  const std::vector<Eigen::Triplet<double>> prior = motionPrior<PD>(m);
  std::vector<std::vector<int>> by_point(np); // observations grouped by point
  for (int i = 0; i < static_cast<int>(m.observations.size()); ++i)
    by_point[m.observations[i].point].push_back(i);

  // Each point's information is kept over the motion columns it touches only (cols[p], sorted):
  // Hpl[p] is 3 x |cols[p]|, and its Schur complement on the motion goes into S over those columns.
  // A point seen in a few of many frames then costs what its own observations cost, not the size
  // of the whole motion (with dense 3 x nl and nl x nl blocks per point, a long log's cost grew
  // with points x frames^2).
  const std::vector<int> pos = frameOrder<PD>(m, nl);
  std::vector<std::vector<int>> cols;
  const int band = pointColumns<PD>(m, by_point, pos, prior, cols);
  // joint: S = Hprior + the sum over points of (Hll_p - schur_p), in frame order; per point:
  // Hprior alone, dense, in the motion's own order.
  MotionInformation S(joint ? nl : 0, joint && nl >= kBandedMinParameters && 2 * band < nl ? band : -1);
  Eigen::MatrixXd Hprior;
  if (joint)
    for (const auto &t : prior)
      S.add(pos[static_cast<std::size_t>(t.row())], pos[static_cast<std::size_t>(t.col())], t.value());
  else {
    Hprior = Eigen::MatrixXd::Zero(nl, nl);
    for (const auto &t : prior)
      Hprior(t.row(), t.col()) += t.value();
  }
  std::vector<Eigen::MatrixXd> Sigma_ll_point(joint ? 0 : np);
  std::vector<Eigen::MatrixXd> Hpl(np);
  std::vector<Eigen::Matrix3d> Hpp_inv(np, Eigen::Matrix3d::Constant(kNaN));
  std::vector<int> where(static_cast<std::size_t>(nl), -1); // global motion column -> position in cols[p]
  for (int p = 0; p < np; ++p) {
    const std::vector<int> &cp = cols[p];
    const int k = static_cast<int>(cp.size());
    Eigen::Matrix3d Hpp = Eigen::Matrix3d::Zero();
    Eigen::MatrixXd Hll_p;
    pointInformation<PD>(m, p, by_point[p], cp, where, Hpp, Hpl[p], Hll_p);
    // A numerically singular point information: no estimate for that point.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Hpp);
    const Eigen::Vector3d &ev = es.eigenvalues();
    if (!(ev(0) > 1e-12 * std::max(ev(2), 1e-300)) || !ev.allFinite())
      continue;
    ok[p] = 1;
    Hpp_inv[p] = es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    const Eigen::MatrixXd reduced = Hll_p - Hpl[p].transpose() * Hpp_inv[p] * Hpl[p];
    if (joint) {
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i)
          S.add(pos[static_cast<std::size_t>(cp[i])], pos[static_cast<std::size_t>(cp[j])], reduced(i, j));
    } else if (nl > 0) {
      Eigen::MatrixXd Si = Hprior;
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i)
          Si(cp[i], cp[j]) += reduced(i, j);
      Si = 0.5 * (Si + Si.transpose());
      const Eigen::LLT<Eigen::MatrixXd> llt(Si);
      if (llt.info() != Eigen::Success || !MotionCovariance::wellConditioned(Eigen::MatrixXd(llt.matrixL()).diagonal())) {
        ok[p] = 0;
        continue;
      }
      Sigma_ll_point[p] = llt.solve(Eigen::MatrixXd::Identity(nl, nl));
    }
  }
  MotionCovariance motion;
  if (joint && nl > 0) {
    motion.compute(S, nl);
    if (motion.failed) { // no point's covariance can be trusted
      ok.assign(np, 0);
      return;
    }
  }

  // Each point's camera-frame position at its report row, c_P = q / rho, and its covariance.
  for (int p = 0; p < np; ++p) {
    if (!ok[p])
      continue;
    cov[p] = pointCovariance<PD>(m, p, joint, Hpp_inv[p], Hpl[p], cols[p], pos, motion,
                                 joint ? motion.dense : Sigma_ll_point[p]);
    if (!cov[p].allFinite())
      ok[p] = 0;
  }
}

} // namespace

void pointCovariances(const Model &m, bool joint, std::vector<Eigen::Matrix3d> &cov, std::vector<char> &ok)
{
  if (m.general)
    pointCovariancesT<6>(m, joint, cov, ok);
  else
    pointCovariancesT<4>(m, joint, cov, ok);
}

} // namespace refine_detail
} // namespace yawdepth
