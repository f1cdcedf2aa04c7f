#include <yawdepth/pipeline/residual_check.h>

#include "residual_statistics.h"
#include "variance_factor.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <yawdepth/error.h>

namespace yawdepth {

void ResidualCheckOptions::validate() const
{
  if (!(gate_probability > 0.5 && gate_probability < 1))
    throw Error("residual check: the gate probability must be in (0.5, 1)");
  if (min_tracks < 1)
    throw Error("residual check: min_tracks must be at least 1");
}

namespace {

/* The standard normal quantile for p in (0.5, 1) (Acklam's rational approximation, relative error
   below 1.2e-9), refined by one Newton step on erfc. */
double normalQuantile(double p)
{
  const double q = std::min(p, 1 - p);
  double x;
  if (q > 0.02425) {
    const double r = q - 0.5, s = r * r;
    x = (((((-3.969683028665376e+01 * s + 2.209460984245205e+02) * s - 2.759285104469687e+02) * s +
           1.383577518672690e+02) * s - 3.066479806614716e+01) * s + 2.506628277459239e+00) * r /
        (((((-5.447609879822406e+01 * s + 1.615858368580409e+02) * s - 1.556989798598866e+02) * s +
           6.680131188771972e+01) * s - 1.328068155288572e+01) * s + 1);
  } else {
    const double r = std::sqrt(-2 * std::log(q));
    x = (((((-7.784894002430293e-03 * r - 3.223964580411365e-01) * r - 2.400758277161838e+00) * r -
           2.549732539343734e+00) * r + 4.374664141464968e+00) * r + 2.938163982698783e+00) /
        ((((7.784695709041462e-03 * r + 3.224671290700398e-01) * r + 2.445134137142996e+00) * r +
          3.754408661907416e+00) * r + 1);
  }
  // x is the q quantile (negative); one Newton step, then the upper one.
  const double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - q;
  x -= e * std::sqrt(2 * M_PI) * std::exp(x * x / 2);
  return -x;
}

/* Rotation angle of one increment (rad): the heading change of a planar log, the angle of the
   relative rotation of a 6-DoF one. */
double incrementAngle(const MotionSample &a, const MotionSample &b)
{
  if (!a.six_dof && !b.six_dof)
    return std::abs(b.heading - a.heading);
  return logSO3(a.rotation().transpose() * b.rotation()).norm();
}

/* The noise one increment of the log adds (MotionNoise::Increment): rotation and translation
   variance per axis (rad^2, m^2), and the step's length d (m), over which the rotation error so far
   turns the translation. */
struct StepNoise {
  double var_rot = 0, var_t = 0, d = 0;
};
StepNoise stepNoise(const NoiseModel &noise, const MotionSample &p, const MotionSample &c)
{
  const double r = c.six_dof ? noise.sigma_rot : noise.sigma_heading;
  StepNoise s;
  s.d = (c.position() - p.position()).norm();
  const double theta = incrementAngle(p, c), odom = noise.odom_per_metre * s.d;
  const double per_rad = noise.rot_per_radian * theta, per_m = noise.rot_per_metre * s.d;
  s.var_t = noise.sigma_odom * noise.sigma_odom + odom * odom;
  s.var_rot = r * r + per_rad * per_rad + per_m * per_m;
  return s;
}

/* Walks the log from row `from` towards row `to` (either direction), composing the increments'
   noise as relativePoseSigma() says; `at(row, var_rot, var_t)` is called on every row reached,
   `from` included (with zero variance before the yaw readings). */
template <class Visit>
void walkPoseNoise(const NoiseModel &noise, const std::vector<MotionSample> &motion, std::size_t from, std::size_t to,
                   Visit at)
{
  const double yaw2 = 2 * noise.sigma_yaw * noise.sigma_yaw;
  at(from, 0.0, 0.0);
  if (from == to)
    return;
  const bool six = motion[from].six_dof;
  const double r = six ? noise.sigma_rot : noise.sigma_heading;
  if (noise.motion_noise == MotionNoise::Absolute) { // two independent pose errors, whatever lies between
    const double var_rot = 2 * r * r + yaw2, var_t = 2 * noise.sigma_odom * noise.sigma_odom;
    const long step = to > from ? 1 : -1;
    for (long i = static_cast<long>(from) + step;; i += step) {
      at(static_cast<std::size_t>(i), var_rot, var_t);
      if (static_cast<std::size_t>(i) == to)
        break;
    }
    return;
  }
  double var_rot = 0, var_t = 0;
  const long step = to > from ? 1 : -1;
  for (long i = static_cast<long>(from) + step;; i += step) {
    const StepNoise q = stepNoise(noise, motion[static_cast<std::size_t>(i - step)], motion[static_cast<std::size_t>(i)]);
    var_t += q.var_t + var_rot * q.d * q.d; // the rotation error so far turns this step
    var_rot += q.var_rot;
    at(static_cast<std::size_t>(i), var_rot + yaw2, var_t);
    if (static_cast<std::size_t>(i) == to)
      break;
  }
}

/* The chi-square of a track's residuals along one walk from the point's row, with the pose errors'
   correlation along the walk (a per-increment drift is shared by every later observation, a per-pose
   error by none but the reference's): a Kalman filter per pixel axis on the state (rotation error,
   translation error) of the walk's pose relative to the point's, each residual r = f theta +
   (f / Z) tau + pixel noise (the isotropic stand-in of the file); the sum of the normalised
   innovations. Feed rows in walk order with start(), step() between rows, observe() per residual. */
class WalkChi2 {
public:
  WalkChi2(const NoiseModel &noise, double f) : noise_(noise), f_(f)
  {
    const double y2 = noise.sigma_yaw * noise.sigma_yaw;
    if (noise.motion_noise == MotionNoise::Absolute) { // the reference pose's own error, shared
      const double r = noise.sigma_rot > 0 ? noise.sigma_rot : noise.sigma_heading;
      rot_ = r * r;
      P_ << rot_ + y2, 0, 0, noise.sigma_odom * noise.sigma_odom;
    } else {
      P_ << y2, 0, 0, 0; // the reference's yaw reading, shared
    }
  }
  void setSixDof(bool six)
  {
    if (noise_.motion_noise == MotionNoise::Absolute) {
      const double r = six ? noise_.sigma_rot : noise_.sigma_heading;
      const double y2 = noise_.sigma_yaw * noise_.sigma_yaw;
      rot_ = r * r;
      if (!started_)
        P_(0, 0) = rot_ + y2;
    }
  }
  void step(const StepNoise &q)
  {
    if (noise_.motion_noise == MotionNoise::Absolute)
      return;
    Eigen::Matrix2d F;
    F << 1, 0, q.d, 1;
    P_ = F * P_ * F.transpose();
    P_(0, 0) += q.var_rot;
    P_(1, 1) += q.var_t;
    xu_ = F * xu_;
    xv_ = F * xv_;
  }
  /* One residual (px) at depth z; returns the modelled motion variance of it (px^2). */
  double observe(const Eigen::Vector2d &r, double z)
  {
    started_ = true;
    const double var_px = noise_.sigma_px * noise_.sigma_px, y2 = noise_.sigma_yaw * noise_.sigma_yaw;
    double own = f_ * f_ * y2; // this reading's own yaw error
    if (noise_.motion_noise == MotionNoise::Absolute)
      own += f_ * f_ * (rot_ + noise_.sigma_odom * noise_.sigma_odom / (z * z)); // this pose's own error
    const Eigen::RowVector2d H(f_, f_ / z);
    const double S = H * P_ * H.transpose() + own + var_px;
    const double var_motion = S - var_px;
    const Eigen::Vector2d K = P_ * H.transpose() / S;
    const double nu = r.x() - H * xu_, nv = r.y() - H * xv_;
    chi2_ += (nu * nu + nv * nv) / S;
    xu_ += K * nu;
    xv_ += K * nv;
    P_ -= K * H * P_;
    return var_motion;
  }
  double chi2() const { return chi2_; }

private:
  const NoiseModel &noise_;
  double f_, rot_ = 0, chi2_ = 0;
  bool started_ = false;
  Eigen::Matrix2d P_;
  Eigen::Vector2d xu_ = Eigen::Vector2d::Zero(), xv_ = Eigen::Vector2d::Zero();
};

/* cMw of every row (the world's pose in each row's camera). */
struct CameraPoses {
  std::vector<Eigen::Isometry3d> cMw;
  CameraPoses(const YawRig &rig, const std::vector<MotionSample> &motion)
  {
    cMw.reserve(motion.size());
    for (const MotionSample &s : motion)
      cMw.push_back(toIsometry(wMc(rig, s)).inverse());
  }
};

/* The observed pixel of camera-frame point c_P and its Jacobian with respect to c_P (false behind the camera). */
bool projectPoint(const CameraModel &camera, const Eigen::Vector3d &c_P, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> &J)
{
  if (!(c_P.z() > 0))
    return false;
  const double iz = 1.0 / c_P.z();
  const Eigen::Vector2d m(c_P.x() * iz, c_P.y() * iz);
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d md = camera.distortNormalized(m, &Jd);
  uv = Eigen::Vector2d(camera.u0() + camera.kx() * md.x(), camera.v0() + camera.ky() * md.y());
  Eigen::Matrix<double, 2, 3> Jm;
  Jm << iz, 0, -m.x() * iz, 0, iz, -m.y() * iz;
  J = Eigen::DiagonalMatrix<double, 2>(camera.kx(), camera.ky()) * Jd * Jm;
  return true;
}

/* Residuals of the track's least-squares point (Gauss-Newton from w_P, equal weights): what its
   errors look like once no estimator's own error is in them. Empty when the fit fails. */
std::vector<Eigen::Vector2d> leastSquaresResiduals(const CameraModel &camera, const CameraPoses &poses,
                                                   const std::vector<std::pair<std::size_t, const Observation *>> &used,
                                                   Eigen::Vector3d w_P)
{
  constexpr int kIterations = 5;
  std::vector<Eigen::Vector2d> r(used.size());
  for (int it = 0; it <= kIterations; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (std::size_t u = 0; u < used.size(); ++u) {
      const std::size_t row = used[u].first;
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 3> J;
      if (!projectPoint(camera, poses.cMw[row] * w_P, uv, J))
        return {};
      r[u] = uv - Eigen::Vector2d(used[u].second->u, used[u].second->v);
      const Eigen::Matrix<double, 2, 3> Jw = J * poses.cMw[row].linear();
      H += Jw.transpose() * Jw;
      g += Jw.transpose() * r[u];
    }
    if (it == kIterations)
      break;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0))
      return {};
    w_P -= ldlt.solve(g);
  }
  return r;
}

