#include <yawdepth/estimation/depth_filter.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <string>
#include <unsupported/Eigen/AutoDiff>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

constexpr int kNoise = 8; // d_x, d_y, d_z, rot_x, rot_y, rot_z, yaw_prev, yaw_cur
using Vec8 = Eigen::Matrix<double, kNoise, 1>;
using AD8 = Eigen::AutoDiffScalar<Vec8>;

// Joint variable of one step: w = (x, y, lambda, e_prev, d_x, d_y, d_z, rot_x, rot_y, rot_z, e_cur),
// lambda = log(1/Z); the last 7 are the increment's noise (IncrementPrior).
constexpr int kW = 11;
constexpr int kN = 7;
using Vec11 = Eigen::Matrix<double, kW, 1>;
using Mat4W = Eigen::Matrix<double, 4, kW>;
// Index of each increment-noise input (IncrementModel order) in w.
constexpr int kNoiseInW[kNoise] = {4, 5, 6, 7, 8, 9, 3, 10};

/* Prediction s' = g(w) through the increment, and its Jacobian (first order in the noise, which
   is exact at zero noise and accurate to O(sigma^2) ~ 1e-6 around it). Returns false when the
   point would be at or behind the new camera's plane. */
bool predict(const IncrementModel &inc, const Vec11 &w, Eigen::Vector4d &s, Mat4W *G)
{
  Eigen::Matrix3d R = inc.R;
  Eigen::Vector3d t = inc.t;
  for (int j = 0; j < kNoise; ++j) {
    const double n = w(kNoiseInW[j]);
    if (n != 0.0) {
      R += n * inc.dR[j];
      t += n * inc.dt[j];
    }
  }
  const Eigen::Vector3d m(w(0), w(1), 1.0);
  if (!(std::abs(w(2)) < 40.0)) // depth beyond e^40: no longer a number we can carry
    return false;
  const double rho = std::exp(w(2));
  const Eigen::Vector3d q = R * m + rho * t;
  if (!(q.z() > 1e-9))
    return false;
  const double iq = 1.0 / q.z();
  s << q.x() * iq, q.y() * iq, w(2) - std::log(q.z()), w(10);
  if (G) {
    Eigen::Matrix<double, 3, kW> dq;
    dq.col(0) = R.col(0);
    dq.col(1) = R.col(1);
    dq.col(2) = rho * t;
    for (int j = 0; j < kNoise; ++j)
      dq.col(kNoiseInW[j]) = inc.dR[j] * m + rho * inc.dt[j];
    G->row(0) = (dq.row(0) - s(0) * dq.row(2)) * iq;
    G->row(1) = (dq.row(1) - s(1) * dq.row(2)) * iq;
    G->row(2) = -iq * dq.row(2);
    (*G)(2, 2) += 1.0;
    G->row(3).setZero();
    (*G)(3, 10) = 1.0;
  }
  return true;
}

/* G Pw G^T for a 4x11 G and the block-diagonal prior Pw = diag(P, Q) of w = (state, increment noise). */
Eigen::Matrix4d propagateJoint(const Mat4W &G, const Eigen::Matrix4d &P, const Eigen::Matrix<double, kN, kN> &Q)
{
  const Eigen::Matrix4d Gs = G.leftCols<4>();
  const Eigen::Matrix<double, 4, kN> Gn = G.rightCols<kN>();
  return Gs * P * Gs.transpose() + Gn * Q * Gn.transpose();
}

/* The first update from the diffuse depth prior is the most nonlinear one (a large rotation between
   the frames makes it worse): the iterations start at the depth that the two observations
   triangulate, Z (m x R b) = -(m x t), where the MAP lies (the prior still counts). `s` is the state
   at the earlier frame; w, s_new and G are replaced only when that depth is usable. */
void startAtTriangulatedDepth(const IncrementModel &inc, const Eigen::Vector4d &s, const Eigen::Vector2d &m, Vec11 &w,
                              Eigen::Vector4d &s_new, Mat4W &G)
{
  const Eigen::Vector3d b(s(0), s(1), 1.0), mh(m.x(), m.y(), 1.0);
  const Eigen::Vector3d a = mh.cross(inc.R * b), c = mh.cross(inc.t);
  const double Z = -a.dot(c) / a.squaredNorm();
  Eigen::Vector4d s_try;
  Mat4W G_try;
  Vec11 w_try = w;
  w_try(2) = -std::log(Z);
  if (Z > 0 && std::isfinite(w_try(2)) && predict(inc, w_try, s_try, &G_try)) {
    w = w_try;
    s_new = s_try;
    G = G_try;
  }
}

