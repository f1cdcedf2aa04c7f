// WindowEstimator: the sliding-window smoother (Eigen only, no Ceres). See window_estimator.h.
#include "window_impl.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <yawdepth/error.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

using namespace refine_detail;

void WindowOptions::validate() const
{
  noise.validateFor(Method::Window);
  gates.validate();
  if (window < 2)
    throw Error("window estimator: the window must hold at least 2 frames (got " + std::to_string(window) + ")");
  auto positive = [](double v, const char *what) {
    if (!(std::isfinite(v) && v > 0))
      throw Error(std::string("window estimator: ") + what + " must be finite and positive");
  };
  if (!(robust_threshold_px >= kMinWeightPx))
    throw Error("window estimator: the robust threshold must be at least 1e-6 px (the scale of its robust loss)");
  if (!(outlier_threshold_px >= kMinWeightPx))
    throw Error("window estimator: the outlier threshold must be at least 1e-6 px");
  positive(prior_sigma_inverse_depth, "prior_sigma_inverse_depth");
  positive(convergence, "convergence");
  if (!std::isfinite(prior_inverse_depth))
    throw Error("window estimator: prior_inverse_depth must be finite");
  if (max_iterations < 1)
    throw Error("window estimator: max_iterations must be at least 1");
}

using namespace refine_detail;
using Impl = WindowState;

Impl::WindowState(const CameraModel &cam, const YawRig &r, const WindowOptions &opt) : camera(cam), rig(r), o(opt)
{
  o.validate();
  mount.R0 = rig.cameraRotation();
  mount.t0 = rig.cameraOffset();
  c_robust = o.robust_threshold_px / o.noise.sigma_px;
  const double t = o.outlier_threshold_px / o.noise.sigma_px;
  c_outlier_sq = t * t;
}

std::vector<int> Impl::freeComponents(const Frame &f) const
{
  std::vector<int> c;
  if (!f.gauge)
    c = pose_components;
  if (yaws_free)
    c.push_back(6);
  return c;
}

int Impl::frameIndex(long frame) const
{
  const auto it = std::lower_bound(frames.begin(), frames.end(), frame,
                                   [](const Frame &f, long k) { return f.row.frame < k; });
  return it != frames.end() && it->row.frame == frame ? static_cast<int>(it - frames.begin()) : -1;
}

/* The free parameters of a frame, cached in it. */
void Impl::setComponents(Frame &f) const
{
  const std::vector<int> c = freeComponents(f);
  std::fill(f.local, f.local + kFrameDim, -1);
  for (std::size_t k = 0; k < c.size(); ++k)
    f.local[c[k]] = static_cast<int>(k);
  f.dim = static_cast<int>(c.size());
}

/* The first row: what is free (poses when the motion has noise, yaws when the readings have), and
   the gauge (the first pose is held for increment noise, as dead reckoning holds it). */
void Impl::startLog(const MotionSample &row, Frame &f)
{
  started = true;
  six_dof = row.six_dof;
  absolute = o.noise.motion_noise == MotionNoise::Absolute;
  const Eigen::Vector3d sr = incrementRotationSigma(o.noise, six_dof, 1.0, 1.0);
  poses_free = incrementTranslationSigma(o.noise, 1.0) > 0 || sr.maxCoeff() > 0 ||
               (absolute && (o.noise.sigma_odom > 0 || poseRotationSigma(o.noise, six_dof).maxCoeff() > 0));
  yaws_free = o.noise.sigma_yaw > 0;
  pose_components.clear();
  if (poses_free) {
    pose_components = {0, 1, 2};
    if (six_dof)
      pose_components.insert(pose_components.end(), {3, 4, 5});
    else
      pose_components.push_back(4);
  }
  f.gauge = !absolute;
  f.x[0] = row.x;
  f.x[1] = row.y;
  f.x[2] = row.z;
}

/* Dead reckoning from the previous frame's estimate. */
void Impl::deadReckon(const MotionSample &row, Frame &f) const
{
  const Frame &p = frames.back();
  const Eigen::Matrix3d Vp = p.Rref * expSO3<double>(Eigen::Vector3d(p.x[3], p.x[4], p.x[5]));
  const Eigen::Vector3d pos =
      Eigen::Vector3d(p.x[0], p.x[1], p.x[2]) + Vp * p.Rref.transpose() * (row.position() - p.row.position());
  const Eigen::Matrix3d V = Vp * p.Rref.transpose() * f.Rref;
  const Eigen::Vector3d d = logSO3(f.Rref.transpose() * V);
  for (int k = 0; k < 3; ++k) {
    f.x[k] = pos(k);
    f.x[3 + k] = d(k);
  }
  if (!six_dof) { // exactly a heading offset
    f.x[3] = 0;
    f.x[5] = 0;
  }
}

