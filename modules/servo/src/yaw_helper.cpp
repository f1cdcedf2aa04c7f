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
  if (!(std::isfinite(lookahead) && lookahead > 0 && lookahead <= 60))
    throw Error("yaw helper: lookahead must be in (0, 60] s");
  if (steps < 1 || steps > 1000)
    throw Error("yaw helper: steps must be in [1, 1000]");
  if (!(std::isfinite(sigma_px) && sigma_px > 0))
    throw Error("yaw helper: sigma_px must be finite and positive");
  if (!(std::isfinite(frame_rate) && frame_rate > 0))
    throw Error("yaw helper: frame_rate must be finite and positive");
  if (!(std::isfinite(switch_margin) && switch_margin >= 0))
    throw Error("yaw helper: switch_margin must be finite and non-negative");
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

/* The rate law: toward `target` at gain x the error, within +-max_rate. */
double rateToward(const YawHelperOptions &o, double yaw, double target)
{
  return std::clamp(o.gain * (target - yaw), -o.max_rate, o.max_rate);
}

struct Candidate {
  double yaw = 0;
  double parallax = 0;    // translational flow now, panning toward the candidate (px/s)
  double information = 0; // J: the D-optimal information gain over the lookahead
  double centring = 0;    // squared relative centroid offset (at most 1), averaged over the lookahead
  bool keeps = true;      // every weighted feature now in view stays in view at the candidate yaw
};

/* The largest normalised radius up to which the lens model maps outward (its radial derivative stays
   positive): beyond it a polynomial model folds back, and a point far outside the field of view would
   project inside the image. Scanned along the x axis, to 10 (84 degrees off axis). */
double validRadius(const CameraModel &camera)
{
  constexpr double kStep = 0.01, kMax = 10.0;
  for (double r = kStep; r <= kMax; r += kStep) {
    Eigen::Matrix2d J;
    camera.distortNormalized(Eigen::Vector2d(r, 0.0), &J);
    if (!(J(0, 0) > 0))
      return r - kStep;
  }
  return kMax;
}

bool inImage(const CameraModel &camera, double valid_radius, const Eigen::Vector3d &c_P, double margin_px,
             Eigen::Vector2d *uv)
{
  if (!(c_P.z() > 1e-9))
    return false;
  const Eigen::Vector2d m(c_P.x() / c_P.z(), c_P.y() / c_P.z());
  if (!(m.squaredNorm() < valid_radius * valid_radius))
    return false;
  *uv = camera.project(m);
  return uv->x() >= margin_px && uv->x() <= camera.width() - 1 - margin_px && uv->y() >= margin_px &&
         uv->y() <= camera.height() - 1 - margin_px;
}

/* The camera centre's velocity in the vision frame when panning at `rate`: the robot's, plus the
   lever arm's rate * (e_y x Ry(yaw) t0). */
Eigen::Vector3d centreVelocity(const YawRig &rig, double yaw, double rate, const Eigen::Vector3d &v_velocity)
{
  const Eigen::Vector3d off = rotY(yaw) * rig.cameraOffset();
  return v_velocity + rate * Eigen::Vector3d(off.z(), 0, -off.x());
}

struct Scene {
  const CameraModel &camera;
  const YawRig &rig;
  double yaw;                              // now
  Eigen::Vector3d v_velocity;              // of the vision frame's origin
  std::vector<Eigen::Vector3d> v_points;   // the features, vision frame now
  std::vector<double> weights;             // w_i
  std::vector<double> prior;               // sigma_r,i^2
  std::vector<bool> in_view_now;           // inside the image minus the margin now
  Eigen::Vector3d v_C0;                    // the camera centre now, vision frame
  double valid_radius;                     // validRadius(camera)
  const std::vector<YawHelperFeature> &features;
};