/* How the iterated update of one observation ended. */
enum class Iterated { Converged, Gated, Failed };

/* Iterated EKF on w, started at `w` (s_new = g(w), G its Jacobian): the measurement h(w) is the first
   two components of g(w). With `gate`, the first iteration's innovation is tested against
   `outlier_chi2` (Gated: rejected). Failed: the innovation covariance is not positive or the
   iterate leaves the valid region (the caller restarts). */
Iterated iterateUpdate(const IncrementModel &inc, const Vec11 &mu, const Eigen::Matrix4d &P,
                       const Eigen::Matrix<double, kN, kN> &Q, const Eigen::Vector2d &m, const Eigen::Matrix2d &m_cov,
                       bool gate, double outlier_chi2, int max_iterations, Vec11 &w, Eigen::Vector4d &s_new, Mat4W &G)
{
  for (int it = 0; it < max_iterations; ++it) {
    const Eigen::Matrix<double, 2, kW> H = G.topRows<2>();
    Eigen::Matrix<double, kW, 2> PHt;
    PHt.topRows<4>() = P * H.leftCols<4>().transpose();
    PHt.bottomRows<kN>() = Q * H.rightCols<kN>().transpose();
    const Eigen::Matrix2d S = H * PHt + m_cov;
    const double det = S.determinant();
    if (!(det > 0) || !std::isfinite(det))
      return Iterated::Failed;
    const Eigen::Matrix2d S_inv = S.inverse();
    const Eigen::Vector2d nu = m - s_new.head<2>() - H * (mu - w);
    if (it == 0 && gate && !(nu.dot(S_inv * nu) <= outlier_chi2))
      return Iterated::Gated;
    const Vec11 w_next = mu + PHt * (S_inv * nu);
    const double change = std::abs(w_next(2) - w(2));
    w = w_next;
    if (!predict(inc, w, s_new, &G))
      return Iterated::Failed;
    if (change <= 1e-9 * (1.0 + std::abs(w(2))))
      break;
  }
  return Iterated::Converged;
}

/* The posterior covariance: the predicted state s' = g(w) linearised at the estimate has covariance
   M = G Pw G^T, and the observation is linear in s' (its first two components), so the update is a
   linear Kalman update of M, in Joseph form (stays positive semi-definite when the observation is
   far more precise than the prediction). */
Eigen::Matrix4d josephUpdate(const Eigen::Matrix4d &M, const Eigen::Matrix2d &m_cov)
{
  const Eigen::Matrix2d S = M.topLeftCorner<2, 2>() + m_cov;
  const Eigen::Matrix<double, 4, 2> K = M.leftCols<2>() * S.inverse();
  Eigen::Matrix4d IKC = Eigen::Matrix4d::Identity();
  IKC.leftCols<2>() -= K;
  const Eigen::Matrix4d P = IKC * M * IKC.transpose() + K * m_cov * K.transpose();
  return 0.5 * (P + P.transpose());
}

} // namespace

void composeIncrementNoise(Eigen::Matrix<double, 6, 6> &cov, Eigen::Matrix3d &R, const Eigen::Vector3d &d,
                           const Eigen::Matrix3d &dR, const Eigen::Matrix<double, 6, 6> &Q)
{
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Identity();
  A.topRightCorner<3, 3>() = -R * skew(d);
  A.bottomRightCorner<3, 3>() = dR.transpose();
  Eigen::Matrix<double, 6, 6> B = Eigen::Matrix<double, 6, 6>::Identity();
  B.topLeftCorner<3, 3>() = R;
  cov = A * cov * A.transpose() + B * Q * B.transpose();
  cov = 0.5 * (cov + cov.transpose());
  R = R * dR;
}

namespace {
const double kTwoSigmaProbability = std::erf(2.0 / std::sqrt(2.0)); // 0.9545
double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }
} // namespace