/* One point against its track, with what the correlation correction needs: per observation used (in
   row order) the residual (px), the Jacobian of its pixel with respect to the point in the point's
   camera frame (distortion's own derivative left out), and whether the pixel noise dominates its
   variance (the motion's part under a quarter of it). */
struct TrackFit {
  TrackResidual summary;
  std::vector<Eigen::Vector2d> r; // the track's least-squares point's residuals (empty: that fit failed)
  std::vector<Eigen::Matrix<double, 2, 3>> J;
  std::vector<bool> pixel_dominated;
  bool pixels_only = true; // every observation's motion part under kPixelOnly of its pixel variance
  std::vector<long> rows; // the observations' motion-log rows
  double pixel_share_sum = 0; // sum over the observations of the pixels' share of their variance
};

/* Share of an observation's variance that per-increment motion noise (a drift) may have for its
   residual to say something about the tracker's own errors (their correlation). */
constexpr double kPixelDominated = 0.25;
/* Share of an observation's variance the motion may have for its residual to say what the tracker's
   errors look like over a whole track (TrackerErrorModel); per-increment motion noise may have none:
   a drift, however small, persists in the residuals as the tracker's slow part does (a residual
   check on odometry with 0.01 mm per increment found a "slow part" of 0.17 px that was the drift). */
