/*
  bench_active_yaw: does steering the pan help depth? A robot drives straight past a group of
  target points while the window estimator measures them; the camera's yaw is held fixed (front
  view, 30, 60 or 90 degrees) or steered every frame by YawHelper (recommendYawRate() with a memory
  of where it looked, started pointing at the targets), with and without its exploration of unseen
  bearings. Reported per target layout and yaw policy: the time until every target's depth sigma
  (the estimator's own) has fallen below 2 % of its depth, over several noise seeds.

    bench_active_yaw [--seeds N] [--seed S] [--frames F] [--layout I]

  Scene: the paper's camera (1734 px focal length, 640x480: +-10.5 degrees of horizontal field of
  view) and rig (optical centre 0.1503 m off the pan axis); 0.2 m/s forward, 10 frames per second;
  0.3 px, 1 mm and 0.05 deg of odometry per frame, 0.05 deg per pan reading (the estimator's model).
  The pan is limited to +-120 degrees and 0.5 rad/s. A target that has never been seen, or whose
  sigma never gets below 2 %, leaves its layout's time at "never".
*/
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <yawdepth/window/window_estimator.h>
#include <yawdepth/servo/yaw_helper.h>

#include "bench_common.h"

using namespace yawdepth;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kDt = 0.1;      // s per frame
constexpr double kSpeed = 0.2;   // m/s
constexpr double kTarget = 0.02; // sigma_Z / Z to reach
constexpr double kNever = std::numeric_limits<double>::infinity();

struct Layout {
  const char *name;
  Eigen::Vector3d centre; // in the start vision frame (x right, y down, z ahead), m
  Eigen::Vector3d extent; // half-size of the box the points are drawn in, m
};

struct Policy {
  const char *name;
  bool steered;
  double yaw; // fixed yaw (rad); the steered policy starts pointing at the layout
  bool explore = true; // the steered policy explores unseen bearings (YawHelper) once nothing is left to learn
};

/* Dead reckoning over one frame: the increment with its noise, in the previous measured heading. */
void deadReckon(MotionSample &measured, const NoiseModel &noise, std::mt19937_64 &rng,
                std::normal_distribution<double> &gauss)
{
  const Eigen::Vector3d d(noise.sigma_odom * gauss(rng), noise.sigma_odom * gauss(rng),
                          kSpeed * kDt + noise.sigma_odom * gauss(rng));
  const double dh = noise.sigma_heading * gauss(rng);
  const Eigen::Vector3d w = rotY(measured.heading) * d;
  measured.x += w.x();
  measured.y += w.y();
  measured.z += w.z();
  measured.heading += dh;
}

/* The targets in view from the true pose, their pixels with noise. */
std::vector<FeatureObservation> observeTargets(const CameraModel &camera, const YawRig &rig, const MotionSample &truth,
                                               const std::vector<Eigen::Vector3d> &points, const NoiseModel &noise,
                                               std::mt19937_64 &rng, std::normal_distribution<double> &gauss)
{
  const vpHomogeneousMatrix cMw = wMc(rig, truth).inverse();
  std::vector<FeatureObservation> obs;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    const vpColVector P = cMw * vpColVector({points[i].x(), points[i].y(), points[i].z(), 1.0});
    if (!(P[2] > 0.05))
      continue;
    const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(P[0] / P[2], P[1] / P[2]));
    if (uv.x() < 0 || uv.y() < 0 || uv.x() > camera.width() - 1 || uv.y() > camera.height() - 1)
      continue;
    const double u = uv.x() + noise.sigma_px * gauss(rng), v = uv.y() + noise.sigma_px * gauss(rng);
    obs.push_back(FeatureObservation{i, u, v});
  }
  return obs;
}

/* What the helper gets: every target the estimator tracks that still needs depth (predicted into the
   current view from the measured motion, whether or not it is in view now) and the ones in view. */