bool inverseDepthBounded(double r)
{
  // P(|1/u - 1| <= c) for u = rho / rho_hat ~ N(1, r^2) grows with c to normalCdf(1/r) (negative inverse
  // depths are never inside): some c reaches the 2-sigma probability only if normalCdf(1/r) exceeds it.
  return r >= 0 && std::isfinite(r) && (r == 0 || normalCdf(1.0 / r) > kTwoSigmaProbability);
}

double inverseDepthInterval(double r)
{
  if (!(r >= 0) || !std::isfinite(r))
    return std::numeric_limits<double>::quiet_NaN();
  if (r == 0)
    return 0.0;
  if (!inverseDepthBounded(r))
    return std::numeric_limits<double>::infinity();
  // P(c) = P(|1/u - 1| <= c) for u = rho / rho_hat ~ N(1, r^2), increasing in c.
  const double target = kTwoSigmaProbability;
  auto P = [&](double c) {
    const double near = c < 1.0 ? normalCdf(c / ((1.0 - c) * r)) : 1.0;
    return near - normalCdf(-c / ((1.0 + c) * r));
  };
  double lo = 0.0, hi = 2.0 * r;
  while (P(hi) < target) {
    lo = hi;
    hi *= 2.0;
    if (!(hi < 1e12))
      return std::numeric_limits<double>::infinity();
  }
  for (int i = 0; i < 60 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (P(mid) < target ? lo : hi) = mid;
  }
  return hi;
}

IncrementModel IncrementModel::between(const YawRig &rig, const MotionSample &prev, const MotionSample &cur)
{
  IncrementPerturbation<AD8> p;
  for (int i = 0; i < 3; ++i) {
    p.d_translation(i) = AD8(0.0, kNoise, i);
    p.d_rotation(i) = AD8(0.0, kNoise, 3 + i);
  }
  p.d_yaw_prev = AD8(0.0, kNoise, 6);
  p.d_yaw_cur = AD8(0.0, kNoise, 7);
  Eigen::Matrix<AD8, 3, 3> R;
  Eigen::Matrix<AD8, 3, 1> t;
  relativeMotion<AD8>(rig, prev, cur, p, R, t);
  IncrementModel inc;
  for (int j = 0; j < kNoise; ++j) {
    inc.dR[j].setZero();
    inc.dt[j].setZero();
  }
  for (int r = 0; r < 3; ++r) {
    inc.t(r) = t(r).value();
    for (int j = 0; j < kNoise; ++j)
      inc.dt[j](r) = t(r).derivatives().size() ? t(r).derivatives()(j) : 0.0;
    for (int c = 0; c < 3; ++c) {
      inc.R(r, c) = R(r, c).value();
      for (int j = 0; j < kNoise; ++j)
        inc.dR[j](r, c) = R(r, c).derivatives().size() ? R(r, c).derivatives()(j) : 0.0;
    }
  }
  inc.frame_prev = prev.frame;
  inc.frame_cur = cur.frame;
  inc.yaw_cur = cur.yaw;
  inc.six_dof = prev.six_dof || cur.six_dof;
  inc.distance = (cur.position() - prev.position()).norm();
  inc.angle = Eigen::AngleAxisd(prev.rotation().transpose() * cur.rotation()).angle();
  return inc;
}

DepthFilter::DepthFilter(const Options &options, double kx, double ky) : o_(options), kx_(kx), ky_(ky)
{
  o_.noise.validate();
  o_.gates.validate();
  if (!(kx > 0) || !(ky > 0) || !std::isfinite(kx) || !std::isfinite(ky))
    throw Error("depth filter: focal lengths must be finite and positive");
  if (!(o_.prior_depth > 0) || !(o_.prior_log_depth_sigma > 0) || !std::isfinite(o_.prior_depth) ||
      !std::isfinite(o_.prior_log_depth_sigma))
    throw Error("depth filter: the depth prior must be finite and positive, with a positive sigma");
  if (!(o_.outlier_chi2 > 0) || o_.max_consecutive_outliers < 1 || o_.max_iterations < 1 || !(o_.max_log_depth_sigma > 0))
    throw Error("depth filter: outlier gate and iteration counts must be positive");
}

