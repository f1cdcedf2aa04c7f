// `window`: the sliding-window smoother (WindowEstimator). Jacobians against finite differences,
// noise-free exactness with marginalisation, Monte Carlo against the joint bound, gross outliers,
// features that appear and vanish, frames without motion or features, per-pose motion noise, a
// long sequence without drift, and bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <yawdepth/error.h>
#include <yawdepth/refine/refine.h>
#include <yawdepth/window/window_estimator.h>
#include <yawdepth/simulation/scene.h>

// The estimator's model with its analytic Jacobians (private to the module, header-only).
#include "window_model.h"

#include "scene_support.h"

using namespace yawdepth;
using namespace yawdepth::test;

namespace {

constexpr double kDeg = M_PI / 180.0;
// Round-off of the exact maths (relative), and of central differences with step 1e-6.
constexpr double kExact = 1e-6;
constexpr double kFiniteDifference = 1e-5;
// Noise-scaled acceptance of the Monte Carlo tests (fewer trials than the benchmark's, so a little
// looser than docs/method.md's pooled 1.2 and coverage 0.90 to 0.98).
constexpr double kMaxRatio = 1.3;
constexpr double kMinCoverage = 0.86, kMaxCoverage = 0.995;

std::size_t rowOf(const Scene &s, long frame)
{
  for (std::size_t r = 0; r < s.truth.size(); ++r)
    if (s.truth[r].frame == frame)
      return r;
  FAIL("frame not in the scene");
  return 0;
}

Eigen::Vector3d truthAtLast(const Scene &s, const YawRig &rig, const Track &t)
{
  return s.cameraPoint(rig, t.id, rowOf(s, t.observations.back().frame));
}

using Stats = CrlbStats;

/* Every frame's observations, for feeding a WindowEstimator by hand. */
std::vector<std::vector<FeatureObservation>> byFrame(const Scene &s, const std::vector<Track> &tracks)
{
  std::vector<std::vector<FeatureObservation>> out(s.measured.size());
  for (const Track &t : tracks)
    for (const Observation &ob : t.observations)
      out[rowOf(s, ob.frame)].push_back(FeatureObservation{t.id, ob.u, ob.v});
  return out;
}

} // namespace

namespace {

// The step of the central differences.
constexpr double kStep = 1e-6;

/* A random frame of the Jacobian tests: the mount, the frame's reference rotation, its parameters
   and the camera they give. */
struct JacobianFrame {
  window_detail::Mount mount;
  Eigen::Matrix3d Rref;
  double x[window_detail::kFrameDim];
  window_detail::CameraPose cam;
};

JacobianFrame randomFrame(std::mt19937_64 &rng, std::uniform_real_distribution<double> &u)
{
  using namespace window_detail;
  JacobianFrame fr;
  fr.mount.R0 = expSO3<double>(Eigen::Vector3d(0.3 * u(rng), 0.3 * u(rng), 1.5 + 0.1 * u(rng)));
  fr.mount.t0 = Eigen::Vector3d(0.1 * u(rng), 0.05 * u(rng), 0.05 * u(rng));
  fr.Rref = expSO3<double>(Eigen::Vector3d(0.2 * u(rng), u(rng), 0.2 * u(rng)));
  double x[kFrameDim] = {u(rng), 0.1 * u(rng), u(rng), 0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng), u(rng)};
  std::copy(x, x + kFrameDim, fr.x);
  cameraPose(fr.x, fr.Rref, fr.mount, fr.cam);
  return fr;
}

/* The camera of `fr` with frame parameter j moved by +kStep (cp) and by -kStep (cm). */
void shifted(const JacobianFrame &fr, int j, window_detail::CameraPose &cp, window_detail::CameraPose &cm)
{
  using namespace window_detail;
  double xp[kFrameDim], xm[kFrameDim];
  std::copy(fr.x, fr.x + kFrameDim, xp);
  std::copy(fr.x, fr.x + kFrameDim, xm);
  xp[j] += kStep;
  xm[j] -= kStep;
  cameraPose(xp, fr.Rref, fr.mount, cp);
  cameraPose(xm, fr.Rref, fr.mount, cm);
}

