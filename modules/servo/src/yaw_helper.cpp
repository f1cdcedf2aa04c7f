#include <yawdepth/servo/yaw_helper.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <yawdepth/error.h>

namespace yawdepth {

void YawHelperOptions::validate() const
{
  if (!(std::isfinite(max_rate) && max_rate > 0))
    throw Error("yaw helper: max_rate must be finite and positive");
  if (!(std::isfinite(horizon) && horizon > 0))
    throw Error("yaw helper: horizon must be finite and positive");
  if (candidates < 3 || candidates % 2 == 0)
    throw Error("yaw helper: candidates must be odd and at least 3");
  if (!(std::isfinite(gain) && gain > 0))
    throw Error("yaw helper: gain must be finite and positive");
  if (!(std::isfinite(centring_weight) && centring_weight >= 0))
    throw Error("yaw helper: centring_weight must be finite and non-negative");
  if (!(std::isfinite(margin_px) && margin_px >= 0))
    throw Error("yaw helper: margin_px must be finite and non-negative");
  if (!(std::isfinite(min_yaw) && std::isfinite(max_yaw) && min_yaw < max_yaw))
    throw Error("yaw helper: need min_yaw < max_yaw");
  if (!std::isnan(home_yaw) && !(std::isfinite(home_yaw) && home_yaw >= min_yaw && home_yaw <= max_yaw))
    throw Error("yaw helper: home_yaw must be NaN (none) or within [min_yaw, max_yaw]");
}

double parallaxRate(const CameraModel &camera, const Eigen::Vector3d &c_T, const std::vector<YawHelperFeature> &features)
{
  double sum = 0, wsum = 0;
  for (const YawHelperFeature &f : features) {
    if (!(f.Z > 0) || !(f.weight >= 0))
      continue;
    const double fx = camera.kx() * (f.x * c_T.z() - c_T.x()) / f.Z;
    const double fy = camera.ky() * (f.y * c_T.z() - c_T.y()) / f.Z;
    sum += f.weight * std::hypot(fx, fy);
    wsum += f.weight;
  }
  return wsum > 0 ? sum / wsum : 0.0;
}

namespace {

struct Candidate {
  double yaw = 0;
  double parallax = 0;
  double centring = 0; // squared relative centroid offset
  bool visible = false;
};

Candidate evaluate(const CameraModel &camera, const YawRig &rig, double yaw, double rate, const Eigen::Vector3d &v_velocity,
                   const std::vector<Eigen::Vector3d> &v_points, const std::vector<YawHelperFeature> &features,
                   double margin_px)
{
  Candidate c;
  c.yaw = yaw;
  c.visible = true;
  const Eigen::Matrix3d cRv = rig.vRc(yaw).transpose();
  std::vector<YawHelperFeature> seen = features;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  const double w = camera.width(), h = camera.height();
  for (std::size_t i = 0; i < v_points.size(); ++i) {
    const Eigen::Vector3d c_P = rig.cameraPoint(yaw, v_points[i]);
    if (!(c_P.z() > 1e-9)) {
      c.visible = false;
      seen[i].Z = 1.0; // keep a finite score
      continue;
    }
    seen[i].x = c_P.x() / c_P.z();
    seen[i].y = c_P.y() / c_P.z();
    seen[i].Z = c_P.z();
    const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(seen[i].x, seen[i].y));
    if (!(uv.x() >= margin_px && uv.x() <= w - 1 - margin_px && uv.y() >= margin_px && uv.y() <= h - 1 - margin_px))
      c.visible = false;
    centroid += uv;
  }
  centroid /= static_cast<double>(v_points.size());
  const double ox = (centroid.x() - camera.u0()) / (0.5 * w), oy = (centroid.y() - camera.v0()) / (0.5 * h);
  c.centring = ox * ox + oy * oy;
  // Panning at `rate` moves the optical centre (offset t0 from the yaw axis): rate * (e_y x Ry(yaw) t0).
  const Eigen::Vector3d off = rotY(yaw) * rig.cameraOffset();
  const Eigen::Vector3d v_cam = v_velocity + rate * Eigen::Vector3d(off.z(), 0, -off.x());
  c.parallax = parallaxRate(camera, cRv * v_cam, seen);
  return c;
}

} // namespace

