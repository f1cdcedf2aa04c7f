#include <yawdepth/pipeline/residual_check.h>

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
    const MotionSample &p = motion[static_cast<std::size_t>(i - step)], &c = motion[static_cast<std::size_t>(i)];
    const double d = (c.position() - p.position()).norm(), theta = incrementAngle(p, c);
    const double odom = noise.odom_per_metre * d;
    var_t += noise.sigma_odom * noise.sigma_odom + odom * odom + var_rot * d * d; // the rotation error so far turns this step
    const double per_rad = noise.rot_per_radian * theta, per_m = noise.rot_per_metre * d;
    var_rot += r * r + per_rad * per_rad + per_m * per_m;
    at(static_cast<std::size_t>(i), var_rot + yaw2, var_t);
    if (static_cast<std::size_t>(i) == to)
      break;
  }
}

/* cMw of every row, as Eigen (rotation, translation). */
struct CameraPoses {
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> t;
  CameraPoses(const YawRig &rig, const std::vector<MotionSample> &motion)
  {
    R.reserve(motion.size());
    t.reserve(motion.size());
    for (const MotionSample &s : motion) {
      const vpHomogeneousMatrix cMw = wMc(rig, s).inverse();
      Eigen::Matrix3d r;
      Eigen::Vector3d v;
      for (unsigned i = 0; i < 3; ++i) {
        for (unsigned j = 0; j < 3; ++j)
          r(i, j) = cMw[i][j];
        v[i] = cMw[i][3];
      }
      R.push_back(r);
      t.push_back(v);
    }
  }
};

TrackResidual residualOf(const CameraModel &camera, const std::vector<MotionSample> &motion, const CameraPoses &poses,
                         const Track &track, const std::vector<bool> &outliers, const PointEstimate &point,
                         const NoiseModel &noise)
{
  TrackResidual out;
  const long k = rowOfFrame(motion, point.frame);
  if (k < 0 || !point.c_P.allFinite())
    return out;
  const std::size_t kr = static_cast<std::size_t>(k);
  const Eigen::Vector3d w_P = poses.R[kr].transpose() * (point.c_P - poses.t[kr]);
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
    return out;
  std::sort(used.begin(), used.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
  const double f = std::max(camera.kx(), camera.ky());
  double chi2 = 0, sum2 = 0;
  const auto visit = [&](std::size_t row, double var_rot, double var_t) {
    for (std::size_t u = 0; u < used.size(); ++u) {
      if (used[u].first != row)
        continue;
      const Eigen::Vector3d c_P = poses.R[row] * w_P + poses.t[row];
      if (!(c_P.z() > 0)) {
        chi2 = std::numeric_limits<double>::infinity();
        continue;
      }
      const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(c_P.x() / c_P.z(), c_P.y() / c_P.z()));
      const double r2 = (uv - Eigen::Vector2d(used[u].second->u, used[u].second->v)).squaredNorm();
      const double var = noise.sigma_px * noise.sigma_px + f * f * (var_rot + var_t / (c_P.z() * c_P.z()));
      chi2 += r2 / var;
      sum2 += r2;
    }
  };
  walkPoseNoise(noise, motion, kr, std::min(kr, used.front().first), visit);
  if (used.back().first > kr) // observations after the point's frame (not for the methods here, but allowed)
    walkPoseNoise(noise, motion, kr, used.back().first, [&](std::size_t row, double vr, double vt) {
      if (row != kr)
        visit(row, vr, vt);
    });
  out.chi2 = chi2;
  out.dof = static_cast<int>(2 * used.size()) - 3;
  out.rms_px = std::sqrt(sum2 / static_cast<double>(used.size()));
  return out;
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

TrackResidual trackResidual(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                            const Track &track, const std::vector<bool> &outliers, const PointEstimate &point,
                            const NoiseModel &noise)
{
  return residualOf(camera, motion, CameraPoses(rig, motion), track, outliers, point, noise);
}

ResidualCheckResult checkResiduals(const CameraModel &camera, const YawRig &rig,
                                   const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                   const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                   const ResidualCheckOptions &options, std::vector<PointEstimate> &points)
{
  options.validate();
  if (points.size() != tracks.size())
    throw Error("residual check: " + std::to_string(points.size()) + " estimates for " +
                std::to_string(tracks.size()) + " tracks");
  ResidualCheckResult out;
  out.tracks.resize(tracks.size());
  const CameraPoses poses(rig, motion);
  const std::vector<bool> none;
  std::vector<double> ratios;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    if (!points[i].ok())
      continue;
    out.tracks[i] = residualOf(camera, motion, poses, tracks[i], i < outliers.size() ? outliers[i] : none, points[i],
                               noise);
    if (out.tracks[i].dof >= 1) {
      ratios.push_back(out.tracks[i].chi2 / chiSquareMedian(out.tracks[i].dof));
      ++out.tracks_used;
    }
  }
  if (out.tracks_used >= options.min_tracks) {
    const auto mid = ratios.begin() + static_cast<long>(ratios.size() / 2);
    std::nth_element(ratios.begin(), mid, ratios.end());
    out.variance_factor = *mid;
  }
  const double factor = std::max(1.0, out.variance_factor);
  if (options.scale_sigma)
    out.sigma_scale = std::sqrt(factor);
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const TrackResidual &t = out.tracks[i];
    if (!points[i].ok())
      continue;
    if (t.dof >= 1 && !(t.chi2 <= factor * chiSquareQuantile(t.dof, options.gate_probability))) {
      points[i].status = Status::Inconsistent;
      ++out.inconsistent;
      continue;
    }
    points[i].c_cov *= out.sigma_scale * out.sigma_scale;
  }
  return out;
}

} // namespace yawdepth