/* The camera's derivatives (rotation, centre, and the vehicle rotation's) against central differences. */
void checkCameraJacobians(const JacobianFrame &fr)
{
  using namespace window_detail;
  const double h = kStep;
  for (int j = 0; j < kFrameDim; ++j) {
    CameraPose cp, cm;
    shifted(fr, j, cp, cm);
    CHECK(((cp.R - cm.R) / (2 * h) - fr.cam.dR[j]).norm() < kFiniteDifference);
    CHECK(((cp.c - cm.c) / (2 * h) - fr.cam.dc[j]).norm() < kFiniteDifference);
    if (j >= 3 && j < 6)
      CHECK(((cp.Rv - cm.Rv) / (2 * h) - fr.cam.dRv[j - 3]).norm() < kFiniteDifference);
  }
}

/* Reprojection: a point 1 to 3 m in front of the camera, anchored in another camera; the residual's
   Jacobian (frame parameters, then the anchored inverse-depth point) against central differences. */
void checkReprojectionJacobian(const JacobianFrame &fr, std::mt19937_64 &rng, std::uniform_real_distribution<double> &u)
{
  using namespace window_detail;
  const double h = kStep;
  const CameraPose &cam = fr.cam;
  const Eigen::Vector3d P = cam.c + cam.R * Eigen::Vector3d(0.3 * u(rng), 0.2 * u(rng), 2.0 + u(rng));
  const Eigen::Matrix3d Ra = cam.R * expSO3<double>(Eigen::Vector3d(0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng)));
  const Eigen::Vector3d ca = cam.c + Eigen::Vector3d(0.2 * u(rng), 0.05 * u(rng), 0.2 * u(rng));
  const Eigen::Vector3d qa = Ra.transpose() * (P - ca);
  double p[3] = {qa.x() / qa.z(), qa.y() / qa.z(), 1.0 / qa.z()};
  WhitenedObservation w;
  w.m[0] = 0.01;
  w.m[1] = -0.02;
  w.s00 = 3000;
  w.s01 = 40;
  w.s11 = 2900;
  Eigen::Vector2d r;
  Eigen::Matrix<double, 2, 10> J;
  REQUIRE(observationResidual(Ra, ca, p, cam, w, r, &J));
  for (int j = 0; j < 10; ++j) {
    Eigen::Vector2d rp, rm;
    if (j < kFrameDim) {
      CameraPose cp, cm;
      shifted(fr, j, cp, cm);
      observationResidual(Ra, ca, p, cp, w, rp, nullptr);
      observationResidual(Ra, ca, p, cm, w, rm, nullptr);
    } else {
      double pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]};
      pp[j - 7] += h;
      pm[j - 7] -= h;
      observationResidual(Ra, ca, pp, cam, w, rp, nullptr);
      observationResidual(Ra, ca, pm, cam, w, rm, nullptr);
    }
    const Eigen::Vector2d fd = (rp - rm) / (2 * h);
    CHECK((fd - J.col(j)).norm() <= kFiniteDifference * (1.0 + fd.norm()));
  }
}

/* Increment: a second frame near the first, the measurement near the truth; the residual against
   refine's, and its Jacobian (both frames' parameters) against central differences. */