YawRecommendation recommendYawRate(const CameraModel &camera, const YawRig &rig, double yaw,
                                   const Eigen::Vector3d &v_velocity, const std::vector<YawHelperFeature> &features,
                                   const YawHelperOptions &options)
{
  options.validate();
  if (camera.width() == 0 || camera.height() == 0)
    throw Error("yaw helper: the camera needs an image size");
  if (features.empty())
    throw Error("yaw helper: no features");
  if (!std::isfinite(yaw) || !v_velocity.allFinite())
    throw Error("yaw helper: yaw and velocity must be finite");
  std::vector<Eigen::Vector3d> v_points;
  v_points.reserve(features.size());
  for (const YawHelperFeature &f : features) {
    if (!(std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.Z) && f.Z > 0 && std::isfinite(f.weight) &&
          f.weight >= 0))
      throw Error("yaw helper: each feature needs finite x, y, a positive depth and a non-negative weight");
    v_points.emplace_back(rig.visionPoint(yaw, Eigen::Vector3d(f.x * f.Z, f.y * f.Z, f.Z)));
  }

  const double reach = options.max_rate * options.horizon;
  const double lo = std::max(options.min_yaw, yaw - reach), hi = std::min(options.max_yaw, yaw + reach);
  const bool measured = std::all_of(features.begin(), features.end(), [](const YawHelperFeature &f) { return f.weight == 0; });
  if (measured && std::isfinite(options.home_yaw)) { // nothing left to learn here: back to the home view
    YawRecommendation r;
    r.target_yaw = std::clamp(options.home_yaw, lo, hi);
    r.rate = std::clamp(options.gain * (r.target_yaw - yaw), -options.max_rate, options.max_rate);
    const Candidate now = evaluate(camera, rig, yaw, 0.0, v_velocity, v_points, features, options.margin_px);
    r.parallax_now = r.parallax_target = now.parallax;
    r.visible_now = now.visible;
    return r;
  }
  std::vector<Candidate> cands;
  const Candidate now = evaluate(camera, rig, yaw, 0.0, v_velocity, v_points, features, options.margin_px);
  for (int k = 0; k < options.candidates; ++k) {
    const double t = lo + (hi - lo) * k / (options.candidates - 1.0);
    const double rate = std::clamp(options.gain * (t - yaw), -options.max_rate, options.max_rate);
    cands.push_back(evaluate(camera, rig, t, rate, v_velocity, v_points, features, options.margin_px));
  }
  double pmax = 0;
  bool any_visible = false;
  for (const Candidate &c : cands)
    if (c.visible) {
      pmax = std::max(pmax, c.parallax);
      any_visible = true;
    }
  // Score; with no admissible candidate, only recentre the features.
  const Candidate *best = nullptr;
  double best_score = -std::numeric_limits<double>::infinity();
  for (const Candidate &c : cands) {
    if (any_visible && !c.visible)
      continue;
    const double p = (any_visible && pmax > 0) ? c.parallax / pmax : 0.0;
    // Ties (e.g. no translation) go to the smallest change of yaw.
    const double score = p - options.centring_weight * c.centring - 1e-9 * std::abs(c.yaw - yaw);
    if (score > best_score) {
      best_score = score;
      best = &c;
    }
  }
  YawRecommendation r;
  r.target_yaw = best ? best->yaw : yaw;
  r.rate = std::clamp(options.gain * (r.target_yaw - yaw), -options.max_rate, options.max_rate);
  r.parallax_now = now.parallax;
  r.parallax_target = best ? best->parallax : now.parallax;
  r.visible_now = now.visible;
  r.feasible = any_visible;
  return r;
}

} // namespace yawdepth