Candidate evaluate(const Scene &sc, double target, const YawHelperOptions &o)
{
  const CameraModel &camera = sc.camera;
  Candidate c;
  c.yaw = target;
  // Now, at the candidate yaw: does every weighted feature now in view stay in view?
  for (std::size_t i = 0; i < sc.v_points.size(); ++i) {
    Eigen::Vector2d uv;
    if (sc.weights[i] > 0 && sc.in_view_now[i] && !inImage(camera, sc.valid_radius, sc.rig.cameraPoint(target, sc.v_points[i]), o.margin_px, &uv))
      c.keeps = false;
  }
  const double rate0 = rateToward(o, sc.yaw, target);
  c.parallax = parallaxRate(camera, sc.rig.vRc(sc.yaw).transpose() * centreVelocity(sc.rig, sc.yaw, rate0, sc.v_velocity),
                            sc.features);
  // Played forward: the pan under the recommended rate law, the robot at its velocity.
  const double dt = o.lookahead / o.steps;
  const double frames = o.frame_rate * dt / (o.sigma_px * o.sigma_px);
  std::vector<double> info(sc.v_points.size(), 0.0);
  double yaw = sc.yaw;
  for (int s = 1; s <= o.steps; ++s) {
    const double rate = rateToward(o, yaw, target);
    yaw = std::clamp(yaw + rate * dt, o.min_yaw, o.max_yaw);
    const Eigen::Vector3d v_origin = sc.v_velocity * (s * dt);
    const Eigen::Matrix3d cRv = sc.rig.vRc(yaw).transpose();
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    int counted = 0;
    for (std::size_t i = 0; i < sc.v_points.size(); ++i) {
      const Eigen::Vector3d c_P = sc.rig.cameraPoint(yaw, sc.v_points[i] - v_origin);
      const Eigen::Vector2d m(c_P.x() / c_P.z(), c_P.y() / c_P.z());
      if (c_P.z() > 1e-9 && m.squaredNorm() < sc.valid_radius * sc.valid_radius) { // not folded by the lens model
        centroid += camera.project(m);
        ++counted;
      }
      Eigen::Vector2d uv;
      if (!(sc.weights[i] > 0) || !inImage(camera, sc.valid_radius, c_P, o.margin_px, &uv))
        continue;
      // d m / d log Z along the current bearing: the point moves by (P - C0) per unit log-depth.
      const Eigen::Vector3d d = cRv * (sc.v_points[i] - sc.v_C0);
      const double iz = 1.0 / c_P.z();
      const double du = camera.kx() * iz * (d.x() - c_P.x() * iz * d.z());
      const double dv = camera.ky() * iz * (d.y() - c_P.y() * iz * d.z());
      info[i] += frames * (du * du + dv * dv);
    }
    // The recentring term: the features' centroid offset, averaged over the lookahead.
    double offset2 = 1.0; // none in front of the camera: as bad as the image border
    if (counted > 0) {
      centroid /= counted;
      const double ox = (centroid.x() - camera.u0()) / (0.5 * camera.width());
      const double oy = (centroid.y() - camera.v0()) / (0.5 * camera.height());
      offset2 = std::min(1.0, ox * ox + oy * oy);
    }
    c.centring += offset2 / o.steps;
  }
  for (std::size_t i = 0; i < info.size(); ++i)
    if (sc.weights[i] > 0)
      c.information += sc.weights[i] * std::log1p(sc.prior[i] * info[i]);
  return c;
}

/* The features as the candidates see them (each checked): vision-frame points, weights, priors and
   whether each is in view now. */