void checkIncrementJacobian(const JacobianFrame &fr, std::mt19937_64 &rng, std::uniform_real_distribution<double> &u)
{
  using namespace window_detail;
  const double h = kStep;
  const double *x = fr.x;
  const Eigen::Matrix3d &Rref = fr.Rref;
  const Mount &mount = fr.mount;
  double y[kFrameDim];
  for (int j = 0; j < kFrameDim; ++j)
    y[j] = x[j] + 0.02 * u(rng);
  const Eigen::Matrix3d Rref2 = Rref * expSO3<double>(Eigen::Vector3d(0.01 * u(rng), 0.1 * u(rng), 0.01 * u(rng)));
  CameraPose cam2;
  cameraPose(y, Rref2, mount, cam2);
  OdometryMeasurementGeneral o;
  o.d[0] = 0.01;
  o.d[1] = -0.003;
  o.d[2] = 0.02;
  o.dR = expSO3<double>(Eigen::Vector3d(0.001, 0.02, -0.002));
  o.inv_sigma_t = 1000;
  o.inv_sigma_r[0] = 2000;
  o.inv_sigma_r[1] = 1500;
  o.inv_sigma_r[2] = 1800;
  Eigen::Matrix<double, 6, 1> ro;
  Eigen::Matrix<double, 6, 14> Jo;
  odometryResidual(x, fr.cam, y, cam2, o, ro, &Jo);
  // Against the residual refine uses (refine_model.h), with Rref folded into the blocks' frames.
  o.Rref_prev = Rref;
  o.Rref_cur = Rref2;
  double rr[6];
  refine_detail::odometryResidualGeneral(x, y, o, rr);
  for (int k = 0; k < 6; ++k)
    CHECK(ro(k) == Approx(rr[k]).margin(kExact));
  for (int j = 0; j < 14; ++j) {
    double xp[kFrameDim], xm[kFrameDim], yp[kFrameDim], ym[kFrameDim];
    std::copy(x, x + kFrameDim, xp);
    std::copy(x, x + kFrameDim, xm);
    std::copy(y, y + kFrameDim, yp);
    std::copy(y, y + kFrameDim, ym);
    (j < kFrameDim ? xp[j] : yp[j - kFrameDim]) += h;
    (j < kFrameDim ? xm[j] : ym[j - kFrameDim]) -= h;
    CameraPose a, b, c, d;
    cameraPose(xp, Rref, mount, a);
    cameraPose(yp, Rref2, mount, b);
    cameraPose(xm, Rref, mount, c);
    cameraPose(ym, Rref2, mount, d);
    Eigen::Matrix<double, 6, 1> rp, rm;
    odometryResidual(xp, a, yp, b, o, rp, nullptr);
    odometryResidual(xm, c, ym, d, o, rm, nullptr);
    const Eigen::Matrix<double, 6, 1> fd = (rp - rm) / (2 * h);
    CHECK((fd - Jo.col(j)).norm() <= kFiniteDifference * (1.0 + fd.norm()));
  }
}

} // namespace

TEST_CASE("window: camera, reprojection and increment Jacobians match central finite differences", "[window]")
{
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Each trial draws its frame, then the reprojection's point and anchor, then the second frame.
  for (int trial = 0; trial < 20; ++trial) {
    const JacobianFrame fr = randomFrame(rng, u);
    checkCameraJacobians(fr);
    checkReprojectionJacobian(fr, rng, u);
    checkIncrementJacobian(fr, rng, u);
  }
}

TEST_CASE("window returns the truth on noise-free scenes, with and without marginalisation", "[window]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  for (int frames : {10, 25}) {
    for (double yaw : {0.0, 90 * kDeg}) {
      const Scene s = simulateScene(camera, rig, paperScene(yaw, 1 * kDeg, frames, 3, false));
      WindowOptions o;
      o.noise = paperNoise(); // the model of noisy data; these happen to be exact
      o.window = 8;
      o.convergence = 1e-12; // to round-off
      o.max_iterations = 30;
      o.prior_sigma_inverse_depth = 1e4; // the weak prior pulls by (sigma_rho / its sigma)^2: here nothing
      const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, s.tracks, o);
      REQUIRE(est.size() == s.tracks.size());
      int ok = 0;
      for (std::size_t i = 0; i < s.tracks.size(); ++i) {
        if (!est[i].ok())
          continue;
        ++ok;
        const Eigen::Vector3d truth = truthAtLast(s, rig, s.tracks[i]);
        CHECK((est[i].c_P - truth).norm() / truth.norm() < kExact);
        CHECK(est[i].frame == s.tracks[i].observations.back().frame);
        CHECK(est[i].c_cov.allFinite());
        CHECK(est[i].sigmaZ() > 0);
      }
      CHECK(ok >= 20);
    }
  }
}