void DepthFilter::initialize(long frame, double yaw, const Eigen::Vector2d &m, const Eigen::Matrix2d &m_cov)
{
  if (!m.allFinite() || !m_cov.allFinite())
    throw Error("depth filter: non-finite observation");
  initialized_ = true;
  frame_ = frame;
  yaw_ = yaw;
  s_ << m.x(), m.y(), -std::log(o_.prior_depth), 0.0;
  P_.setZero();
  P_.topLeftCorner<2, 2>() = m_cov;
  P_(2, 2) = o_.prior_log_depth_sigma * o_.prior_log_depth_sigma;
  P_(3, 3) = o_.noise.sigma_yaw * o_.noise.sigma_yaw;
  inliers_ = 1;
  outliers_ = 0;
  consecutive_outliers_ = 0;
  anchor_bearing_ = Eigen::Vector3d(m.x(), m.y(), 1.0);
  anchor_centre_.setZero();
  parallax_px_ = 0;
  baseline_ = 0;
}

IncrementPrior DepthFilter::defaultPrior(bool six_dof, double distance, double angle) const
{
  IncrementPrior p;
  const double st = incrementTranslationSigma(o_.noise, distance);
  const double so2 = st * st;
  const Eigen::Vector3d rot = incrementRotationSigma(o_.noise, six_dof, distance, angle);
  p.mean.setZero();
  p.cov.setZero();
  p.cov.diagonal() << so2, so2, so2, rot.cwiseAbs2(), o_.noise.sigma_yaw * o_.noise.sigma_yaw;
  return p;
}

DepthFilter::Update DepthFilter::step(const IncrementModel &inc, const Eigen::Vector2d *m, const Eigen::Matrix2d *m_cov,
                                      const IncrementPrior *prior)
{
  if (!initialized_)
    throw Error("depth filter: step() before initialize()");
  if (inc.frame_prev != frame_)
    throw Error("depth filter: increment starts at frame " + std::to_string(inc.frame_prev) + ", the filter is at frame " +
                std::to_string(frame_));
  if (m && (!m_cov || !m->allFinite() || !m_cov->allFinite()))
    throw Error("depth filter: an observation needs a finite point and covariance");

  // Track geometry since the first observation (for the gates).
  anchor_bearing_ = inc.R * anchor_bearing_;
  anchor_centre_ = inc.R * anchor_centre_ + inc.t;
  baseline_ = std::max(baseline_, anchor_centre_.norm());

  // Prior of the joint variable w = (state, increment noise): block diagonal, the state block is
  // P_ and the noise block Q (the noise model, or FusedEstimator's composed noise of the motion from
  // a key frame). Products with it are done by blocks.
  const IncrementPrior np = prior ? *prior : defaultPrior(inc.six_dof, inc.distance, inc.angle);
  if (!np.mean.allFinite() || !np.cov.allFinite())
    throw Error("depth filter: non-finite increment prior");
  Vec11 mu;
  mu << s_, np.mean;
  const Eigen::Matrix<double, kN, kN> &Q = np.cov;

  Eigen::Vector4d s_new;
  Mat4W G;
  const bool can_predict = predict(inc, mu, s_new, &G);
  frame_ = inc.frame_cur;
  yaw_ = inc.yaw_cur;

  auto restartAt = [&](const Eigen::Vector2d &mm, const Eigen::Matrix2d &cov) {
    initialize(inc.frame_cur, inc.yaw_cur, mm, cov);
    return Update::Restarted;
  };
  auto predictOnly = [&]() {
    s_ = s_new;
    P_ = propagateJoint(G, P_, Q);
    P_ = 0.5 * (P_ + P_.transpose());
  };

  if (!can_predict) // the estimate put the point behind the new camera: start again if we can
    return m ? restartAt(*m, *m_cov) : (initialized_ = false, Update::PredictOnly);
  if (!m) {
    predictOnly();
    return Update::PredictOnly;
  }

  // Iterated EKF on w (the measurement is the first two components of g(w)). The gate needs a
  // prediction to test against: the first update after a (re)start comes from the diffuse depth
  // prior, whose linearisation cannot judge it.
  Vec11 w = mu;
  if (inliers_ == 1)
    startAtTriangulatedDepth(inc, s_, *m, w, s_new, G);
  const Iterated result = iterateUpdate(inc, mu, P_, Q, *m, *m_cov, inliers_ >= 2, o_.outlier_chi2,
                                        o_.max_iterations, w, s_new, G);
  if (result == Iterated::Failed)
    return restartAt(*m, *m_cov);
  if (result == Iterated::Gated) {
    ++outliers_;
    ++rejected_;
    if (++consecutive_outliers_ >= o_.max_consecutive_outliers)
      return restartAt(*m, *m_cov);
    predictOnly();
    return Update::Outlier;
  }
  // Posterior: the iterated mean, the covariance by a Joseph-form update at it.
  P_ = josephUpdate(propagateJoint(G, P_, Q), *m_cov);
  s_ = s_new;
  ++inliers_;
  consecutive_outliers_ = 0;

  // Rotation-compensated parallax of this observation against the first one.
  if (anchor_bearing_.z() > 1e-12)
    parallax_px_ = std::max(parallax_px_, std::hypot(kx_ * (m->x() - anchor_bearing_.x() / anchor_bearing_.z()),
                                                     ky_ * (m->y() - anchor_bearing_.y() / anchor_bearing_.z())));
  else
    parallax_px_ = std::numeric_limits<double>::infinity();
  return Update::Inlier;
}