/* The new frame's observations (undistorted and whitened; outside the model: flagged); a feature's
   second window observation brings it into the state. */
std::vector<Impl::ObservationResult> Impl::addObservations(const MotionSample &row,
                                                           const std::vector<FeatureObservation> &observations)
{
  std::vector<ObservationResult> results;
  for (const FeatureObservation &fo : observations) {
    ObservationResult res;
    res.id = fo.id;
    Eigen::Vector2d m;
    Eigen::Matrix2d J;
    Feature &ft = features[fo.id];
    ft.id = fo.id;
    ft.last_frame = row.frame;
    if (!std::isfinite(fo.u) || !std::isfinite(fo.v) || !camera.undistort(Eigen::Vector2d(fo.u, fo.v), m, &J)) {
      res.undistorted = false;
      res.inlier = false;
      ft.undistort_failed = true;
      results.push_back(res);
      continue;
    }
    ft.obs.push_back(Obs{row.frame, whitenObservation(m, J, o.noise.sigma_px), false});
    results.push_back(res);
  }
  // Features seen once or not at all this frame but without any window observation: forget.
  for (auto it = features.begin(); it != features.end();)
    it = it->second.obs.empty() && !it->second.in_state ? features.erase(it) : std::next(it);
  for (auto &kv : features)
    if (!kv.second.in_state && kv.second.obs.size() >= 2)
      enterState(kv.second);
  return results;
}

std::vector<Impl::ObservationResult> Impl::addFrame(const MotionSample &row,
                                                    const std::vector<FeatureObservation> &observations)
{
  // The streaming form of validateInputs()'s log rules: frames arrive one at a time, so each is checked
  // against the last (a batch driven from a TracksByFrame never trips them).
  if (started) {
    if (!(row.frame > frames.back().row.frame))
      throw Error("window estimator: frame " + std::to_string(row.frame) + " after frame " +
                  std::to_string(frames.back().row.frame) + " (frames must increase)");
    if (row.six_dof != six_dof)
      throw Error("window estimator: a motion log must be all planar or all 6-DoF rows");
  }
  for (std::size_t i = 0; i < observations.size(); ++i)
    for (std::size_t j = i + 1; j < observations.size(); ++j)
      if (observations[i].id == observations[j].id)
        throw Error("window estimator: feature " + std::to_string(observations[i].id) + " observed twice in frame " +
                    std::to_string(row.frame));
  Frame f;
  f.row = row;
  f.Rref = row.rotation();
  f.x[6] = row.yaw;
  if (!started)
    startLog(row, f);
  else if (absolute)
    std::copy_n(Eigen::Vector3d(row.x, row.y, row.z).data(), 3, f.x);
  else
    deadReckon(row, f);
  setComponents(f);
  if (!frames.empty())
    f.from_prev = increment(frames.back(), f);
  refreshCamera(f);
  frames.push_back(f);
  std::vector<ObservationResult> results = addObservations(row, observations);

  alignNewFrame();
  // Least squares on the inliers (a gross error barely moves the motion that 30 features pin down,
  // so it stands out after it); if any flag changes, the robust path.
  solve(Phase::Inliers);
  if (flagOutliers())
    robustSolve();
  cache_valid = false;
  for (ObservationResult &res : results)
    if (res.undistorted)
      for (const Obs &ob : features.at(res.id).obs)
        if (ob.frame == row.frame)
          res.inlier = !ob.outlier;
  while (static_cast<int>(frames.size()) > o.window)
    marginaliseOldest();
  return results;
}

WindowEstimator::WindowEstimator(const CameraModel &camera, const YawRig &rig, const Options &options)
    : impl_(std::make_unique<Impl>(camera, rig, options))
{
}
WindowEstimator::~WindowEstimator() = default;
WindowEstimator::WindowEstimator(WindowEstimator &&) noexcept = default;
WindowEstimator &WindowEstimator::operator=(WindowEstimator &&) noexcept = default;

std::vector<WindowEstimator::ObservationResult> WindowEstimator::addFrame(const MotionSample &row,
                                                                          const std::vector<FeatureObservation> &obs)
{
  return impl_->addFrame(row, obs);
}