TEST_CASE_METHOD(PaperSetup, "window is efficient and honest with marginalisation (Monte Carlo against the joint bound)",
          "[window][montecarlo]")
{
  Stats pooled;
  for (double yaw : {0.0, 45 * kDeg, 90 * kDeg}) {
    Stats st;
    for (int t = 0; t < 25; ++t) {
      const Scene s = simulateScene(camera, rig, paperScene(yaw, 0.5 * kDeg, 20, 100 + static_cast<std::uint64_t>(t)));
      const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
      WindowOptions o;
      o.noise = noise;
      o.window = 8; // 12 of the 20 frames are marginalised
      const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, s.tracks, o);
      for (std::size_t i = 0; i < s.tracks.size(); ++i) {
        if (!est[i].ok() || !(crlb[i] > 0) || !std::isfinite(crlb[i]))
          continue;
        const double e = est[i].c_P.z() - truthAtLast(s, rig, s.tracks[i]).z();
        st.add(e, crlb[i], est[i].sigmaZ());
        pooled.add(e, crlb[i], est[i].sigmaZ());
      }
    }
    INFO("yaw " << yaw / kDeg << " deg: RMSE/CRLB " << st.ratio() << ", coverage " << st.coverage() << ", n " << st.n);
    CHECK(st.n > 500);
    CHECK(st.ratio() < 1.5);
  }
  INFO("pooled: RMSE/CRLB " << pooled.ratio() << ", coverage " << pooled.coverage());
  CHECK(pooled.ratio() < kMaxRatio);
  CHECK(pooled.coverage() > kMinCoverage);
  CHECK(pooled.coverage() < kMaxCoverage);
}

TEST_CASE_METHOD(PaperSetup, "window flags gross outliers and stays near the clean bound", "[window][outliers][slow]")
{
  long corrupted = 0, tp = 0, fp = 0;
  Stats st;
  for (int t = 0; t < 12; ++t) {
    const Scene s = simulateScene(camera, rig, paperScene(45 * kDeg, 0.5 * kDeg, 20, 300 + static_cast<std::uint64_t>(t)));
    std::vector<Track> tracks = s.tracks;
    std::vector<std::vector<bool>> truth(tracks.size());
    std::mt19937_64 rng(900 + static_cast<std::uint64_t>(t));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (std::size_t i = 0; i < tracks.size(); ++i)
      for (Observation &ob : tracks[i].observations) {
        const bool bad = u(rng) < 0.05;
        truth[i].push_back(bad);
        if (bad) {
          const double a = 2 * M_PI * u(rng), r = 10 + 40 * u(rng);
          ob.u = std::clamp(ob.u + r * std::cos(a), 0.0, 639.0);
          ob.v = std::clamp(ob.v + r * std::sin(a), 0.0, 479.0);
          ++corrupted;
        }
      }
    const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
    WindowOptions o;
    o.noise = noise;
    o.window = 8;
    std::vector<std::vector<bool>> flags;
    const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, tracks, o, &flags);
    REQUIRE(flags.size() == tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      REQUIRE(flags[i].size() == tracks[i].observations.size());
      for (std::size_t k = 0; k < flags[i].size(); ++k)
        if (flags[i][k])
          (truth[i][k] ? tp : fp) += 1;
      if (est[i].ok() && crlb[i] > 0 && std::isfinite(crlb[i]))
        st.add(est[i].c_P.z() - truthAtLast(s, rig, s.tracks[i]).z(), crlb[i], est[i].sigmaZ());
    }
  }
  REQUIRE(corrupted > 100);
  const double recall = double(tp) / corrupted, precision = double(tp) / std::max(tp + fp, 1L);
  INFO("recall " << recall << ", precision " << precision << ", RMSE/CRLB " << st.ratio());
  CHECK(recall >= 0.95);
  CHECK(precision >= 0.95);
  CHECK(st.ratio() < 1.6);
}