Scene makeScene(const CameraModel &camera, const YawRig &rig, double yaw, const Eigen::Vector3d &v_velocity,
                const std::vector<YawHelperFeature> &features, const YawHelperOptions &options)
{
  Scene sc{camera, rig, yaw, v_velocity, {}, {}, {}, {}, rig.visionPoint(yaw, Eigen::Vector3d::Zero()), validRadius(camera),
           features};
  for (const YawHelperFeature &f : features) {
    if (!(std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.Z) && f.Z > 0 && std::isfinite(f.weight) &&
          f.weight >= 0))
      throw Error("yaw helper: each feature needs finite x, y, a positive depth and a non-negative weight");
    if (!(std::isnan(f.sigma_rel) || (std::isfinite(f.sigma_rel) && f.sigma_rel > 0)))
      throw Error("yaw helper: a feature's sigma_rel must be NaN (unknown) or finite and positive");
    const Eigen::Vector3d c_P(f.x * f.Z, f.y * f.Z, f.Z);
    sc.v_points.emplace_back(rig.visionPoint(yaw, c_P));
    sc.weights.push_back(f.weight);
    const double sr = std::isnan(f.sigma_rel) ? 1.0 : f.sigma_rel;
    sc.prior.push_back(sr * sr);
    Eigen::Vector2d uv;
    sc.in_view_now.push_back(inImage(camera, sc.valid_radius, c_P, options.margin_px, &uv));
  }
  return sc;
}

// Below this, nothing is learnt (the round-off of a camera that does not translate): recentre only.
constexpr double kNoInformation = 1e-6;

/* The largest information among the candidates that keep the features in view (all when none does). */
double maxInformation(const std::vector<Candidate> &cands, bool any_keeps)
{
  double jmax = 0;
  for (const Candidate &c : cands)
    if (c.keeps || !any_keeps)
      jmax = std::max(jmax, c.information);
  return jmax;
}

/* A candidate's score: its information relative to jmax less the centring penalty. */
double candidateScore(const Candidate &c, double jmax, const YawHelperOptions &o)
{
  if (jmax > kNoInformation)
    return c.information / jmax - o.centring_weight * c.centring;
  return -c.centring; // nothing to learn: recentre the features
}

/* The best-scoring candidate among those that keep the features in view (all when none does); with
   hysteresis, the current yaw's (cands.front()) unless the best is clearly better. */
const Candidate &bestCandidate(const std::vector<Candidate> &cands, double yaw, double jmax, bool any_keeps,
                               const YawHelperOptions &o)
{
  const Candidate *best = nullptr;
  double best_score = -std::numeric_limits<double>::infinity();
  for (const Candidate &c : cands) {
    if (any_keeps && !c.keeps)
      continue;
    // Ties (e.g. no translation) go to the smallest change of yaw.
    const double sc_c = candidateScore(c, jmax, o) - 1e-9 * std::abs(c.yaw - yaw);
    if (sc_c > best_score) {
      best_score = sc_c;
      best = &c;
    }
  }
  const Candidate &now = cands.front();
  if (best != &now && (now.keeps || !any_keeps) && candidateScore(now, jmax, o) >= best_score - o.switch_margin)
    best = &now;
  return *best;
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
  const Scene sc = makeScene(camera, rig, yaw, v_velocity, features, options);

  const double reach = options.max_rate * options.horizon;
  const double lo = std::max(options.min_yaw, yaw - reach), hi = std::min(options.max_yaw, yaw + reach);
  const double hold_yaw = std::clamp(yaw, options.min_yaw, options.max_yaw);
  const Candidate now = evaluate(sc, hold_yaw, options);
  YawRecommendation r;
  r.parallax_now = parallaxRate(camera, rig.vRc(yaw).transpose() * v_velocity, features);
  r.information_now = now.information;
  r.visible_now = true;
  for (std::size_t i = 0; i < features.size(); ++i)
    r.visible_now = r.visible_now && sc.in_view_now[i];

  const bool measured = std::all_of(features.begin(), features.end(), [](const YawHelperFeature &f) { return f.weight == 0; });
  if (measured && std::isfinite(options.home_yaw)) { // nothing left to learn here: back to the home view
    r.target_yaw = std::clamp(options.home_yaw, lo, hi);
    r.rate = rateToward(options, yaw, r.target_yaw);
    r.parallax_target = r.parallax_now;
    r.information_target = now.information;
    r.mode = YawMode::Home;
    return r;
  }
  std::vector<Candidate> cands{now};
  for (int k = 0; k < options.candidates; ++k)
    cands.push_back(evaluate(sc, lo + (hi - lo) * k / (options.candidates - 1.0), options));
  const bool any_keeps = std::any_of(cands.begin(), cands.end(), [](const Candidate &c) { return c.keeps; });
  const double jmax = maxInformation(cands, any_keeps);
  const Candidate &best = bestCandidate(cands, yaw, jmax, any_keeps, options);
  r.target_yaw = best.yaw;
  r.rate = rateToward(options, yaw, r.target_yaw);
  r.parallax_target = best.parallax;
  r.information_target = best.information;
  r.feasible = any_keeps;
  r.mode = jmax > kNoInformation ? YawMode::Measure : YawMode::Recentre;
  return r;
}