PointEstimate WindowEstimator::estimate(long id) const
{
  const auto it = impl_->features.find(id);
  if (it != impl_->features.end() && it->second.in_state) {
    impl_->ensureCache();
    return impl_->cache.at(id);
  }
  const auto fin = impl_->finished.find(id);
  if (fin != impl_->finished.end())
    return fin->second;
  bool rho_only = false;
  if (it != impl_->features.end())
    return impl_->gatedEstimate(it->second, &rho_only);
  PointEstimate e;
  e.status = Status::TooFewFrames;
  return e;
}

bool WindowEstimator::isOutlier(long id, long frame) const
{
  if (impl_->rejected.count({id, frame}))
    return true;
  const auto it = impl_->features.find(id);
  if (it == impl_->features.end())
    return false;
  for (const WindowState::Obs &ob : it->second.obs)
    if (ob.frame == frame)
      return ob.outlier;
  return false;
}

std::vector<long> WindowEstimator::ids() const
{
  std::vector<long> out;
  for (const auto &kv : impl_->features)
    if (kv.second.in_state)
      out.push_back(kv.first);
  return out;
}

void WindowEstimator::forget(long id)
{
  impl_->finished.erase(id);
  auto &rej = impl_->rejected; // its final outlier flags too
  rej.erase(rej.lower_bound({id, std::numeric_limits<long>::min()}),
            rej.upper_bound({id, std::numeric_limits<long>::max()}));
  const auto it = impl_->features.find(id);
  if (it == impl_->features.end())
    return;
  impl_->dropFromPrior(it->second); // its window observations are dropped with it
  impl_->features.erase(it);
  impl_->cache_valid = false;
}

long WindowEstimator::frame() const { return impl_->frames.empty() ? 0 : impl_->frames.back().row.frame; }

int WindowEstimator::windowFrames() const { return static_cast<int>(impl_->frames.size()); }

MotionSample WindowEstimator::motion(long frame) const
{
  const int fi = impl_->frameIndex(frame);
  if (fi < 0)
    throw Error("window estimator: frame " + std::to_string(frame) + " is not in the window");
  const WindowState::Frame &f = impl_->frames[static_cast<std::size_t>(fi)];
  MotionSample s = f.row;
  s.x = f.x[0];
  s.y = f.x[1];
  s.z = f.x[2];
  s.yaw = f.x[6];
  if (s.six_dof)
    s.theta_u = logSO3(f.Rref * expSO3<double>(Eigen::Vector3d(f.x[3], f.x[4], f.x[5])));
  else
    s.heading = f.row.heading + f.x[4];
  return s;
}

int WindowEstimator::stateDimension() const
{
  SchurSystem s;
  impl_->layoutSystem(s);
  return s.dimension();
}

std::vector<PointEstimate> windowTracks(const CameraModel &camera, const YawRig &rig,
                                        const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                        const WindowOptions &options, std::vector<std::vector<bool>> *outliers)
{
  return windowTracks(camera, rig, validateInputs(motion, tracks), options, outliers);
}

std::vector<PointEstimate> windowTracks(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                        const WindowOptions &options, std::vector<std::vector<bool>> *outliers)
{
  const std::vector<MotionSample> &motion = input.motion();
  const std::vector<Track> &tracks = input.tracks();
  std::vector<PointEstimate> out(tracks.size());
  if (outliers) {
    outliers->assign(tracks.size(), {});
    for (std::size_t t = 0; t < tracks.size(); ++t)
      (*outliers)[t].assign(tracks[t].observations.size(), false);
  }
  if (motion.empty())
    return out;
  WindowEstimator est(camera, rig, options);
  auto collect = [&](std::size_t t) {
    out[t] = est.estimate(tracks[t].id);
    if (out[t].frame != tracks[t].observations.back().frame) { // restarted after a gap, not yet re-estimated
      out[t] = PointEstimate();
      out[t].frame = tracks[t].observations.back().frame;
    }
    if (outliers)
      for (std::size_t k = 0; k < tracks[t].observations.size(); ++k)
        (*outliers)[t][k] = est.isOutlier(tracks[t].id, tracks[t].observations[k].frame);
  };
  for (std::size_t r = 0; r < motion.size(); ++r) {
    std::vector<FeatureObservation> frame;
    frame.reserve(input.observedAt(r).size());
    for (const TracksByFrame::Entry &e : input.observedAt(r)) {
      const Observation &ob = tracks[e.first].observations[e.second];
      frame.push_back({tracks[e.first].id, ob.u, ob.v});
    }
    est.addFrame(motion[r], frame);
  }
  // Estimates of features that left the state were kept when they left; the others are read now.
  for (std::size_t t = 0; t < tracks.size(); ++t)
    if (!tracks[t].observations.empty())
      collect(t);
  return out;
}

} // namespace yawdepth