PointEstimate DepthFilter::estimate(const YawRig &rig) const
{
  PointEstimate e;
  e.frame = frame_;
  e.parallax_px = parallax_px_;
  if (!initialized_ || inliers_ < 2) {
    // Enough observations, all rejected: say so, not "too few frames".
    e.status = initialized_ && rejected_ > 0 ? Status::Inconsistent : Status::TooFewFrames;
    return e;
  }
  if (!(baseline_ >= o_.gates.min_baseline)) {
    e.status = Status::NoMotion;
    return e;
  }
  if (!(parallax_px_ >= o_.gates.min_parallax_px)) {
    e.status = Status::Degenerate;
    return e;
  }
  const double Z = std::exp(-s_(2));
  if (!P_.allFinite() || !(P_(2, 2) >= 0) || !std::isfinite(Z)) { // numerical breakdown
    e.status = Status::Degenerate;
    return e;
  }
  // Depth not resolved: the data leave it uncertain by more than a factor e^max at 1 sigma.
  if (!(std::sqrt(P_(2, 2)) <= o_.max_log_depth_sigma)) {
    e.status = Status::Degenerate;
    return e;
  }
  e.status = Status::Ok;
  e.c_P = Eigen::Vector3d(s_(0) * Z, s_(1) * Z, Z);
  // d(X, Y, Z)/d(x, y, lambda), lambda = -log Z
  Eigen::Matrix3d J;
  J << Z, 0, -s_(0) * Z, 0, Z, -s_(1) * Z, 0, 0, -Z;
  e.c_cov = J * P_.topLeftCorner<3, 3>() * J.transpose();
  // The observations are close to linear in inverse depth, so the depth's belief is read as
  // Gaussian in rho = 1/Z with sigma(rho) = rho sigma(lambda); Z = 1/rho is then skewed toward far
  // depths, and sigma_Z = Z sigma(lambda) would leave the far tail outside zc + 2 sigma_Z (a 2-sigma
  // coverage of 0.89 at sigma(lambda) = 0.3). The reported sigma is widened so that zc +- 2 sigma
  // holds the depth with a Gaussian's 2-sigma probability.
  const double r = std::sqrt(P_(2, 2));
  const double c = inverseDepthInterval(r);
  if (!std::isfinite(c)) { // that interval has no far end: the depth is not bounded
    e.status = Status::Degenerate;
    e.c_P = Eigen::Vector3d::Zero();
    e.c_cov = Eigen::Matrix3d::Zero();
    return e;
  }
  if (r > 0) {
    const double k = c / (2.0 * r);
    e.c_cov *= k * k;
  }
  // Vision frame with the filter's estimate of the current yaw (reading + estimated error).
  e.v_P = rig.visionPoint(yaw_ + s_(3), e.c_P);
  return e;
}

} // namespace yawdepth
