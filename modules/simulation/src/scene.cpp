#include <yawdepth/simulation/scene.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <yawdepth/error.h>

namespace yawdepth {

void SceneOptions::validate() const
{
  for (double v : {step, lateral_step, yaw, yaw_rate, heading, turn_rate, min_depth, max_depth, margin_px})
    if (!std::isfinite(v))
      throw Error("simulate: every scene parameter must be a finite number");
  if (frames < 1 || frames > 1000000)
    throw Error("simulate: frames must be between 1 and 1000000");
  if (points < 0 || points > 10000000)
    throw Error("simulate: points must be between 0 and 10000000");
  for (const Eigen::Vector3d &p : world_points)
    if (!p.allFinite())
      throw Error("simulate: a world point is not finite");
  if (!(min_depth > 0) || !(max_depth >= min_depth))
    throw Error("simulate: depths must satisfy 0 < min-depth <= max-depth");
  if (margin_px < 0)
    throw Error("simulate: margin must be non-negative");
  if (!vision_poses.empty() && static_cast<std::size_t>(frames) != vision_poses.size())
    throw Error("simulate: frames must equal the number of vision poses");
  noise.validate();
}

Eigen::Vector3d Scene::cameraPoint(const YawRig &rig, long id, std::size_t index) const
{
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(wMc(rig, truth.at(index)).inverse(), R, t);
  return R * w_points.at(static_cast<std::size_t>(id)) + t;
}

namespace {

using Rng = std::mt19937_64;
using Gauss = std::normal_distribution<double>;
using Uniform = std::uniform_real_distribution<double>;

/* True trajectory: the given vision poses, or steps along the vision frame's own axes, so a
   turning robot curves. */
std::vector<MotionSample> trueTrajectory(const SceneOptions &o, bool six_dof)
{
  std::vector<MotionSample> truth;
  MotionSample s;
  s.heading = o.heading;
  s.yaw = o.yaw;
  for (int k = 0; six_dof && k < o.frames; ++k)
    truth.push_back(MotionSample::fromPose(k, o.vision_poses[static_cast<std::size_t>(k)], o.yaw + k * o.yaw_rate));
  for (int k = 0; !six_dof && k < o.frames; ++k) {
    s.frame = k;
    if (k > 0) {
      const Eigen::Vector3d w_d = rotY(s.heading) * Eigen::Vector3d(o.lateral_step, 0, o.step);
      s.x += w_d.x();
      s.y += w_d.y();
      s.z += w_d.z();
      s.heading += o.turn_rate;
      s.yaw += o.yaw_rate;
    }
    truth.push_back(s);
  }
  return truth;
}

/* Per-pose noise (kinematics, motion capture): each row errs independently about the truth. */
void perturbPoses(const SceneOptions &o, bool six_dof, Rng &rng, Gauss &gauss, std::vector<MotionSample> &measured)
{
  for (int k = 0; k < o.frames; ++k) {
    MotionSample &m = measured[k];
    const Eigen::Vector3d p = m.position() + o.noise.sigma_odom * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    m.x = p.x();
    m.y = p.y();
    m.z = p.z();
    if (six_dof) {
      const Eigen::Vector3d n(gauss(rng), gauss(rng), gauss(rng));
      m.theta_u = logSO3(m.rotation() * expSO3<double>(o.noise.sigma_rot * n));
    } else {
      m.heading += o.noise.sigma_heading * gauss(rng);
    }
  }
}

/* Dead reckoning of a 6-DoF log: each increment (translation in the earlier vision frame, rotation)
   is perturbed and accumulated. */
void perturbIncrementsGeneral(const SceneOptions &o, const std::vector<MotionSample> &truth, Rng &rng, Gauss &gauss,
                              std::vector<MotionSample> &measured)
{
  for (int k = 1; k < o.frames; ++k) {
    const MotionSample &a = truth[k - 1], &b = truth[k];
    const Eigen::Matrix3d Ra = a.rotation();
    const Eigen::Vector3d d = Ra.transpose() * (b.position() - a.position());
    const double angle = Eigen::AngleAxisd(Ra.transpose() * b.rotation()).angle();
    const Eigen::Vector3d d_noisy =
        d + incrementTranslationSigma(o.noise, d.norm()) * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Vector3d n(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Matrix3d dR_noisy =
        Ra.transpose() * b.rotation() * expSO3<double>(incrementRotationSigma(o.noise, true, d.norm(), angle).cwiseProduct(n));
    MotionSample &pm = measured[k - 1], &m = measured[k];
    const Eigen::Matrix3d Rpm = pm.rotation();
    const Eigen::Vector3d p = pm.position() + Rpm * d_noisy;
    m.x = p.x();
    m.y = p.y();
    m.z = p.z();
    m.theta_u = logSO3(Rpm * dR_noisy);
  }
}

/* Dead reckoning of a planar log: each increment (in the earlier vision frame) and heading change is
   perturbed and accumulated. */
void perturbIncrementsPlanar(const SceneOptions &o, const std::vector<MotionSample> &truth, Rng &rng, Gauss &gauss,
                             std::vector<MotionSample> &measured)
{
  for (int k = 1; k < o.frames; ++k) {
    const MotionSample &a = truth[k - 1], &b = truth[k];
    const Eigen::Vector3d d = rotY(a.heading).transpose() * Eigen::Vector3d(b.x - a.x, b.y - a.y, b.z - a.z);
    const Eigen::Vector3d d_noisy =
        d + incrementTranslationSigma(o.noise, d.norm()) * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    const double dh = b.heading - a.heading +
                      incrementRotationSigma(o.noise, false, d.norm(), std::fabs(b.heading - a.heading)).y() * gauss(rng);
    MotionSample &pm = measured[k - 1], &m = measured[k];
    const Eigen::Vector3d w_d = rotY(pm.heading) * d_noisy;
    m.x = pm.x + w_d.x();
    m.y = pm.y + w_d.y();
    m.z = pm.z + w_d.z();
    m.heading = pm.heading + dh;
  }
}

/* Points uniform in the first image (inside the margin) and in depth, in the world frame. */
std::vector<Eigen::Vector3d> randomPoints(const CameraModel &camera, const YawRig &rig, const MotionSample &first,
                                          const SceneOptions &o, double width, double height, Rng &rng, Uniform &uni)
{
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  fromVisp(wMc(rig, first), R0, t0);
  std::vector<Eigen::Vector3d> w_points;
  for (int i = 0; i < o.points; ++i) {
    const double u = o.margin_px + uni(rng) * std::max(0.0, width - 2 * o.margin_px);
    const double v = o.margin_px + uni(rng) * std::max(0.0, height - 2 * o.margin_px);
    const double Z = o.min_depth + uni(rng) * (o.max_depth - o.min_depth);
    Eigen::Vector2d m;
    if (!camera.undistort(Eigen::Vector2d(u, v), m))
      throw Error("simulate: the camera's distortion model cannot be inverted inside the image");
    w_points.emplace_back(R0 * (Z * Eigen::Vector3d(m.x(), m.y(), 1.0)) + t0);
  }
  return w_points;
}

/* One track per point: its noisy pixels in every frame where it is in front of the camera and
   inside the image. */
std::vector<Track> observeTracks(const Scene &scene, const CameraModel &camera, const YawRig &rig,
                                 const SceneOptions &o, double width, double height, Rng &rng, Gauss &gauss)
{
  const int points = static_cast<int>(scene.w_points.size());
  std::vector<Track> tracks(static_cast<std::size_t>(points));
  for (int i = 0; i < points; ++i)
    tracks[i].id = i;
  for (std::size_t k = 0; k < scene.truth.size(); ++k) {
    for (int i = 0; i < points; ++i) {
      const Eigen::Vector3d c_P = scene.cameraPoint(rig, i, k);
      if (!(c_P.z() > 1e-6))
        continue;
      const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(c_P.x() / c_P.z(), c_P.y() / c_P.z()));
      if (!(uv.x() >= 0 && uv.x() <= width - 1 && uv.y() >= 0 && uv.y() <= height - 1))
        continue;
      Observation ob;
      ob.frame = scene.truth[k].frame;
      ob.u = uv.x() + o.noise.sigma_px * gauss(rng);
      ob.v = uv.y() + o.noise.sigma_px * gauss(rng);
      tracks[i].observations.push_back(ob);
    }
  }
  return tracks;
}

} // namespace

Scene simulateScene(const CameraModel &camera, const YawRig &rig, const SceneOptions &o)
{
  o.validate();
  const double width = camera.width() > 0 ? camera.width() : 640.0;
  const double height = camera.height() > 0 ? camera.height() : 480.0;
  Rng rng(o.seed);
  Gauss gauss(0.0, 1.0);
  Uniform uni(0.0, 1.0);

  Scene scene;
  const bool six_dof = !o.vision_poses.empty();
  scene.truth = trueTrajectory(o, six_dof);
  // The measured motion: per-pose noise, or dead reckoning (each increment perturbed and
  // accumulated); each yaw reading is perturbed independently.
  scene.measured = scene.truth;
  if (o.noise.motion_noise == MotionNoise::Absolute)
    perturbPoses(o, six_dof, rng, gauss, scene.measured);
  else if (six_dof)
    perturbIncrementsGeneral(o, scene.truth, rng, gauss, scene.measured);
  else
    perturbIncrementsPlanar(o, scene.truth, rng, gauss, scene.measured);
  for (auto &m : scene.measured)
    m.yaw += o.noise.sigma_yaw * gauss(rng);

  if (o.world_points.empty())
    scene.w_points = randomPoints(camera, rig, scene.truth.front(), o, width, height, rng, uni);
  else
    scene.w_points = o.world_points;
  scene.tracks = observeTracks(scene, camera, rig, o, width, height, rng, gauss);
  return scene;
}

ArmPath armPathFromString(const std::string &word)
{
  if (word == "approach")
    return ArmPath::Approach;
  if (word == "orbit")
    return ArmPath::Orbit;
  if (word == "random")
    return ArmPath::Random;
  throw Error("unknown arm path '" + word + "' (approach, orbit or random)");
}

namespace {

/* Camera pose wMc at `position` looking at `target`, image +Y toward the world's +Y (down), then
   rolled about the optical axis. */
Eigen::Isometry3d lookAt(const Eigen::Vector3d &position, const Eigen::Vector3d &target, double roll)
{
  const Eigen::Vector3d z = (target - position).normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);
  if (!(x.norm() > 1e-9))
    x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R << x, y, z;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = position;
  return T;
}

} // namespace