TEST_CASE("window: features appear and vanish, frames without motion or without features", "[window]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  Scene s = simulateScene(camera, rig, paperScene(60 * kDeg, 0.0, 30, 21));
  // Features 0..9 only from frame 12 on (appearing), 10..19 only up to frame 15 (vanishing).
  std::vector<Track> tracks = s.tracks;
  for (Track &t : tracks) {
    auto &ob = t.observations;
    if (t.id < 10)
      ob.erase(std::remove_if(ob.begin(), ob.end(), [](const Observation &o) { return o.frame < 12; }), ob.end());
    else if (t.id < 20)
      ob.erase(std::remove_if(ob.begin(), ob.end(), [](const Observation &o) { return o.frame > 15; }), ob.end());
  }
  const auto frames = byFrame(s, tracks);
  WindowOptions o;
  o.noise = paperNoise();
  o.window = 6;
  WindowEstimator est(camera, rig, o);
  for (std::size_t k = 0; k < s.measured.size(); ++k) {
    // Frame 8 carries no feature; frame 20 repeats frame 19's row (the robot stood still).
    std::vector<FeatureObservation> obs = k == 8 ? std::vector<FeatureObservation>() : frames[k];
    MotionSample row = s.measured[k];
    if (k == 20) {
      const long f = row.frame;
      row = s.measured[19];
      row.frame = f;
      obs = frames[19];
    }
    const auto res = est.addFrame(row, obs);
    CHECK(res.size() == obs.size());
    CHECK(est.windowFrames() <= o.window);
  }
  int ok = 0;
  for (const Track &t : tracks) {
    if (t.observations.size() < 2)
      continue;
    const PointEstimate e = est.estimate(t.id);
    if (!e.ok())
      continue;
    ++ok;
    const long fed_last = t.observations.back().frame == s.measured[19].frame ? s.measured[20].frame
                                                                                : t.observations.back().frame;
    CHECK(e.frame == fed_last);
    CHECK(e.c_cov.allFinite());
    // Frame 20's observations were frame 19's: its points are off by one step there; the others are
    // measured to within 10 sigma of their own uncertainty.
    if (e.frame != s.measured[20].frame && e.frame == t.observations.back().frame) {
      const double err = std::abs(e.c_P.z() - truthAtLast(s, rig, t).z());
      CHECK(err < 10 * e.sigmaZ() + 1e-3);
    }
  }
  CHECK(ok >= 20);
  // Unknown ids, and a feature seen once.
  CHECK(est.estimate(123456).status == Status::TooFewFrames);
  MotionSample next = s.measured.back();
  next.frame += 1;
  est.addFrame(next, {FeatureObservation{777, 320, 240}});
  CHECK(est.estimate(777).status == Status::TooFewFrames);
  est.forget(20);
  CHECK(est.estimate(20).status == Status::TooFewFrames);
  for (const Observation &ob : tracks[20].observations)
    CHECK_FALSE(est.isOutlier(20, ob.frame)); // its flags are forgotten too
  // Frames without any feature until every feature has left the state (free poses, no point).
  for (int k = 0; k < o.window + 2; ++k) {
    next.frame += 1;
    next.x += 0.02;
    est.addFrame(next, {});
  }
  CHECK(est.ids().empty());
  CHECK(est.stateDimension() > 0);
}

TEST_CASE("window: a camera that does not move gives no_motion, not a depth", "[window]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  Scene s = simulateScene(camera, rig, paperScene(0.0, 0.0, 6, 5, false));
  for (MotionSample &m : s.measured)
    m = MotionSample{m.frame, 0, 0, 0, 0, 0};
  // Every observation at its first frame's pixel: a still camera.
  for (Track &t : s.tracks)
    for (Observation &ob : t.observations)
      ob = Observation{ob.frame, t.observations.front().u, t.observations.front().v};
  WindowOptions o;
  o.noise = paperNoise();
  const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, s.tracks, o);
  for (const PointEstimate &e : est) {
    CHECK_FALSE(e.ok());
    CHECK((e.status == Status::NoMotion || e.status == Status::Degenerate));
  }
}

TEST_CASE("window: a depth the frames do not resolve is degenerate, not ok or behind", "[window]")
{
  // 15 frames 0.05 mm apart (0.7 mm of travel for points 0.5 to 3 m away): a fraction of a pixel of
  // parallax against 0.3 px of noise, so most inverse depths span zero at 2 sigma.
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  SceneOptions so = paperScene(1.0, 0.0, 15, 11);
  so.step = 0.00005;
  so.points = 60;
  so.noise.sigma_odom = 1e-4;
  const Scene s = simulateScene(camera, rig, so);
  WindowOptions o;
  o.noise = so.noise;
  const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, s.tracks, o);
  int degenerate = 0;
  for (const PointEstimate &e : est) {
    degenerate += e.status == Status::Degenerate ? 1 : 0;
    if (e.ok()) { // every ok depth has a bounded 2-sigma interval
      const double rel = std::sqrt(e.c_cov(2, 2)) / e.c_P.z();
      CHECK(std::isfinite(inverseDepthInterval(rel)));
    }
  }
  CHECK(degenerate > static_cast<int>(est.size()) / 2);
}