void YawExploreOptions::validate() const
{
  if (!(std::isfinite(bin) && bin >= 1e-4 && bin <= 0.2))
    throw Error("yaw helper: the exploration bin must be within [1e-4, 0.2] rad");
  if (!(std::isfinite(stale_time) && stale_time > 0))
    throw Error("yaw helper: stale_time must be finite and positive");
  if (!(std::isfinite(min_stale) && min_stale >= 0 && min_stale <= 1))
    throw Error("yaw helper: min_stale must be within [0, 1]");
  if (!(std::isfinite(parallax_floor) && parallax_floor >= 0 && parallax_floor <= 1))
    throw Error("yaw helper: parallax_floor must be within [0, 1]");
}

namespace {

/* Bearing about the pan axis (the vision frame's y) of a direction: 0 straight ahead (+z), positive
   toward +x (the yaw's sense: rotY(theta) adds theta to it). */
double bearing(const Eigen::Vector3d &d) { return std::atan2(d.x(), d.z()); }

} // namespace

YawHelper::YawHelper(const CameraModel &camera, const YawRig &rig, const YawHelperOptions &options,
                     const YawExploreOptions &explore)
    : camera_(camera), rig_(rig), options_(options), explore_(explore)
{
  options_.validate();
  explore_.validate();
  if (camera_.width() == 0 || camera_.height() == 0)
    throw Error("yaw helper: the camera needs an image size");
  Eigen::Vector2d left, right;
  if (!camera_.undistort(Eigen::Vector2d(0.0, camera_.v0()), left) ||
      !camera_.undistort(Eigen::Vector2d(camera_.width() - 1.0, camera_.v0()), right))
    throw Error("yaw helper: the camera model cannot undistort its image's left and right edges");
  const Eigen::Matrix3d v_R0 = rig_.vRc(0.0);
  fov_left_ = bearing(v_R0 * Eigen::Vector3d(left.x(), 0.0, 1.0));
  fov_right_ = bearing(v_R0 * Eigen::Vector3d(right.x(), 0.0, 1.0));
  if (!(fov_right_ > fov_left_))
    throw Error("yaw helper: the camera's field of view does not span any bearing about the pan axis");
  bin_origin_ = options_.min_yaw + fov_left_;
  const double span = options_.max_yaw + fov_right_ - bin_origin_;
  // A pan joint turns at most a few times around; the memory and each call's scan are bounded.
  constexpr double kMaxBins = 1e5;
  if (!(options_.max_yaw - options_.min_yaw <= 4 * M_PI) || !(span / explore_.bin <= kMaxBins))
    throw Error("yaw helper: the pan range must be at most 4 pi and hold at most 100000 exploration bins");
  last_seen_.assign(static_cast<std::size_t>(std::ceil(span / explore_.bin)) + 1,
                    -std::numeric_limits<double>::infinity());
}

void YawHelper::reset()
{
  std::fill(last_seen_.begin(), last_seen_.end(), -std::numeric_limits<double>::infinity());
  last_t_ = -std::numeric_limits<double>::infinity();
}