std::vector<vpHomogeneousMatrix> armTrajectory(const YawRig &rig, ArmPath path, int frames, double distance,
                                               std::uint64_t seed, double yaw)
{
  if (frames < 1 || frames > 1000000)
    throw Error("arm trajectory: frames must be between 1 and 1000000");
  if (!(distance > 0) || !std::isfinite(distance) || !std::isfinite(yaw))
    throw Error("arm trajectory: the distance must be finite and positive, the yaw finite");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const Eigen::Vector3d target(0, 0, distance);
  const Eigen::Isometry3d cMv = toIsometry(rig.vMc(yaw)).inverse();
  const double jitter = 0.5 * M_PI / 180;
  std::vector<vpHomogeneousMatrix> poses;
  for (int k = 0; k < frames; ++k) {
    const double s = frames > 1 ? static_cast<double>(k) / (frames - 1) : 0.0;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double roll = 0;
    switch (path) {
    case ArmPath::Approach:
      p = distance * Eigen::Vector3d(0.08 * s, 0.04 * s, 0.3 * s);
      roll = 0.1 * s;
      break;
    case ArmPath::Orbit: {
      const double phi = s * 40 * M_PI / 180;
      p = target + distance * Eigen::Vector3d(-std::sin(phi), 0.05 * std::sin(2 * M_PI * s), -std::cos(phi));
      break;
    }
    case ArmPath::Random:
      if (k > 0) {
        p = 0.15 * distance * Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
        roll = 0.3 * uni(rng);
      }
      break;
    }
    Eigen::Vector3d aim = target;
    if (k > 0)
      aim += jitter * distance * Eigen::Vector3d(gauss(rng), gauss(rng), 0.0);
    const Eigen::Isometry3d wMc = lookAt(p, aim, roll);
    const Eigen::Isometry3d wMv = wMc * cMv;
    poses.push_back(toVisp(wMv.linear(), wMv.translation()));
  }
  return poses;
}

void addTrackerErrors(std::vector<Track> &tracks, double sigma, double phi, std::uint64_t seed)
{
  if (!(std::isfinite(sigma) && sigma >= 0 && phi >= 0 && phi <= kMaxPixelCorrelation))
    throw Error("tracker errors: sigma must be finite and >= 0 and phi in [0, 0.99]");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  for (Track &t : tracks) {
    double eu = sigma * n(rng), ev = sigma * n(rng);
    bool first = true;
    long last = 0;
    for (Observation &ob : t.observations) {
      const double a = first ? 1.0 : pixelCorrelationOver(phi, ob.frame - last); // the first keeps its draw
      first = false;
      const double s = sigma * std::sqrt(1.0 - a * a);
      eu = a * eu + s * n(rng);
      ev = a * ev + s * n(rng);
      last = ob.frame;
      ob.u += eu;
      ob.v += ev;
    }
  }
}

} // namespace yawdepth