TEST_CASE("window with per-pose motion noise on arm scenes is near the joint bound", "[window][6dof][montecarlo]")
{
  const CameraModel camera = CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480);
  const YawRig rig(vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818));
  NoiseModel noise = paperNoise();
  noise.sigma_yaw = 0;
  noise.motion_noise = MotionNoise::Absolute;
  Stats st;
  for (int t = 0; t < 15; ++t) {
    SceneOptions so = paperScene(0, 0, 16, 500 + static_cast<std::uint64_t>(t));
    so.noise = noise;
    so.min_depth = 0.4;
    so.max_depth = 0.8;
    so.vision_poses = armTrajectory(rig, ArmPath::Orbit, so.frames, 0.6, so.seed);
    const Scene s = simulateScene(camera, rig, so);
    const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
    WindowOptions o;
    o.noise = noise;
    o.window = 6;
    const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, s.tracks, o);
    for (std::size_t i = 0; i < s.tracks.size(); ++i)
      if (est[i].ok() && crlb[i] > 0 && std::isfinite(crlb[i]))
        st.add(est[i].c_P.z() - truthAtLast(s, rig, s.tracks[i]).z(), crlb[i], est[i].sigmaZ());
  }
  INFO("RMSE/CRLB " << st.ratio() << ", coverage " << st.coverage() << ", n " << st.n);
  CHECK(st.n > 300);
  CHECK(st.ratio() < 1.5);
  CHECK(st.coverage() > kMinCoverage);
}

TEST_CASE_METHOD(PaperSetup, "window does not drift over a long sequence (features appearing and vanishing)", "[window][montecarlo]")
{
  // Normalised squared errors of the first and the last third of a 300-frame drive past a wall.
  double nees[3] = {0, 0, 0};
  int n[3] = {0, 0, 0};
  for (int t = 0; t < 3; ++t) {
    std::mt19937_64 rng(40 + static_cast<std::uint64_t>(t));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    SceneOptions so = paperScene(60 * kDeg, 0.0, 300, 40 + static_cast<std::uint64_t>(t));
    for (int i = 0; i < 300; ++i)
      so.world_points.emplace_back(1.5 + 1.5 * u(rng), -0.3 + 0.6 * u(rng), -1.0 + 10.0 * u(rng));
    const Scene s = simulateScene(camera, rig, so);
    WindowOptions o;
    o.noise = noise;
    const std::vector<PointEstimate> est = windowTracks(camera, rig, s.measured, s.tracks, o);
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      if (!est[i].ok())
        continue;
      const double e = est[i].c_P.z() - truthAtLast(s, rig, s.tracks[i]).z();
      const int third = static_cast<int>(std::min<long>(2, s.tracks[i].observations.back().frame / 100));
      nees[third] += (e / est[i].sigmaZ()) * (e / est[i].sigmaZ());
      ++n[third];
    }
  }
  for (int k = 0; k < 3; ++k) {
    INFO("third " << k << ": NEES " << nees[k] / n[k] << " over " << n[k] << " points");
    CHECK(n[k] > 100);
    CHECK(nees[k] / n[k] < 3.0); // without first-estimate Jacobians it grows past 10 here
  }
}