std::vector<YawHelperFeature> helperFeatures(const CameraModel &camera, const YawRig &rig, const WindowEstimator &est,
                                             const std::vector<FeatureObservation> &obs,
                                             const std::vector<double> &reached, const std::vector<MotionSample> &log,
                                             int k, double prior_depth)
{
  std::vector<YawHelperFeature> helper;
  const vpHomogeneousMatrix cMw_measured = wMc(rig, log.back()).inverse();
  std::vector<bool> in_view(reached.size(), false);
  for (const FeatureObservation &o : obs) {
    in_view[static_cast<std::size_t>(o.id)] = true;
    const PointEstimate e = est.estimate(o.id);
    Eigen::Vector2d m;
    if (!camera.undistort(Eigen::Vector2d(o.u, o.v), m))
      continue;
    YawHelperFeature f;
    f.x = m.x();
    f.y = m.y();
    const bool ok = e.ok() && e.frame == k && e.c_P.z() > 0;
    f.Z = ok ? e.c_P.z() : prior_depth;
    f.sigma_rel = ok ? e.sigmaZ() / e.c_P.z() : std::numeric_limits<double>::quiet_NaN();
    f.weight = reached[static_cast<std::size_t>(o.id)] < kNever ? 0.0 : 1.0;
    helper.push_back(f);
  }
  for (std::size_t i = 0; i < reached.size(); ++i) {
    const PointEstimate e = est.estimate(static_cast<long>(i));
    if (in_view[i] || reached[i] < kNever || !e.ok() || !(e.c_P.z() > 0))
      continue;
    const vpColVector P = cMw_measured * wMc(rig, log[static_cast<std::size_t>(e.frame)]) *
                          vpColVector({e.c_P.x(), e.c_P.y(), e.c_P.z(), 1.0});
    if (!(P[2] > 0.05))
      continue; // behind the camera now: passed
    helper.push_back(YawHelperFeature{P[0] / P[2], P[1] / P[2], P[2], 1.0, e.sigmaZ() / e.c_P.z()});
  }
  return helper;
}

/* Seconds until every target reached sigma_Z / Z < 2 % (kNever if one never does). */
double runOnce(const CameraModel &camera, const YawRig &rig, const Layout &layout, const Policy &policy, int frames,
               std::uint64_t seed, double side, double *final_yaw)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const NoiseModel noise{0.3, 1e-3, 0.05 * kDeg, 0.05 * kDeg};
  const int n = 12;
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i)
    points.push_back(layout.centre + layout.extent.cwiseProduct(Eigen::Vector3d(uni(rng), uni(rng), uni(rng))));
  WindowOptions wo;
  wo.noise = noise;
  WindowEstimator est(camera, rig, wo);
  YawHelperOptions ho;
  ho.min_yaw = -120 * kDeg;
  ho.max_yaw = 120 * kDeg;
  ho.home_yaw = side * 90 * kDeg; // measured what it sees: back to the side view, toward the targets
  YawExploreOptions xo;
  xo.enabled = policy.explore;
  YawHelper helper_state(camera, rig, ho, xo);
  double yaw = policy.steered ? std::atan2(layout.centre.x(), layout.centre.z()) : policy.yaw;
  MotionSample truth, measured;
  std::vector<double> reached(n, kNever);
  std::vector<MotionSample> log; // the measured motion, one row per frame
  for (int k = 0; k < frames; ++k) {
    truth.frame = measured.frame = k;
    truth.z = kSpeed * kDt * k;
    truth.yaw = yaw;
    if (k > 0)
      deadReckon(measured, noise, rng, gauss);
    measured.yaw = yaw + noise.sigma_yaw * gauss(rng);
    const std::vector<FeatureObservation> obs = observeTargets(camera, rig, truth, points, noise, rng, gauss);
    est.addFrame(measured, obs);
    int done = 0;
    for (int i = 0; i < n; ++i) {
      const PointEstimate e = est.estimate(i);
      const bool converged = e.ok() && e.c_P.z() > 0 && e.sigmaZ() / e.c_P.z() < kTarget;
      if (converged && reached[i] == kNever)
        reached[i] = k * kDt;
      done += reached[i] < kNever ? 1 : 0;
    }
    log.push_back(measured);
    const std::vector<YawHelperFeature> helper =
        helperFeatures(camera, rig, est, obs, reached, log, k, 1.0 / wo.prior_inverse_depth);
    if (done == n)
      break;
    if (policy.steered) {
      const YawRecommendation r = helper_state.recommend(k * kDt, measured.yaw, Eigen::Vector3d(0, 0, kSpeed), helper);
      yaw = std::clamp(yaw + r.rate * kDt, ho.min_yaw, ho.max_yaw);
    }
  }
  *final_yaw = yaw;
  return *std::max_element(reached.begin(), reached.end());
}