std::pair<int, int> YawHelper::binsInView(double yaw) const
{
  const int n = static_cast<int>(last_seen_.size());
  const int lo = static_cast<int>(std::ceil((yaw + fov_left_ - bin_origin_) / explore_.bin));
  const int hi = static_cast<int>(std::floor((yaw + fov_right_ - bin_origin_) / explore_.bin));
  return {std::clamp(lo, 0, n - 1), std::clamp(hi, 0, n - 1)};
}

double YawHelper::staleness(double t, double yaw) const
{
  const std::pair<int, int> b = binsInView(std::clamp(yaw, options_.min_yaw, options_.max_yaw));
  double sum = 0;
  for (int i = b.first; i <= b.second; ++i)
    sum += -std::expm1(-(t - last_seen_[static_cast<std::size_t>(i)]) / explore_.stale_time);
  return sum / (b.second - b.first + 1);
}

YawRecommendation YawHelper::recommend(double t, double yaw, const Eigen::Vector3d &v_velocity,
                                       const std::vector<YawHelperFeature> &features)
{
  if (!std::isfinite(t) || !(t >= last_t_))
    throw Error("yaw helper: times must be finite and not decrease");
  if (!std::isfinite(yaw) || !v_velocity.allFinite())
    throw Error("yaw helper: yaw and velocity must be finite");
  last_t_ = t;
  const std::pair<int, int> seen = binsInView(std::clamp(yaw, options_.min_yaw, options_.max_yaw));
  for (int i = seen.first; i <= seen.second; ++i)
    last_seen_[static_cast<std::size_t>(i)] = t;

  YawRecommendation r;
  r.target_yaw = yaw;
  r.mode = YawMode::Recentre;
  if (!features.empty()) {
    YawHelperOptions o = options_;
    o.home_yaw = std::numeric_limits<double>::quiet_NaN(); // home is decided below, after exploring
    r = recommendYawRate(camera_, rig_, yaw, v_velocity, features, o);
    if (r.mode == YawMode::Measure)
      return r;
  }
  if (explore_.enabled) {
    // The view with the most stale parallax within the joint's range; among about equal ones, the nearest.
    constexpr double kNearness = 0.05; // value traded per pi of pan travel
    const Eigen::Vector3d v_axis0 = rig_.vRc(0.0) * Eigen::Vector3d::UnitZ();
    const double axis0 = bearing(v_axis0);
    const double speed = std::hypot(v_velocity.x(), v_velocity.z());
    const double heading = speed > 1e-9 ? std::atan2(v_velocity.x(), v_velocity.z()) : 0.0;
    double best = -std::numeric_limits<double>::infinity(), best_yaw = yaw, best_stale = 0;
    const int n = static_cast<int>(std::ceil((options_.max_yaw - options_.min_yaw) / explore_.bin));
    for (int k = 0; k <= n; ++k) {
      const double cand = std::min(options_.max_yaw, options_.min_yaw + k * explore_.bin);
      const double stale = staleness(t, cand);
      // What a new feature seen there is worth: its parallax, the sine of its angle to the motion
      // (uniform when the robot does not translate), with a floor for the features that the motion
      // will later bring to the side.
      const double parallax = speed > 1e-9 ? std::abs(std::sin(cand + axis0 - heading)) : 1.0;
      const double score = stale * (explore_.parallax_floor + (1.0 - explore_.parallax_floor) * parallax) -
                           kNearness * std::abs(cand - yaw) / M_PI;
      if (score > best) {
        best = score;
        best_yaw = cand;
        best_stale = stale;
      }
    }
    if (best_stale >= explore_.min_stale && best_stale > 0) {
      r.target_yaw = best_yaw;
      r.rate = rateToward(options_, yaw, best_yaw);
      r.mode = YawMode::Explore;
      return r;
    }
  }
  if (std::isfinite(options_.home_yaw)) {
    r.target_yaw = options_.home_yaw;
    r.rate = rateToward(options_, yaw, options_.home_yaw);
    r.mode = YawMode::Home;
    return r;
  }
  if (features.empty())
    r.rate = 0.0; // nothing to centre: hold
  return r;
}

} // namespace yawdepth