TEST_CASE_METHOD(PaperSetup, "window models the tracker's correlated errors (AR(1)): honest where independence is not",
                 "[window][montecarlo]")
{
  constexpr double kPhi = 0.9, kSigmaPx = 1.0; // the pixels' errors dominate the odometry's here
  // The marginalised chain against the whole track in the window: the same sigma to this share
  // (first-estimate Jacobians and the prior's dropped directions, 1e-5 of a point's information here).
  constexpr double kSigmaAgreement = 0.03;
  constexpr double kHonestCoverage = 0.90; // docs/method.md's band is 0.90 to 0.98
  Stats white, modelled, whole_stats;
  double sum_sq_white = 0, sum_sq_modelled = 0;
  std::vector<double> sigma_ratio;
  for (int t = 0; t < 30; ++t) {
    const Scene s = trackerErrorScene(camera, rig, kSigmaPx, kPhi, 300 + static_cast<std::uint64_t>(t));
    const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
    WindowOptions o;
    o.noise = noise;
    o.noise.sigma_px = kSigmaPx;
    o.window = 8; // 12 of the 20 frames are marginalised, with their chains' links
    const std::vector<PointEstimate> w = windowTracks(camera, rig, s.measured, s.tracks, o);
    o.noise.pixel_correlation = kPhi;
    const std::vector<PointEstimate> m = windowTracks(camera, rig, s.measured, s.tracks, o);
    o.window = 25; // every frame in the window: nothing marginalised
    const std::vector<PointEstimate> whole = windowTracks(camera, rig, s.measured, s.tracks, o);
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      if (!w[i].ok() || !m[i].ok() || !whole[i].ok() || !(crlb[i] > 0) || !std::isfinite(crlb[i]))
        continue;
      const double z = truthAtLast(s, rig, s.tracks[i]).z();
      white.add(w[i].c_P.z() - z, crlb[i], w[i].sigmaZ());
      modelled.add(m[i].c_P.z() - z, crlb[i], m[i].sigmaZ());
      whole_stats.add(whole[i].c_P.z() - z, crlb[i], whole[i].sigmaZ());
      sum_sq_white += std::pow(w[i].c_P.z() - z, 2);
      sum_sq_modelled += std::pow(m[i].c_P.z() - z, 2);
      sigma_ratio.push_back(m[i].sigmaZ() / whole[i].sigmaZ());
    }
  }
  std::sort(sigma_ratio.begin(), sigma_ratio.end());
  const double median_ratio = sigma_ratio[sigma_ratio.size() / 2];
  INFO("independent model: coverage " << white.coverage() << "; AR(1) model: coverage " << modelled.coverage()
                                       << ", RMSE " << std::sqrt(sum_sq_modelled / modelled.n) << " against "
                                       << std::sqrt(sum_sq_white / white.n) << "; sigma marginalised / whole "
                                       << median_ratio << " over " << modelled.n << " points; whole window: coverage "
                                       << whole_stats.coverage());
  REQUIRE(modelled.n > 400);
  CHECK(white.coverage() < kHonestCoverage); // the independent model is overconfident on these errors
  CHECK(modelled.coverage() > kMinCoverage);
  CHECK(modelled.coverage() < kMaxCoverage);
  CHECK(sum_sq_modelled <= 1.02 * sum_sq_white); // the right weights cost no accuracy
  CHECK(std::abs(median_ratio - 1.0) < kSigmaAgreement);
}