std::string fmtTime(double t)
{
  if (!std::isfinite(t))
    return "never";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", t);
  return buf;
}

} // namespace

int main(int argc, char **argv)
{
  int seeds = 10, frames = 400, only = -1;
  std::uint64_t seed = 1;
  bench::CommandLine cli("[--seeds N] [--seed S] [--frames F] [--layout I (0-based row)]");
  cli.option("--seeds", seeds).option("--seed", seed).option("--frames", frames).option("--layout", only);
  if (!cli.parse(argc, argv))
    return 2;
  if (seeds < 1 || frames < 10) {
    std::fprintf(stderr, "bench_active_yaw: --seeds must be >= 1 and --frames >= 10\n");
    return 2;
  }
  const CameraModel camera = bench::paperCamera();
  const YawRig rig = bench::paperRig();
  const std::vector<Layout> layouts = {
      {"ahead on the path, 6 m", {0.0, 0.0, 6.0}, {0.3, 0.1, 0.3}},
      {"ahead-right, 1 m off the path, 5 m", {1.0, 0.0, 5.0}, {0.3, 0.1, 0.3}},
      {"right, 2 m off the path, 3 m", {2.0, 0.0, 3.0}, {0.3, 0.1, 0.3}},
      {"beside, 1.5 m to the right", {1.5, 0.0, 0.8}, {0.2, 0.1, 0.3}},
      {"left, 2 m off the path, 4 m", {-2.0, 0.0, 4.0}, {0.3, 0.1, 0.3}},
      {"far right, 4 m off the path, 8 m", {4.0, 0.0, 8.0}, {0.4, 0.1, 0.4}},
      {"spread right, 1-3 m off, 1.5-4.5 m", {2.0, 0.0, 3.0}, {1.0, 0.2, 1.5}},
  };
  if (only >= static_cast<int>(layouts.size())) {
    std::fprintf(stderr, "bench_active_yaw: --layout must be below %zu\n", layouts.size());
    return 2;
  }
  const std::vector<Policy> policies = {{"front (0 deg)", false, 0.0},     {"30 deg toward", false, 30 * kDeg},
                                        {"60 deg toward", false, 60 * kDeg}, {"90 deg toward", false, 90 * kDeg},
                                        {"no exploring", true, 0.0, false}, {"steered (helper)", true, 0.0}};
  std::printf("yawdepth active yaw: seconds until every goal point's depth sigma < 2 %% of its depth (window estimator)\n");
  std::printf("Reproduce: build/benchmarks/bench_active_yaw --seeds %d --seed %llu --frames %d\n", seeds,
              static_cast<unsigned long long>(seed), frames);
  std::printf("12 goal points per layout in a box (+-0.2 to 0.4 m, +-0.1 m high); 0.2 m/s, 10 frames/s, run of %.0f s; median\n"
              "(and worst) over %d seeds; fixed yaws look toward the layout's side (right or left).\n",
              frames * kDt, seeds);
  std::printf("%s\n", std::string(127, '-').c_str());
  std::printf("%-36s", "layout");
  for (const Policy &p : policies)
    std::printf(" %14s", p.name);
  std::printf("\n%s\n", std::string(127, '-').c_str());
  for (std::size_t li = 0; li < layouts.size(); ++li) {
    if (only >= 0 && static_cast<std::size_t>(only) != li)
      continue;
    const Layout &L = layouts[li];
    std::printf("%-36s", L.name);
    const double side = L.centre.x() < 0 ? -1.0 : 1.0;
    for (const Policy &p : policies) {
      Policy q = p;
      q.yaw = side * p.yaw;
      std::vector<double> t;
      for (int s = 0; s < seeds; ++s) {
        double final_yaw = 0;
        t.push_back(runOnce(camera, rig, L, q, frames, seed + static_cast<std::uint64_t>(s), side, &final_yaw));
      }
      std::sort(t.begin(), t.end());
      const std::string cell = fmtTime(t[t.size() / 2]) + " (" + fmtTime(t.back()) + ")";
      std::printf(" %14s", cell.c_str());
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  std::printf("%s\n", std::string(127, '-').c_str());
  return 0;
}