constexpr double kPixelOnly = 0.05;

TrackFit fitOf(const CameraModel &camera, const std::vector<MotionSample> &motion, const CameraPoses &poses,
               const Track &track, const std::vector<bool> &outliers, const PointEstimate &point, const NoiseModel &noise)
{
  TrackFit fit;
  const long k = rowOfFrame(motion, point.frame);
  if (k < 0 || !point.c_P.allFinite())
    return fit;
  const std::size_t kr = static_cast<std::size_t>(k);
  const Eigen::Vector3d w_P = poses.cMw[kr].inverse() * point.c_P;
  // Observations used, by row; the walk starts at the point's row and goes back to the first.
  std::vector<std::pair<std::size_t, const Observation *>> used;
  for (std::size_t j = 0; j < track.observations.size(); ++j) {
    if (j < outliers.size() && outliers[j])
      continue;
    const long row = rowOfFrame(motion, track.observations[j].frame);
    if (row >= 0)
      used.emplace_back(static_cast<std::size_t>(row), &track.observations[j]);
  }
  if (used.size() < 2)
    return fit;
  std::sort(used.begin(), used.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
  fit.J.assign(used.size(), Eigen::Matrix<double, 2, 3>::Zero());
  for (const auto &u : used)
    fit.rows.push_back(static_cast<long>(u.first));
  fit.pixel_dominated.assign(used.size(), false);
  const double f = std::max(camera.kx(), camera.ky()), var_px = noise.sigma_px * noise.sigma_px;
  double chi2 = 0, sum2 = 0;
  // Two walks from the point's row: back to the first observation, on to the last (if any after it).
  for (const long dir : {-1L, 1L}) {
    const std::size_t end = dir < 0 ? std::min(kr, used.front().first) : std::max(kr, used.back().first);
    if (dir > 0 && end == kr)
      break;
    WalkChi2 walk(noise, f);
    walk.setSixDof(motion[kr].six_dof);
    for (std::size_t row = kr;; row = static_cast<std::size_t>(static_cast<long>(row) + dir)) {
      if (row != kr)
        walk.step(stepNoise(noise, motion[static_cast<std::size_t>(static_cast<long>(row) - dir)], motion[row]));
      for (std::size_t u = 0; u < used.size(); ++u) {
        if (used[u].first != row || (dir > 0 && row == kr))
          continue;
        const Eigen::Vector3d c_P = poses.cMw[row] * w_P;
        Eigen::Vector2d uv;
        Eigen::Matrix<double, 2, 3> J;
        if (!projectPoint(camera, c_P, uv, J)) {
          chi2 = std::numeric_limits<double>::infinity();
          continue;
        }
        const Eigen::Vector2d res = uv - Eigen::Vector2d(used[u].second->u, used[u].second->v);
        const double var_motion = walk.observe(res, c_P.z());
        sum2 += res.squaredNorm();
        // Pose errors per pose are white; per increment they drift, and would look like the tracker's.
        fit.pixel_dominated[u] = noise.motion_noise == MotionNoise::Absolute || var_motion < kPixelDominated * var_px;
        fit.pixels_only = fit.pixels_only && var_motion < kPixelOnly * var_px &&
                          (noise.motion_noise == MotionNoise::Absolute || !(var_motion > 0));
        fit.pixel_share_sum += var_px / (var_px + var_motion);
        fit.J[u] = J * poses.cMw[row].linear() * poses.cMw[kr].linear().transpose(); // d(pixel) / d(point in the point's camera)
      }
      if (row == end)
        break;
    }
    chi2 += walk.chi2();
  }
  if (std::isfinite(chi2))
    fit.r = leastSquaresResiduals(camera, poses, used, w_P);
  fit.summary.chi2 = chi2;
  fit.summary.dof = static_cast<int>(2 * used.size()) - 3;
  fit.summary.rms_px = std::sqrt(sum2 / static_cast<double>(used.size()));
  return fit;
}

/*
  The AR(1) correlation phi of the tracker's errors (NoiseModel::pixel_correlation) the tracks say:
  the phi under which the tracks' residuals, refitted with that model (generalised least squares,
  linearised at the least-squares point) and whitened (the first observation as it is, each next one
  as its innovation, (r_k - a r_k') / sqrt(1 - a^2), a = phi^gap), have no lag-one correlation, pooled
  over consecutive innovations whose pixel noise dominates, from tracks of at least kMinCorrelationObs
  observations. The raw residuals' correlation would say less: the fit absorbs the slow part of
  errors that persist. 0 with fewer than `min_tracks` such tracks; at most kMaxPixelCorrelation.
*/
constexpr std::size_t kMinCorrelationObs = 5;

/* The whitened GLS residuals under phi (see above): their lag-one products and squares added to num
   and den; returns their sum of squares (px^2; NaN when the fit fails). */
double whitenedCorrelation(const TrackFit &fit, double phi, double &num, double &den)
{
  const std::size_t n = fit.r.size();
  std::vector<Eigen::Vector2d> wr(n);
  std::vector<Eigen::Matrix<double, 2, 3>> wJ(n);
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const double a = k == 0 ? 0.0 : pixelCorrelationOver(phi, fit.rows[k] - fit.rows[k - 1]);
    const double scale = 1.0 / std::sqrt(1.0 - a * a);
    wr[k] = scale * (fit.r[k] - (k > 0 ? Eigen::Vector2d(a * fit.r[k - 1]) : Eigen::Vector2d::Zero()));
    wJ[k] = scale * (fit.J[k] - (k > 0 ? Eigen::Matrix<double, 2, 3>(a * fit.J[k - 1]) : Eigen::Matrix<double, 2, 3>::Zero()));
    H += wJ[k].transpose() * wJ[k];
    g += wJ[k].transpose() * wr[k];
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0))
    return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d delta = ldlt.solve(g);
  double sum = 0;
  for (std::size_t k = 0; k < n; ++k) {
    wr[k] -= wJ[k] * delta;
    sum += wr[k].squaredNorm();
  }
  for (std::size_t k = 1; k + 1 < n; ++k) // innovations only (the first has another variance)
    if (fit.pixel_dominated[k] && fit.pixel_dominated[k + 1]) {
      num += wr[k].dot(wr[k + 1]);
      den += 0.5 * (wr[k].squaredNorm() + wr[k + 1].squaredNorm());
    }
  return sum;
}