TEST_CASE_METHOD(PaperSetup, "window's AR(1) chains across gaps and gross outliers: the marginalised chain as the whole track",
                 "[window][montecarlo]")
{
  // Every track loses a seeded 15 % of its observations (gaps: phi^gap) and 3 % are moved 40 px
  // (flagged, the chain skips them). The estimate with 12 of the 20 frames marginalised must agree
  // with the one that keeps every frame, and stay honest.
  constexpr double kPhi = 0.9, kSigmaPx = 1.0, kDrop = 0.15, kGross = 0.03, kGrossPx = 40.0;
  constexpr double kSigmaAgreement = 0.05; // wider than without gaps: flags can differ between the two runs
  Stats marginalised;
  std::vector<double> sigma_ratio;
  std::mt19937_64 rng(91);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int t = 0; t < 20; ++t) {
    Scene s = trackerErrorScene(camera, rig, kSigmaPx, kPhi, 500 + static_cast<std::uint64_t>(t));
    for (Track &tr : s.tracks) {
      std::vector<Observation> kept;
      for (std::size_t k = 0; k < tr.observations.size(); ++k) {
        Observation ob = tr.observations[k];
        const bool end = k == 0 || k + 1 == tr.observations.size();
        if (!end && u(rng) < kDrop)
          continue;
        if (!end && u(rng) < kGross)
          ob.u += kGrossPx;
        kept.push_back(ob);
      }
      tr.observations = kept;
    }
    const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
    WindowOptions o;
    o.noise = noise;
    o.noise.sigma_px = kSigmaPx;
    o.noise.pixel_correlation = kPhi;
    o.window = 8;
    const std::vector<PointEstimate> m = windowTracks(camera, rig, s.measured, s.tracks, o);
    o.window = 25;
    const std::vector<PointEstimate> whole = windowTracks(camera, rig, s.measured, s.tracks, o);
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      if (!m[i].ok() || !whole[i].ok() || !(crlb[i] > 0) || !std::isfinite(crlb[i]))
        continue;
      marginalised.add(m[i].c_P.z() - truthAtLast(s, rig, s.tracks[i]).z(), crlb[i], m[i].sigmaZ());
      sigma_ratio.push_back(m[i].sigmaZ() / whole[i].sigmaZ());
    }
  }
  REQUIRE(marginalised.n > 300);
  std::vector<Track> tracks;
  CHECK_THROWS_AS(addTrackerErrors(tracks, -1.0, kPhi, 1), Error); // bad input: an Error, never a NaN
  CHECK_THROWS_AS(addTrackerErrors(tracks, kSigmaPx, 1.0, 1), Error);
  std::sort(sigma_ratio.begin(), sigma_ratio.end());
  const double median_ratio = sigma_ratio[sigma_ratio.size() / 2];
  INFO("coverage " << marginalised.coverage() << ", sigma marginalised / whole " << median_ratio << " over "
                   << marginalised.n << " points");
  CHECK(marginalised.coverage() > kMinCoverage);
  CHECK(marginalised.coverage() < kMaxCoverage);
  CHECK(std::abs(median_ratio - 1.0) < kSigmaAgreement);
}

TEST_CASE("window rejects bad input", "[window]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  WindowOptions bad;
  bad.window = 1;
  CHECK_THROWS_AS(WindowEstimator(camera, rig, bad), Error);
  bad = WindowOptions();
  bad.noise.sigma_px = 0;
  CHECK_THROWS_AS(WindowEstimator(camera, rig, bad), Error);
  bad = WindowOptions();
  bad.outlier_threshold_px = std::nan("");
  CHECK_THROWS_AS(WindowEstimator(camera, rig, bad), Error);

  WindowEstimator est(camera, rig);
  MotionSample a;
  a.frame = 5;
  est.addFrame(a, {});
  CHECK_THROWS_AS(est.addFrame(a, {}), Error); // not increasing
  MotionSample b = a;
  b.frame = 6;
  CHECK_THROWS_AS(est.addFrame(b, {FeatureObservation{1, 10, 10}, FeatureObservation{1, 20, 20}}), Error);
  MotionSample c = MotionSample::fromPose(7, vpHomogeneousMatrix());
  CHECK_THROWS_AS(est.addFrame(c, {}), Error); // 6-DoF after planar
  MotionSample d = a;
  d.frame = 8;
  const auto res = est.addFrame(d, {FeatureObservation{2, std::nan(""), 10}, FeatureObservation{3, 1e9, 1e9}});
  REQUIRE(res.size() == 2);
  CHECK_FALSE(res[0].undistorted);
  CHECK_FALSE(res[1].undistorted);
  CHECK_THROWS_AS(est.motion(1), Error);
  CHECK(est.motion(8).frame == 8);

  // windowTracks: a frame missing from the log, a repeated id.
  const Scene s = simulateScene(camera, rig, paperScene(0.0, 0.0, 4, 1, false));
  std::vector<Track> tracks = s.tracks;
  tracks[0].observations.push_back(Observation{999, 100, 100});
  CHECK_THROWS_AS(windowTracks(camera, rig, s.measured, tracks), Error);
  tracks = s.tracks;
  tracks[1].id = tracks[0].id;
  CHECK_THROWS_AS(windowTracks(camera, rig, s.measured, tracks), Error);
}