double trackerCorrelation(const std::vector<TrackFit> &fits, int min_tracks)
{
  std::vector<const TrackFit *> used;
  for (const TrackFit &fit : fits) {
    if (fit.r.size() < kMinCorrelationObs)
      continue;
    for (std::size_t u = 1; u + 1 < fit.r.size(); ++u)
      if (fit.pixel_dominated[u] && fit.pixel_dominated[u + 1]) {
        used.push_back(&fit);
        break;
      }
  }
  if (static_cast<int>(used.size()) < min_tracks)
    return 0.0;
  auto correlation = [&](double phi) {
    double num = 0, den = 0;
    for (const TrackFit *fit : used)
      whitenedCorrelation(*fit, phi, num, den);
    return den > 0 ? num / den : 0.0;
  };
  if (!(correlation(0.0) > 0))
    return 0.0;
  if (correlation(kMaxPixelCorrelation) > 0)
    return kMaxPixelCorrelation;
  double lo = 0, hi = kMaxPixelCorrelation; // correlation(lo) > 0 >= correlation(hi)
  for (int it = 0; it < 30; ++it) {
    const double mid = 0.5 * (lo + hi);
    (correlation(mid) > 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct TrackerErrors {
  double phi = 0;             // the AR(1) correlation
  double variance_factor = 0; // the whitened residuals' variance over sigma_px^2 (0: not estimated)
};

/* The variance factor of the tracks' whitened residuals under phi: the median over the tracks whose
   every observation's pixel noise dominates of chi2 / median(chi2 with 2N - 3 dof), chi2 their sum
   of squares over sigma_px^2 (as varianceFactor(): robust to tracks that are not one point). */
double whitenedVarianceFactor(const std::vector<const TrackFit *> &used, double phi, double sigma_px)
{
  std::vector<double> ratios;
  for (const TrackFit *fit : used) {
    if (std::find(fit->pixel_dominated.begin(), fit->pixel_dominated.end(), false) != fit->pixel_dominated.end())
      continue;
    double num = 0, den = 0;
    const double sum = whitenedCorrelation(*fit, phi, num, den);
    const int dof = 2 * static_cast<int>(fit->r.size()) - 3;
    if (std::isfinite(sum))
      ratios.push_back(sum / (sigma_px * sigma_px) / chiSquareMedian(dof));
  }
  if (ratios.empty())
    return 0.0;
  std::nth_element(ratios.begin(), ratios.begin() + static_cast<long>(ratios.size() / 2), ratios.end());
  return ratios[ratios.size() / 2];
}

TrackerErrors trackerErrors(const std::vector<TrackFit> &fits, int min_tracks, double sigma_px)
{
  TrackerErrors out;
  out.phi = trackerCorrelation(fits, min_tracks);
  std::vector<const TrackFit *> used;
  for (const TrackFit &fit : fits)
    if (fit.r.size() >= kMinCorrelationObs)
      used.push_back(&fit);
  if (out.phi > 0 && static_cast<int>(used.size()) >= min_tracks)
    out.variance_factor = whitenedVarianceFactor(used, out.phi, sigma_px);
  return out;
}

/*
  The tracker's errors as a white part plus a persistent part (bench_tracker_errors: a corner tracked
  from image to image errs by a little each time and drifts slowly), per pixel axis:
    cov(e_j, e_k) = sigma^2 [ w delta_jk + (1 - w) phi^|row_j - row_k| ],
  w the white share. (sigma^2, w, phi) by restricted maximum likelihood over the tracks (REML: the
  likelihood of the residuals once each track's own point is fitted, which absorbs nothing the model
  does not know it absorbs), on a grid of (w, phi), sigma^2 profiled. The tracks used: at least
  kMinCorrelationObs observations, the motion's modelled part under kPixelOnly of every one's
  variance, at most kMaxModelTracks (the first ones).
*/
constexpr int kMaxModelTracks = 150;
/* Longest track the model is measured on, or taken whole for a depth's floor (beyond, a thinned one:
   every k-th observation and the last, whose floor is then the larger, never the smaller): a dense
   n x n factorisation per track and model. */
constexpr std::size_t kMaxModelObs = 120;
constexpr double kPhiGrid[] = {0.5, 0.7, 0.8, 0.9, 0.95, 0.97, 0.98, 0.99, 0.995};
constexpr double kWhiteGrid[] = {0.0, 0.1, 0.25, 0.5, 0.75};

/* One axis' correlation matrix of the model at the track's rows. */
Eigen::MatrixXd errorCorrelation(const std::vector<long> &rows, const TrackerErrorModel &m)
{
  const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
  // (1 - w) phi^gap for every gap the track spans (rows increase along it), by products, not powers.
  std::vector<double> link(rows.empty() ? 1 : static_cast<std::size_t>(rows.back() - rows.front()) + 1, 0.0);
  for (std::size_t g = 1; g < link.size(); ++g)
    link[g] = g == 1 ? (1.0 - m.white) * pixelCorrelationOver(m.phi, 1) : link[g - 1] * m.phi;
  Eigen::MatrixXd C(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    C(j, j) = 1.0;
    for (Eigen::Index k = 0; k < j; ++k)
      C(j, k) = C(k, j) = link[static_cast<std::size_t>(rows[static_cast<std::size_t>(j)] - rows[static_cast<std::size_t>(k)])];
  }
  return C;
}

/* A track under the model's correlation (unit variance): log|C| of both axes, log|J' C^-1 J|, the
   REML quadratic r' P r, the information J' C^-1 J. False when not positive definite. */
struct TrackReml {
  double logdet_c = 0, logdet_info = 0, quadratic = 0;
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
};
bool trackReml(const TrackFit &fit, const TrackerErrorModel &m, TrackReml &out)
{
  const Eigen::LLT<Eigen::MatrixXd> llt(errorCorrelation(fit.rows, m));
  if (llt.info() != Eigen::Success)
    return false;
  const Eigen::Index n = static_cast<Eigen::Index>(fit.r.size());
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double rr = 0;
  for (int axis = 0; axis < 2; ++axis) {
    Eigen::MatrixXd X(n, 4); // the point's three columns, then the residuals
    for (Eigen::Index k = 0; k < n; ++k) {
      X.block<1, 3>(k, 0) = fit.J[static_cast<std::size_t>(k)].row(axis);
      X(k, 3) = fit.r[static_cast<std::size_t>(k)](axis);
    }
    llt.matrixL().solveInPlace(X); // L^-1 X: the C^-1 products are plain ones
    out.info += X.leftCols<3>().transpose() * X.leftCols<3>();
    b += X.leftCols<3>().transpose() * X.col(3);
    rr += X.col(3).squaredNorm();
    out.logdet_c += 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(out.info);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0))
    return false;
  out.logdet_info = ldlt.vectorD().array().log().sum();
  out.quadratic = rr - b.dot(ldlt.solve(b));
  return true;
}

/* The tracks' restricted log-likelihood under m (sigma^2 profiled, set in m); -inf when a track fails. */
double remlLogLikelihood(const std::vector<const TrackFit *> &used, TrackerErrorModel &m)
{
  double logdet = 0, quadratic = 0, dof = 0;
  for (const TrackFit *fit : used) {
    TrackReml t;
    if (!trackReml(*fit, m, t)) // a track whose point the model cannot fit counts for no model
      continue;
    logdet += t.logdet_c + t.logdet_info;
    quadratic += t.quadratic;
    dof += 2.0 * static_cast<double>(fit->r.size()) - 3.0;
  }
  if (!(dof > 0 && quadratic > 0))
    return -std::numeric_limits<double>::infinity();
  m.variance = quadratic / dof;
  return -0.5 * (logdet + dof * std::log(m.variance));
}

TrackerErrorModel trackerErrorModel(const std::vector<TrackFit> &fits, int min_tracks)
{
  std::vector<const TrackFit *> used;
  for (const TrackFit &fit : fits)
    if (fit.r.size() >= kMinCorrelationObs && fit.r.size() <= kMaxModelObs &&
        static_cast<int>(used.size()) < kMaxModelTracks && fit.pixels_only)
      used.push_back(&fit);
  TrackerErrorModel best;
  if (static_cast<int>(used.size()) < min_tracks)
    return best;
  double best_l = remlLogLikelihood(used, best); // white (w 1)
  for (double w : kWhiteGrid)
    for (double phi : kPhiGrid) {
      TrackerErrorModel m{w, phi, 0};
      const double l = remlLogLikelihood(used, m);
      if (l > best_l) {
        best_l = l;
        best = m;
      }
    }
  return best;
}

/* The track with at most kMaxModelObs of its observations, evenly, the last kept (a longer one). */
TrackFit thinned(const TrackFit &fit)
{
  const std::size_t n = fit.r.size();
  TrackFit out;
  const std::size_t step = (n + kMaxModelObs - 1) / kMaxModelObs;
  for (std::size_t k = (n - 1) % step; k < n; k += step) {
    out.r.push_back(fit.r[k]);
    out.J.push_back(fit.J[k]);
    out.rows.push_back(fit.rows[k]);
    out.pixel_dominated.push_back(fit.pixel_dominated[k]);
  }
  return out;
}

/* The depth variance of an ok track under the tracker's error model (px^2 in it), at the track's own
   noise (its REML quadratic over its degrees of freedom, shrunk toward the model's by kPoolDof, when
   it is larger beyond doubt); a track too short to show its own errors counts them as independent at
   the model's variance (the tracker lost it early: a hard corner). NaN when not computable. `bound`,
   when the track is long enough: the depth's 1-sigma under the model at its pooled noise (the
   Cramer-Rao bound with the poses known). */
constexpr double kPoolDof = 4;
constexpr double kOwnNoiseProbability = 0.95;
double depthVarianceModel(const TrackFit &whole, const TrackerErrorModel &m, double *bound)
{
  TrackFit thin;
  const TrackFit &fit = whole.r.size() > kMaxModelObs ? (thin = thinned(whole)) : whole;
  const bool known = fit.r.size() >= kMinCorrelationObs;
  const TrackerErrorModel use = known ? m : TrackerErrorModel{1.0, 0.0, m.variance};
  TrackReml t;
  if (fit.r.size() < 2 || !(m.variance > 0) || !trackReml(fit, use, t))
    return std::numeric_limits<double>::quiet_NaN();
  const double dof = 2.0 * static_cast<double>(fit.r.size()) - 3.0;
  // Its own noise only where its residuals show it larger (beyond the 95 % quantile): a floor of the
  // larger of two noisy estimates would raise half of a correct model's sigmas.
  const double chi2 = t.quadratic / m.variance;
  const bool larger = known && chi2 > chiSquareQuantile(static_cast<int>(dof), kOwnNoiseProbability);
  const double own = larger ? (chi2 + kPoolDof) / (dof + kPoolDof) : 1.0;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(t.info);
  const double var_z = m.variance * ldlt.solve(Eigen::Matrix3d::Identity())(2, 2);
  if (bound && known)
    *bound = std::sqrt(var_z);
  return own * var_z;
}

} // namespace

void relativePoseSigma(const NoiseModel &noise, const std::vector<MotionSample> &motion, std::size_t a, std::size_t b,
                       double &sigma_rot, double &sigma_trans)
{
  if (a >= motion.size() || b >= motion.size())
    throw Error("relativePoseSigma: row out of range");
  walkPoseNoise(noise, motion, b, a, [&](std::size_t row, double var_rot, double var_t) {
    if (row == a) {
      sigma_rot = std::sqrt(var_rot);
      sigma_trans = std::sqrt(var_t);
    }
  });
}

double chiSquareQuantile(int dof, double p)
{
  if (dof < 1 || !(p > 0.5 && p < 1))
    throw Error("chiSquareQuantile: needs dof >= 1 and p in (0.5, 1)");
  const double k = dof, a = 2.0 / (9.0 * k);
  const double c = 1 - a + normalQuantile(p) * std::sqrt(a);
  return k * c * c * c;
}

double chiSquareMedian(int dof)
{
  if (dof < 1)
    throw Error("chiSquareMedian: needs dof >= 1");
  const double k = dof, c = 1 - 2.0 / (9.0 * k);
  return k * c * c * c;
}

namespace pipeline_detail {

int varianceFactor(const std::vector<TrackResidual> &tracks, const std::vector<bool> &use, int min_tracks,
                   double &factor, double &sigma)
{
  std::vector<double> ratios;
  double inv_dof_sum = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i)
    if (tracks[i].dof >= 1 && (use.empty() || (i < use.size() && use[i]))) {
      ratios.push_back(tracks[i].chi2 / chiSquareMedian(tracks[i].dof));
      inv_dof_sum += 1.0 / tracks[i].dof;
    }
  const int used = static_cast<int>(ratios.size());
  factor = 1.0;
  sigma = 0;
  if (used >= min_tracks && used > 0) {
    const auto mid = ratios.begin() + static_cast<long>(ratios.size() / 2);
    std::nth_element(ratios.begin(), mid, ratios.end());
    factor = *mid;
    const double n = static_cast<double>(ratios.size());
    sigma = factor * std::sqrt(M_PI / 2 * 2 * inv_dof_sum / n / n);
  }
  return used;
}

ResidualCheckResult checkResidualsGated(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                        const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                        const ResidualCheckOptions &options, double gate_scale,
                                        std::vector<PointEstimate> &points)
{
  const std::vector<MotionSample> &motion = input.motion();
  const std::vector<Track> &tracks = input.tracks();
  options.validate();
  if (!(std::isfinite(gate_scale) && gate_scale >= 1))
    throw Error("residual check: the gate's scale must be finite and at least 1");
  if (points.size() != tracks.size())
    throw Error("residual check: " + std::to_string(points.size()) + " estimates for " +
                std::to_string(tracks.size()) + " tracks");
  ResidualCheckResult out;
  out.tracks.resize(tracks.size());
  const CameraPoses poses(rig, motion);
  const std::vector<bool> none;
  std::vector<TrackFit> fits(tracks.size());
  double share_sum = 0;
  std::size_t observations = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    if (!points[i].ok())
      continue;
    fits[i] = fitOf(camera, motion, poses, tracks[i], i < outliers.size() ? outliers[i] : none, points[i], noise);
    out.tracks[i] = fits[i].summary;
    if (out.tracks[i].dof >= 1) {
      share_sum += fits[i].pixel_share_sum;
      observations += fits[i].J.size();
    }
  }
  if (observations > 0)
    out.pixel_share = share_sum / static_cast<double>(observations);
  out.tracks_used = pipeline_detail::varianceFactor(out.tracks, {}, options.min_tracks, out.variance_factor,
                                                    out.variance_factor_sigma);
  const double factor = std::max(1.0, out.variance_factor);
  if (options.scale_sigma)
    out.sigma_scale = std::sqrt(factor);
  if (options.correlated) {
    // Measured on every ok track, those the gate will call inconsistent too: the gate weighs the
    // residuals as independent errors, so a track whose tracker's errors persist fails it as a
    // T-junction does; leaving them out made the model too small (Castle-simu: 0.81 within 2 sigma
    // instead of 0.94, RMSE 2.5 times the model's bound instead of 1.1).
    const TrackerErrors e = trackerErrors(fits, std::max(1, options.min_tracks / 2), noise.sigma_px);
    out.correlation = e.phi;
    out.correlated_variance_factor = e.variance_factor;
    out.error_model = trackerErrorModel(fits, std::max(1, options.min_tracks / 2));
  }
  // The tracker's errors as measured (white and persistent parts where the residuals show them whole;
  // else the AR(1) correlation at the pixel variance the whitened residuals say): no depth better
  // known than the pixels allow with them, at its track's own noise (a corner's texture sets it:
  // tracks differ by ten times).
  const TrackerErrorModel ar1{0.0, out.correlation,
                              std::max(factor, out.correlated_variance_factor) * noise.sigma_px * noise.sigma_px};
  const TrackerErrorModel &floor = out.error_model.variance > 0 ? out.error_model : ar1;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const TrackResidual &t = out.tracks[i];
    if (!points[i].ok())
      continue;
    const double gate_factor = options.gate_at_model ? 1.0 : factor;
    if (t.dof >= 1 && !(t.chi2 <= gate_scale * gate_factor * chiSquareQuantile(t.dof, options.gate_probability))) {
      points[i].status = Status::Inconsistent;
      ++out.inconsistent;
      continue;
    }
    points[i].c_cov *= out.sigma_scale * out.sigma_scale;
    if (floor.variance > 0 && floor.phi > 0) {
      const double var_z = depthVarianceModel(fits[i], floor, &out.tracks[i].sigma_z_bound);
      if (std::isfinite(var_z) && var_z > points[i].c_cov(2, 2)) {
        points[i].c_cov *= var_z / points[i].c_cov(2, 2);
        ++out.correlation_scaled;
      }
    }
  }
  return out;
}

} // namespace pipeline_detail

ResidualCheckResult checkResiduals(const CameraModel &camera, const YawRig &rig,
                                   const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                   const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                   const ResidualCheckOptions &options, std::vector<PointEstimate> &points)
{
  return pipeline_detail::checkResidualsGated(camera, rig, validateInputs(motion, tracks), outliers, noise, options, 1.0,
                                              points);
}

ResidualCheckResult checkResiduals(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                   const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                   const ResidualCheckOptions &options, std::vector<PointEstimate> &points)
{
  return pipeline_detail::checkResidualsGated(camera, rig, input, outliers, noise, options, 1.0, points);
}

} // namespace yawdepth
