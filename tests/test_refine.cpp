// `refine`: batch MAP refinement of points with odometry and yaw priors, and the Cramér–Rao bound.
// Noise-free exactness, residual Jacobians, Monte Carlo efficiency and honesty of sigma_zc against
// the bound, gross outliers, a brute-force check of the bound, initialisation, and speed.
// refine's Ceres cost functors of the tracker's correlated errors (private; built with Ceres only),
// before Catch: Ceres brings glog, whose CHECK macro would otherwise replace Catch's.
#ifdef YAWDEPTH_TEST_CHAIN_COSTS
#include "costs/innovation_costs.h"
#include <memory>
#undef CHECK
#endif

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>
#include <yawdepth/error.h>
#include <yawdepth/refine/refine.h>
#include <yawdepth/simulation/scene.h>

// The model's templated residuals (private to the module, header-only, no Ceres): the same
// templates the solver instantiates with ceres::Jet and the information matrix with Eigen's AutoDiff.
#include "refine_model.h"
#include <Eigen/LU>
#include <unsupported/Eigen/AutoDiff>

#include "scene_support.h"


using namespace yawdepth;
using namespace yawdepth::test;

namespace {

constexpr double kDeg = M_PI / 180.0;

// Targets (the test's acceptance bounds are a little looser than docs/method.md's pooled 1.10
// because it runs fewer trials).
constexpr double kMaxRmseOverCrlb = 1.15;
constexpr double kMinCoverage2Sigma = 0.88, kMaxCoverage2Sigma = 0.99;
constexpr double kMaxOutlierRmseOverCrlb = 1.3;
constexpr double kMinRecall = 0.9, kMinPrecision = 0.9;

/* The paper's scenes here: 10 frames (paperScene()). */
constexpr int kFrames = 10;

std::size_t rowOfFrame(const Scene &s, long frame)
{
  for (std::size_t r = 0; r < s.truth.size(); ++r)
    if (s.truth[r].frame == frame)
      return r;
  return s.truth.size();
}

/* True camera-frame point of a track at its last observed frame. */
Eigen::Vector3d truePoint(const Scene &s, const YawRig &rig, std::size_t i)
{
  return s.cameraPoint(rig, s.tracks[i].id, rowOfFrame(s, s.tracks[i].observations.back().frame));
}

using Stats = CrlbStats;

/* The pooled Monte Carlo figures every efficiency test holds refine to. */
void checkPooledAgainstCrlb(const Stats &pooled)
{
  CHECK(pooled.ratio() <= kMaxRmseOverCrlb);
  CHECK(pooled.coverage() >= kMinCoverage2Sigma);
  CHECK(pooled.coverage() <= kMaxCoverage2Sigma);
}

/* An automatic-differentiation scalar with N derivatives, and N values seeded as the variables. */
template <int N> using AutoDiff = Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>>;
template <int N> std::array<AutoDiff<N>, N> seededVariables(const double *x)
{
  std::array<AutoDiff<N>, N> a;
  for (int i = 0; i < N; ++i)
    a[i] = AutoDiff<N>(x[i], N, i);
  return a;
}

/* Checks the derivatives in `ad`, the M residuals of `residual(const double *x, double *r)` at the N
   values `x`, against central differences of step h: each within margin * (1 + |fd|), and within
   `epsilon` relative (Catch's default Approx epsilon unless given). */
template <int N, int M, class Residual>
void checkAgainstCentralDifferences(const AutoDiff<N> (&ad)[M], const double *x, double h, const Residual &residual,
                                    double margin, double epsilon = std::numeric_limits<float>::epsilon() * 100)
{
  for (int i = 0; i < N; ++i) {
    double xp[N], xm[N], rp[M], rm[M];
    std::copy(x, x + N, xp);
    std::copy(x, x + N, xm);
    xp[i] += h;
    xm[i] -= h;
    residual(xp, rp);
    residual(xm, rm);
    for (int k = 0; k < M; ++k) {
      const double fd = (rp[k] - rm[k]) / (2 * h);
      CHECK(ad[k].derivatives()(i) == Approx(fd).margin(margin * (1 + std::abs(fd))).epsilon(epsilon));
    }
  }
}

/* Central-difference Jacobian of the vector function f at th, step eps. */
template <class F> Eigen::MatrixXd centralJacobian(const F &f, const Eigen::VectorXd &th, double eps)
{
  Eigen::MatrixXd J(f(th).size(), th.size());
  for (Eigen::Index k = 0; k < th.size(); ++k) {
    Eigen::VectorXd tp = th, tm = th;
    tp(k) += eps;
    tm(k) -= eps;
    J.col(k) = (f(tp) - f(tm)) / (2 * eps);
  }
  return J;
}

/* Central-difference gradient of the scalar function f at th, step eps. */
template <class F> Eigen::VectorXd centralGradient(const F &f, const Eigen::VectorXd &th, double eps)
{
  const auto asVector = [&](const Eigen::VectorXd &t) -> Eigen::VectorXd { return Eigen::VectorXd::Constant(1, f(t)); };
  return centralJacobian(asVector, th, eps).row(0).transpose();
}

/* A whitened observation at (0.05, -0.02) whose whitening matrix is near diag(s00, s11). */
refine_detail::WhitenedObservation randomWhitening(double s00, double s11, std::uniform_real_distribution<double> &U,
                                                   std::mt19937_64 &rng)
{
  refine_detail::WhitenedObservation w;
  w.m[0] = 0.05;
  w.m[1] = -0.02;
  w.s00 = s00 + 100 * U(rng);
  w.s01 = 50 * U(rng);
  w.s11 = s11 + 100 * U(rng);
  return w;
}

/* A brute-force bound on each of `count` depths: h(theta) the whitened measurements, depth(i, theta)
   the i-th depth. The covariance C is the inverse of the Fisher information J^T J, J the central-
   difference Jacobian of h at th; each depth's bound is sqrt(g^T C g), g its central-difference
   gradient there. Steps eps. */
template <class H, class Depth>
std::vector<double> boundsFromFisher(const H &h, const Depth &depth, const Eigen::VectorXd &th, double eps, int count)
{
  const Eigen::MatrixXd J = centralJacobian(h, th, eps);
  const Eigen::MatrixXd C = (J.transpose() * J).inverse();
  std::vector<double> out(count);
  for (int i = 0; i < count; ++i) {
    const Eigen::VectorXd g = centralGradient([&](const Eigen::VectorXd &t) { return depth(i, t); }, th, eps);
    out[i] = std::sqrt(g.dot(C * g));
  }
  return out;
}

/* The world points held in th from index `first` on, 3 coordinates each (a brute-force bound's unknowns). */
std::vector<Eigen::Vector3d> pointsIn(const Eigen::VectorXd &th, int first, int count)
{
  std::vector<Eigen::Vector3d> P(count);
  for (int i = 0; i < count; ++i)
    P[i] = th.segment<3>(first + 3 * i);
  return P;
}

/* Appends the whitened pixel of the camera-frame point c to the measurements z. */
void addWhitenedPixel(std::vector<double> &z, const CameraModel &camera, const Eigen::Vector3d &c, double sigma_px)
{
  const Eigen::Vector2d uv = camera.project(c.head<2>() / c.z());
  z.push_back(uv.x() / sigma_px);
  z.push_back(uv.y() / sigma_px);
}

/* Checks depthCramerRao's joint bound against `brute` (a brute-force Fisher information's) for
   every track seen in two frames or more and, with `per_point_too`, that it is no larger than the
   per-point bound. */
void checkJointBound(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &truth,
                     const std::vector<Track> &tracks, const std::vector<Eigen::Vector3d> &w_points,
                     const NoiseModel &noise, const std::vector<double> &brute, bool per_point_too)
{
  const std::vector<double> joint = depthCramerRao(camera, rig, truth, tracks, w_points, noise, true);
  const std::vector<double> alone =
      per_point_too ? depthCramerRao(camera, rig, truth, tracks, w_points, noise, false) : std::vector<double>();
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    if (tracks[i].observations.size() < 2)
      continue;
    REQUIRE(std::isfinite(joint[i]));
    CHECK(joint[i] == Approx(brute[i]).epsilon(1e-4));
    if (per_point_too)
      CHECK(joint[i] <= alone[i] * (1 + 1e-12));
  }
}

} // namespace

namespace {

/* In a build without Ceres, refineWindow() reports `unavailable` for every track; the tests that
   need the solver check that and stop. */
bool unavailableChecked()
{
  if (refineAvailable())
    return false;
  const Scene s = simulateScene(paperCamera(), paperRig(), paperScene(0.0, 0.0, kFrames, 1, false));
  const RefineResult r = refineWindow(paperCamera(), paperRig(), s.measured, s.tracks, {});
  CHECK_FALSE(r.available);
  REQUIRE(r.points.size() == s.tracks.size());
  for (const PointEstimate &e : r.points)
    CHECK(e.status == Status::Unavailable);
  return true;
}

} // namespace

TEST_CASE("refine reports whether it is available", "[refine]")
{
  if (unavailableChecked())
    return;
  const Scene s = simulateScene(paperCamera(), paperRig(), paperScene(0.0, 0.0, kFrames, 1, false));
  CHECK(refineWindow(paperCamera(), paperRig(), s.measured, s.tracks, {}).available);
}


TEST_CASE_METHOD(PaperSetup, "refine returns the truth on noise-free scenes", "[refine]")
{
  if (unavailableChecked())
    return;
  for (double yaw : {0.0, 45 * kDeg, 90 * kDeg}) {
    Scene s = simulateScene(camera, rig, paperScene(yaw, 1 * kDeg, kFrames, 7, false));
    // A track seen once: too_few_frames.
    Track single;
    single.id = 1000;
    single.observations.push_back(s.tracks[0].observations.front());
    s.tracks.push_back(single);
    RefineOptions opt; // the noise model of the issue; the data happen to be exact
    opt.noise = paperNoise();
    const RefineResult r = refineWindow(camera, rig, s.measured, s.tracks, {}, opt);
    REQUIRE(r.available);
    REQUIRE(r.points.size() == s.tracks.size());
    CHECK(r.points.back().status == Status::TooFewFrames);
    int ok = 0;
    for (std::size_t i = 0; i + 1 < s.tracks.size(); ++i) {
      if (!r.points[i].ok())
        continue;
      ++ok;
      const Eigen::Vector3d truth = truePoint(s, rig, i);
      CHECK((r.points[i].c_P - truth).norm() / truth.norm() < 1e-6);
      CHECK(r.points[i].frame == s.tracks[i].observations.back().frame);
      for (bool f : r.outliers[i])
        CHECK_FALSE(f);
      CHECK(std::isfinite(r.points[i].sigmaZ()));
    }
    CHECK(ok >= 28);
    for (std::size_t k = 0; k < s.truth.size(); ++k) {
      CHECK(std::abs(r.motion[k].x - s.truth[k].x) < 1e-9);
      CHECK(std::abs(r.motion[k].z - s.truth[k].z) < 1e-9);
      CHECK(std::abs(r.motion[k].heading - s.truth[k].heading) < 1e-9);
      CHECK(std::abs(r.motion[k].yaw - s.truth[k].yaw) < 1e-9);
    }
  }
}

TEST_CASE_METHOD(PaperSetup, "refine rejects inconsistent input", "[refine]")
{
  if (unavailableChecked())
    return;
  const Scene s = simulateScene(camera, rig, paperScene(0.0, 0.0, kFrames, 3, false));
  std::vector<PointEstimate> wrong(s.tracks.size() + 1);
  CHECK_THROWS_AS(refineWindow(camera, rig, s.measured, s.tracks, wrong), Error);
  std::vector<Track> unknown = s.tracks;
  unknown[0].observations.back().frame = 999;
  CHECK_THROWS_AS(refineWindow(camera, rig, s.measured, unknown, {}), Error);
}

TEST_CASE("refine residual Jacobians match central finite differences", "[refine]")
{
  using refine_detail::WhitenedObservation;
  constexpr int N = 13; // point(3), pose_a(4), yaw_a(1), pose_k(4), yaw_k(1)
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double t0[3] = {-0.1503, 0.01, 0.02};
  for (int trial = 0; trial < 20; ++trial) {
    double x[N] = {0.1 * U(rng), 0.1 * U(rng), 0.5 + 0.3 * U(rng),    // alpha, beta, rho
                   0.1 * U(rng), 0.01 * U(rng), 0.1 * U(rng), 0.3 * U(rng), 0.5 * U(rng),
                   0.1 * U(rng), 0.01 * U(rng), 0.2 + 0.1 * U(rng), 0.3 * U(rng), 0.5 * U(rng)};
    const WhitenedObservation w = randomWhitening(5000, 5200, U, rng);
    auto eval = [&](const double *v, double *r) {
      REQUIRE(refine_detail::reprojectionResidual(v + 3, v + 7, v + 8, v + 12, v, t0, w, r));
    };
    const std::array<AutoDiff<N>, N> xa = seededVariables<N>(x);
    const AutoDiff<N> *xv = xa.data();
    AutoDiff<N> ra[2];
    REQUIRE(refine_detail::reprojectionResidual(xv + 3, xv + 7, xv + 8, xv + 12, xv, t0, w, ra));
    double r0[2];
    eval(x, r0);
    CHECK(ra[0].value() == Approx(r0[0]));
    checkAgainstCentralDifferences(ra, x, 1e-6, eval, 1e-5, 1e-6);
    // The anchored point agrees with the plain frame chain: world point through wMc.
    const double rho = x[2];
    const Eigen::Vector3d Pa = Eigen::Vector3d(x[0], x[1], 1.0) / rho;
    const Eigen::Vector3d t0v(t0[0], t0[1], t0[2]);
    const Eigen::Matrix3d Ra = rotY(x[6] + x[7]), Rk = rotY(x[11] + x[12]);
    const Eigen::Vector3d Pw = Ra * Pa + Eigen::Vector3d(x[3], x[4], x[5]) + Ra * t0v;
    const Eigen::Vector3d Pk = Rk.transpose() * (Pw - Eigen::Vector3d(x[8], x[9], x[10]) - Rk * t0v);
    double q[3];
    refine_detail::anchoredPoint(x + 3, x + 7, x + 8, x + 12, x, t0, q);
    CHECK((Eigen::Vector3d(q[0], q[1], q[2]) / rho - Pk).norm() < 1e-12);

    // Odometry residual.
    refine_detail::OdometryMeasurement om;
    om.d[0] = 0.001;
    om.d[2] = 0.02;
    om.dh = 0.01;
    om.inv_sigma_t = 1000;
    om.inv_sigma_h = 1.0 / (0.05 * kDeg);
    double poses[8]; // pose_a, pose_k
    for (int i = 0; i < 8; ++i)
      poses[i] = x[3 + (i < 4 ? i : i + 1)];
    const std::array<AutoDiff<8>, 8> pa = seededVariables<8>(poses);
    AutoDiff<8> ro[4];
    refine_detail::odometryResidual(pa.data(), pa.data() + 4, om, ro);
    checkAgainstCentralDifferences(
        ro, poses, 1e-6, [&](const double *p, double *r) { refine_detail::odometryResidual(p, p + 4, om, r); }, 1e-4);
  }
}

namespace {

struct McScene {
  const char *name;
  double yaw, turn_rate;
};
const McScene kScenes[] = {{"front straight", 0.0, 0.0},       {"front turning", 0.0, 1 * kDeg},
                           {"oblique straight", 45 * kDeg, 0.0}, {"oblique turning", 45 * kDeg, 1 * kDeg},
                           {"side straight", 90 * kDeg, 0.0},    {"side turning", 90 * kDeg, 1 * kDeg}};

/* Replace about `fraction` of the observations by gross errors of 10 to 50 px; returns the flags. */
std::vector<std::vector<bool>> addGrossErrors(Scene &s, double fraction, std::mt19937_64 &rng)
{
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<std::vector<bool>> truth(s.tracks.size());
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    truth[i].assign(s.tracks[i].observations.size(), false);
    for (std::size_t j = 0; j < s.tracks[i].observations.size(); ++j) {
      if (!(U(rng) < fraction))
        continue;
      const double mag = 10 + 40 * U(rng), dir = 2 * M_PI * U(rng);
      Observation &ob = s.tracks[i].observations[j];
      ob.u += mag * std::cos(dir);
      ob.v += mag * std::sin(dir);
      truth[i][j] = true;
    }
  }
  return truth;
}

} // namespace

TEST_CASE_METHOD(PaperSetup, "refine is efficient and its sigma_zc honest (Monte Carlo against the CRLB)", "[refine][montecarlo]")
{
  if (unavailableChecked())
    return;
  // Motion errors are shared by a trial's points, so the per-scene figures are loose checks (25
  // trials); the pooled ones over 6 x 25 trials are the tight ones. bench_accuracy runs 200 per scene.
  constexpr int kTrials = 25;
  Stats pooled;
  for (const McScene &sc : kScenes) {
    Stats st;
    for (int trial = 0; trial < kTrials; ++trial) {
      const Scene s = simulateScene(camera, rig, paperScene(sc.yaw, sc.turn_rate, kFrames, 1000 + trial));
      RefineOptions opt;
      opt.noise = noise;
      const RefineResult r = refineWindow(camera, rig, s.measured, s.tracks, {}, opt);
      const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
      for (std::size_t i = 0; i < s.tracks.size(); ++i) {
        if (s.tracks[i].observations.size() < 2)
          continue;
        if (!r.points[i].ok()) {
          ++st.failed;
          continue;
        }
        const double err = r.points[i].c_P.z() - truePoint(s, rig, i).z();
        st.add(err, crlb[i], r.points[i].sigmaZ());
        pooled.add(err, crlb[i], r.points[i].sigmaZ());
      }
    }
    std::printf("refine MC %-17s: RMSE/CRLB %.3f, 2-sigma coverage %.3f, failed %d of %d\n", sc.name, st.ratio(),
                st.coverage(), st.failed, st.n + st.failed);
    CHECK(st.ratio() <= 1.25);
    CHECK(st.coverage() >= 0.85);
    CHECK(st.failed == 0);
  }
  std::printf("refine MC pooled           : RMSE/CRLB %.3f, 2-sigma coverage %.3f over %d depths\n", pooled.ratio(),
              pooled.coverage(), pooled.n);
  checkPooledAgainstCrlb(pooled);
}

TEST_CASE_METHOD(PaperSetup, "refine flags gross outliers and stays near the inlier bound", "[refine][outliers]")
{
  if (unavailableChecked())
    return;
  std::mt19937_64 rng(2024);
  int tp = 0, fp = 0, fn = 0;
  Stats pooled;
  constexpr int kTrials = 15;
  for (const McScene &sc : kScenes) {
    for (int trial = 0; trial < kTrials; ++trial) {
      Scene s = simulateScene(camera, rig, paperScene(sc.yaw, sc.turn_rate, kFrames, 5000 + trial));
      const std::vector<std::vector<bool>> gross = addGrossErrors(s, 0.05, rng);
      RefineOptions opt;
      opt.noise = noise;
      const RefineResult r = refineWindow(camera, rig, s.measured, s.tracks, {}, opt);
      // The inlier bound: the same tracks without their gross observations.
      std::vector<Track> inliers = s.tracks;
      for (std::size_t i = 0; i < inliers.size(); ++i) {
        inliers[i].observations.clear();
        for (std::size_t j = 0; j < s.tracks[i].observations.size(); ++j)
          if (!gross[i][j])
            inliers[i].observations.push_back(s.tracks[i].observations[j]);
      }
      const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, inliers, s.w_points, noise, true);
      for (std::size_t i = 0; i < s.tracks.size(); ++i) {
        for (std::size_t j = 0; j < gross[i].size(); ++j) {
          tp += gross[i][j] && r.outliers[i][j] ? 1 : 0;
          fp += !gross[i][j] && r.outliers[i][j] ? 1 : 0;
          fn += gross[i][j] && !r.outliers[i][j] ? 1 : 0;
        }
        if (!r.points[i].ok() || !std::isfinite(crlb[i]))
          continue;
        // The depth at the track's last frame (which may itself be an outlier observation).
        const double err = r.points[i].c_P.z() - truePoint(s, rig, i).z();
        if (inliers[i].observations.back().frame != s.tracks[i].observations.back().frame)
          continue; // the bound is for another frame's depth
        pooled.add(err, crlb[i], r.points[i].sigmaZ());
      }
    }
  }
  const double recall = double(tp) / std::max(tp + fn, 1), precision = double(tp) / std::max(tp + fp, 1);
  std::printf("refine outliers: recall %.3f, precision %.3f (%d gross), RMSE/CRLB(inliers) %.3f, coverage %.3f\n",
              recall, precision, tp + fn, pooled.ratio(), pooled.coverage());
  CHECK(tp + fn > 100);
  CHECK(recall >= kMinRecall);
  CHECK(precision >= kMinPrecision);
  CHECK(pooled.ratio() <= kMaxOutlierRmseOverCrlb);
}

// The speed of this problem is measured by bench_accuracy (section 3, SPEED), not by a timed test:
// here, that it converges, and in few iterations, every time.
TEST_CASE_METHOD(PaperSetup, "refine: 30 points x 10 frames converge in few iterations", "[refine]")
{
  if (unavailableChecked())
    return;
  RefineOptions opt;
  opt.noise = paperNoise();
  opt.threads = 1;
  constexpr int kMaxIterations = 20;
  for (std::uint64_t seed : {77u, 78u, 79u}) {
    const Scene s = simulateScene(camera, rig, paperScene(45 * kDeg, 1 * kDeg, kFrames, seed));
    const RefineResult r = refineWindow(camera, rig, s.measured, s.tracks, {}, opt);
    REQUIRE(r.converged);
    CHECK(r.iterations <= kMaxIterations);
  }
}

namespace {

/* Brute-force Fisher information of the measurement model, independent of the module's code:
   parameters are the world points (3 each), the poses of rows >= 1 (x, y, z, heading) and every
   yaw; measurements the observed pixels (through ViSP's frames and the camera's distortion), the
   odometry increments and the yaw readings, each divided by its sigma. Central differences. */
std::vector<double> bruteForceCrlb(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &truth,
                                   const std::vector<Track> &tracks, const std::vector<Eigen::Vector3d> &w_points,
                                   const NoiseModel &n)
{
  const int rows = static_cast<int>(truth.size()), np = static_cast<int>(w_points.size());
  const int nl = 4 * (rows - 1) + rows, nth = nl + 3 * np;
  auto unpack = [&](const Eigen::VectorXd &th) {
    std::vector<MotionSample> m = truth;
    for (int r = 1; r < rows; ++r) {
      m[r].x = th(4 * (r - 1));
      m[r].y = th(4 * (r - 1) + 1);
      m[r].z = th(4 * (r - 1) + 2);
      m[r].heading = th(4 * (r - 1) + 3);
    }
    for (int r = 0; r < rows; ++r)
      m[r].yaw = th(4 * (rows - 1) + r);
    return std::make_pair(m, pointsIn(th, nl, np));
  };
  auto camPoint = [&](const MotionSample &s, const Eigen::Vector3d &Pw) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    fromVisp(wMc(rig, s).inverse(), R, t);
    return Eigen::Vector3d(R * Pw + t);
  };
  auto h = [&](const Eigen::VectorXd &th) {
    const auto [m, P] = unpack(th);
    std::vector<double> z;
    for (int i = 0; i < np; ++i) {
      std::size_t prev_row = 0;
      double prev[2] = {0, 0}; // the previous observation's whitened pixel
      for (const Observation &ob : tracks[i].observations) {
        const std::size_t row = rowOfFrame(Scene{truth, truth, {}, {}}, ob.frame);
        addWhitenedPixel(z, camera, camPoint(m[row], P[i]), n.sigma_px);
        const std::size_t k = z.size() - 2;
        const double cur[2] = {z[k], z[k + 1]};
        if (n.pixel_correlation > 0 && &ob != &tracks[i].observations.front()) {
          // AR(1) errors: the innovation of the pixel on the track's previous one, per axis.
          const double a = std::pow(n.pixel_correlation, static_cast<double>(row - prev_row));
          for (std::size_t j = 0; j < 2; ++j)
            z[k + j] = (cur[j] - a * prev[j]) / std::sqrt(1.0 - a * a);
        }
        std::copy(cur, cur + 2, prev);
        prev_row = row;
      }
    }
    for (int r = 1; r < rows; ++r) {
      const Eigen::Vector3d d =
          rotY(m[r - 1].heading).transpose() * Eigen::Vector3d(m[r].x - m[r - 1].x, m[r].y - m[r - 1].y, m[r].z - m[r - 1].z);
      for (int k = 0; k < 3; ++k)
        z.push_back(d(k) / n.sigma_odom);
      z.push_back((m[r].heading - m[r - 1].heading) / n.sigma_heading);
    }
    for (int r = 0; r < rows; ++r)
      z.push_back(m[r].yaw / n.sigma_yaw);
    return Eigen::Map<Eigen::VectorXd>(z.data(), z.size()).eval();
  };
  Eigen::VectorXd th(nth);
  for (int r = 1; r < rows; ++r)
    th.segment<4>(4 * (r - 1)) << truth[r].x, truth[r].y, truth[r].z, truth[r].heading;
  for (int r = 0; r < rows; ++r)
    th(4 * (rows - 1) + r) = truth[r].yaw;
  for (int i = 0; i < np; ++i)
    th.segment<3>(nl + 3 * i) = w_points[i];
  auto depth = [&](int i, const Eigen::VectorXd &t) { // at the track's last frame
    const auto [m, P] = unpack(t);
    return camPoint(m[rowOfFrame(Scene{truth, truth, {}, {}}, tracks[i].observations.back().frame)], P[i]).z();
  };
  return boundsFromFisher(h, depth, th, 1e-6, np);
}

} // namespace

TEST_CASE_METHOD(PaperSetup, "depthCramerRao matches a brute-force Fisher information; joint <= per point", "[refine][crlb]")
{
  for (const McScene &sc : {kScenes[1], kScenes[3], kScenes[4]}) {
    SceneOptions so = paperScene(sc.yaw, sc.turn_rate, kFrames, 99, false);
    so.frames = 4;
    so.points = 5;
    const Scene s = simulateScene(camera, rig, so);
    const std::vector<double> brute = bruteForceCrlb(camera, rig, s.truth, s.tracks, s.w_points, noise);
    checkJointBound(camera, rig, s.truth, s.tracks, s.w_points, noise, brute, true);
  }
  // The bigger scene of the issue: joint <= per point everywhere, and the joint bound is tighter
  // on average (the motion is shared).
  const Scene s = simulateScene(camera, rig, paperScene(0.0, 0.0, kFrames, 5, false));
  const std::vector<double> joint = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
  const std::vector<double> alone = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, false);
  double ratio = 0;
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    CHECK(joint[i] <= alone[i] * (1 + 1e-12));
    ratio += joint[i] / alone[i] / s.tracks.size();
  }
  CHECK(ratio < 0.9);
  // Tracks with one observation have no bound.
  std::vector<Track> one = s.tracks;
  one[0].observations.resize(1);
  CHECK(std::isnan(depthCramerRao(camera, rig, s.truth, one, s.w_points, noise, true)[0]));
}

TEST_CASE_METHOD(PaperSetup, "depthCramerRao with correlated tracker errors (AR(1)) matches a brute-force Fisher information",
                 "[refine][crlb][correlated]")
{
  // The bound whitens in normalised coordinates, the brute force in pixels: the two AR(1) models
  // differ by the change of the distortion's Jacobian between consecutive observations.
  constexpr double kAgreement = 1e-4; // as the independent bound against its brute force; measured 2e-5
  NoiseModel correlated = noise;
  correlated.pixel_correlation = 0.9;
  for (const McScene &sc : {kScenes[1], kScenes[3]}) {
    SceneOptions so = paperScene(sc.yaw, sc.turn_rate, kFrames, 99, false);
    so.frames = 5;
    so.points = 5;
    const Scene s = simulateScene(camera, rig, so);
    const std::vector<double> brute = bruteForceCrlb(camera, rig, s.truth, s.tracks, s.w_points, correlated);
    const std::vector<double> bound = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, correlated, true);
    const std::vector<double> white = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      if (s.tracks[i].observations.size() < 2)
        continue;
      REQUIRE(std::isfinite(bound[i]));
      CHECK(bound[i] == Approx(brute[i]).epsilon(kAgreement));
      CHECK(std::abs(bound[i] / white[i] - 1.0) > 10 * kAgreement); // the model changes the bound
    }
  }
}

TEST_CASE_METHOD(PaperSetup,
                 "depthCramerRao on a long log whose points each see a few frames (the banded solve) matches brute force",
                 "[refine][crlb][long]")
{
  // A robot driving past a wall for 80 frames, each point seen for at most half of them: the motion's
  // information is a band (pointCovariances' sparse Cholesky path), which must give the same
  // bound as the inverse of the whole Fisher information.
  SceneOptions so;
  so.frames = 80;
  so.step = 0.05;
  so.yaw = 60 * kDeg;
  so.seed = 7;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int i = 0; i < 30; ++i)
    so.world_points.emplace_back(1.5 + 1.0 * U(rng), -0.2 + 0.4 * U(rng), 1.0 + 3.5 * U(rng));
  const Scene s = simulateScene(camera, rig, so);
  std::vector<Track> tracks;
  std::vector<Eigen::Vector3d> points;
  std::size_t longest = 0;
  for (std::size_t i = 0; i < s.tracks.size(); ++i)
    if (s.tracks[i].observations.size() >= 2) {
      tracks.push_back(s.tracks[i]);
      points.push_back(s.w_points[static_cast<std::size_t>(s.tracks[i].id)]);
      longest = std::max(longest, s.tracks[i].observations.size());
    }
  REQUIRE(tracks.size() >= 12);
  INFO("longest track " << longest << " frames");
  REQUIRE(2 * longest < 80); // the band holds under half of the motion
  const std::vector<double> brute = bruteForceCrlb(camera, rig, s.truth, tracks, points, noise);
  checkJointBound(camera, rig, s.truth, tracks, points, noise, brute, false);
}

TEST_CASE_METHOD(PaperSetup, "refine converges without initial estimates on a side-view scene", "[refine][init]")
{
  if (unavailableChecked())
    return;
  RefineOptions opt;
  opt.noise = paperNoise();
  const Scene s = simulateScene(camera, rig, paperScene(90 * kDeg, 1 * kDeg, kFrames, 31));
  const std::vector<PointEstimate> none(s.tracks.size()); // every status too_few_frames
  REQUIRE(none.front().status == Status::TooFewFrames);
  std::vector<PointEstimate> truth(s.tracks.size());
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    truth[i].status = Status::Ok;
    truth[i].frame = s.tracks[i].observations.back().frame;
    truth[i].c_P = truePoint(s, rig, i);
  }
  const RefineResult a = refineWindow(camera, rig, s.measured, s.tracks, none, opt);
  const RefineResult b = refineWindow(camera, rig, s.measured, s.tracks, truth, opt);
  CHECK(a.converged);
  CHECK(b.converged);
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    REQUIRE(a.points[i].ok());
    REQUIRE(b.points[i].ok());
    const double z = truePoint(s, rig, i).z();
    CHECK(std::abs(a.points[i].c_P.z() - b.points[i].c_P.z()) < 1e-4 * z);
    CHECK(std::abs(a.points[i].c_P.z() - z) < 5 * a.points[i].sigmaZ());
    // v_P is c_P in the vision frame of the refined yaw.
    const Eigen::Vector3d v = rotY(a.motion[rowOfFrame(s, a.points[i].frame)].yaw) * (a.points[i].c_P + rig.cameraOffset());
    CHECK((v - a.points[i].v_P).norm() < 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------
// The general chain: 6-DoF logs (an arm) and camera mounts with a rotation.

namespace {

/* A wide camera as on an arm (the franka set's RealSense: 600 px, 640x480). */
CameraModel armCamera() { return CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480); }
/* A hand-eye mount like the franka set's eMc. */
YawRig armRig() { return YawRig(vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818)); }

/* Arm noise: 0.3 px, 1 mm and 0.05 deg per increment per axis, no pan joint (yaw exact). */
NoiseModel armNoise()
{
  NoiseModel n = paperNoise();
  n.sigma_yaw = 0.0;
  n.sigma_rot = 0.05 * kDeg;
  return n;
}

/* Per-pose arm noise (forward kinematics): millimetres, tenths of a degree, per pose. */
NoiseModel perPoseNoise()
{
  NoiseModel n = armNoise();
  n.motion_noise = MotionNoise::Absolute;
  n.sigma_odom = 2e-3;
  n.sigma_rot = 0.1 * kDeg;
  return n;
}

Scene armScene(ArmPath path, std::uint64_t seed, bool noisy, int frames = 10, int points = 30,
               const NoiseModel &noise = armNoise())
{
  SceneOptions o;
  o.frames = frames;
  o.points = points;
  o.min_depth = 0.4;
  o.max_depth = 0.8;
  o.vision_poses = armTrajectory(armRig(), path, frames, 0.6, seed);
  o.seed = seed;
  if (noisy)
    o.noise = noise;
  return simulateScene(armCamera(), armRig(), o);
}

/* One Monte Carlo trial on an arm scene: refine with `noise`, each depth's error against the joint
   bound into `st` (and `also`, when given); a track refine could not estimate counts as failed. */
void armTrial(const Scene &s, const NoiseModel &noise, Stats &st, Stats *also = nullptr)
{
  RefineOptions opt;
  opt.noise = noise;
  const RefineResult r = refineWindow(armCamera(), armRig(), s.measured, s.tracks, {}, opt);
  const std::vector<double> crlb = depthCramerRao(armCamera(), armRig(), s.truth, s.tracks, s.w_points, noise, true);
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    if (s.tracks[i].observations.size() < 2 || !std::isfinite(crlb[i]))
      continue;
    for (Stats *x : {&st, also}) {
      if (!x)
        continue;
      if (!r.points[i].ok())
        ++x->failed;
      else
        x->add(r.points[i].c_P.z() - truePoint(s, armRig(), i).z(), crlb[i], r.points[i].sigmaZ());
    }
  }
}

const ArmPath kArmPaths[] = {ArmPath::Approach, ArmPath::Orbit, ArmPath::Random};

/* What the tests on arm scenes share: the arm's camera, mount and noise. */
struct ArmSetup {
  const CameraModel camera = armCamera();
  const YawRig rig = armRig();
  const NoiseModel noise = armNoise();
};

} // namespace

TEST_CASE_METHOD(ArmSetup, "refine (general chain) returns the truth on noise-free arm scenes and camera_pose mounts", "[refine][6dof]")
{
  if (unavailableChecked())
    return;
  for (ArmPath path : kArmPaths) {
    const Scene s = armScene(path, 17, false);
    REQUIRE(s.measured.front().six_dof);
    RefineOptions opt;
    opt.noise = armNoise();
    const RefineResult r = refineWindow(camera, rig, s.measured, s.tracks, {}, opt);
    REQUIRE(r.available);
    int ok = 0;
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      if (!r.points[i].ok())
        continue;
      ++ok;
      const Eigen::Vector3d truth = truePoint(s, rig, i);
      CHECK((r.points[i].c_P - truth).norm() / truth.norm() < 1e-6);
      CHECK((rig.visionPoint(s.truth[rowOfFrame(s, r.points[i].frame)].yaw, r.points[i].c_P) - r.points[i].v_P).norm() < 1e-12);
      CHECK(std::isfinite(r.points[i].sigmaZ()));
    }
    CHECK(ok >= 20);
    for (std::size_t k = 0; k < s.truth.size(); ++k) {
      CHECK(r.motion[k].six_dof);
      CHECK((r.motion[k].position() - s.truth[k].position()).norm() < 1e-9);
      CHECK((r.motion[k].rotation() - s.truth[k].rotation()).norm() < 1e-9);
    }
  }
  // A planar log with a tilted mount runs the general chain with only the heading free.
  const YawRig tilted(vpHomogeneousMatrix(-0.15, 0.0, 0.02, 0.1, 0.0, 0.05));
  SceneOptions so = paperScene(45 * kDeg, 1 * kDeg, kFrames, 7, false);
  const Scene s = simulateScene(paperCamera(), tilted, so);
  RefineOptions opt;
  opt.noise = paperNoise();
  const RefineResult r = refineWindow(paperCamera(), tilted, s.measured, s.tracks, {}, opt);
  int ok = 0;
  for (std::size_t i = 0; i < s.tracks.size(); ++i)
    if (r.points[i].ok()) {
      ++ok;
      const Eigen::Vector3d truth = truePoint(s, tilted, i);
      CHECK((r.points[i].c_P - truth).norm() / truth.norm() < 1e-6);
    }
  CHECK(ok >= 25);
  for (std::size_t k = 0; k < s.truth.size(); ++k) {
    CHECK_FALSE(r.motion[k].six_dof);
    CHECK(std::abs(r.motion[k].heading - s.truth[k].heading) < 1e-9);
  }
}

TEST_CASE("refine general-chain residual Jacobians match central finite differences", "[refine][6dof]")
{
  using refine_detail::WhitenedObservation;
  constexpr int N = 17; // point(3), frame_a(7), frame_k(7)
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  refine_detail::Mount mount;
  mount.R0 = expSO3<double>(Eigen::Vector3d(0.1, -0.2, 1.5));
  mount.t0 = Eigen::Vector3d(0.05, -0.03, -0.04);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d Rref_a = expSO3<double>(Eigen::Vector3d(U(rng), U(rng), U(rng)));
    const Eigen::Matrix3d Rref_k = Rref_a * expSO3<double>(Eigen::Vector3d(0.1 * U(rng), 0.1 * U(rng), 0.1 * U(rng)));
    // A point in front of the anchor camera, seen by a camera close to it.
    double x[N] = {0.1 * U(rng), 0.1 * U(rng), 1.5 + 0.3 * U(rng),
                   0.1 * U(rng), 0.1 * U(rng), 0.1 * U(rng), 0.01 * U(rng), 0.01 * U(rng), 0.01 * U(rng), 0.2 * U(rng),
                   0.0,          0.0,          0.0,          0.01 * U(rng), 0.01 * U(rng), 0.01 * U(rng), 0.2 * U(rng)};
    for (int i = 0; i < 3; ++i)
      x[10 + i] = x[3 + i] + 0.02 * U(rng);
    const WhitenedObservation w = randomWhitening(2000, 2100, U, rng);
    auto eval = [&](const double *v, double *r) {
      REQUIRE(refine_detail::reprojectionResidualGeneral(v + 3, Rref_a, v + 10, Rref_k, v, mount, w, r));
    };
    const std::array<AutoDiff<N>, N> xa = seededVariables<N>(x);
    const AutoDiff<N> *xv = xa.data();
    AutoDiff<N> ra[2];
    REQUIRE(refine_detail::reprojectionResidualGeneral(xv + 3, Rref_a, xv + 10, Rref_k, xv, mount, w, ra));
    checkAgainstCentralDifferences(ra, x, 1e-6, eval, 1e-5, 1e-6);
    // The anchored point is the plain chain of ViSP-style poses: wMc = [Rref Exp(d) | p] vMc(yaw).
    auto wMcOf = [&](const double *f, const Eigen::Matrix3d &Rref) {
      const vpHomogeneousMatrix wMv_ = toVisp(Rref * expSO3<double>(Eigen::Vector3d(f[3], f[4], f[5])),
                                              Eigen::Vector3d(f[0], f[1], f[2]));
      const YawRig r(toVisp(mount.R0, mount.t0));
      return toIsometry(wMv_ * r.vMc(f[6]));
    };
    const Eigen::Vector3d Pa = Eigen::Vector3d(x[0], x[1], 1.0) / x[2];
    const Eigen::Vector3d Pk = wMcOf(x + 10, Rref_k).inverse() * (wMcOf(x + 3, Rref_a) * Pa);
    double q[3];
    refine_detail::anchoredPointGeneral(x + 3, Rref_a, x + 10, Rref_k, x, mount, q);
    CHECK((Eigen::Vector3d(q[0], q[1], q[2]) / x[2] - Pk).norm() < 1e-12);

    // Odometry residual: zero at the measurement, derivatives by finite differences.
    refine_detail::OdometryMeasurementGeneral om;
    om.Rref_prev = Rref_a;
    om.Rref_cur = Rref_k;
    om.dR = Rref_a.transpose() * Rref_k;
    const Eigen::Vector3d d = Rref_a.transpose() * Eigen::Vector3d(x[10] - x[3], x[11] - x[4], x[12] - x[5]);
    std::copy(d.data(), d.data() + 3, om.d);
    om.inv_sigma_t = 1000;
    for (double &v : om.inv_sigma_r)
      v = 1.0 / (0.05 * kDeg);
    double zero_prev[7] = {x[3], x[4], x[5], 0, 0, 0, 0}, zero_cur[7] = {x[10], x[11], x[12], 0, 0, 0, 0}, r0[6];
    refine_detail::odometryResidualGeneral(zero_prev, zero_cur, om, r0);
    for (double v : r0)
      CHECK(std::abs(v) < 1e-9);
    const std::array<AutoDiff<14>, 14> pa = seededVariables<14>(x + 3); // frame_a, frame_k
    AutoDiff<14> ro[6];
    refine_detail::odometryResidualGeneral(pa.data(), pa.data() + 7, om, ro);
    checkAgainstCentralDifferences(
        ro, x + 3, 1e-7, [&](const double *p, double *r) { refine_detail::odometryResidualGeneral(p, p + 7, om, r); },
        1e-4);
  }
}

namespace {

/* Brute-force joint bound of a 6-DoF scene: numerical Jacobian of every whitened measurement with
   respect to (per row >= 1: position, rotation vector about the truth; every point in the world),
   with the rotation increment's residual the exact log of dR_true^T Rp^T Rc (yaws exact); for
   per-pose noise, every row's (row 0 too) position and rotation against the truth's. */
std::vector<double> bruteForceCrlb6(const CameraModel &camera, const YawRig &rig, const Scene &s, const NoiseModel &n)
{
  // Per-pose noise: every row (row 0 too) is a parameter with its own prior, no increments.
  const bool absolute = n.motion_noise == MotionNoise::Absolute;
  const int first = absolute ? 0 : 1;
  const int rows = static_cast<int>(s.truth.size()), np = static_cast<int>(s.w_points.size());
  const int nl = 6 * (rows - first), nth = nl + 3 * np;
  auto unpack = [&](const Eigen::VectorXd &th) {
    std::vector<MotionSample> m = s.truth;
    for (int r = first; r < rows; ++r) {
      const Eigen::Vector3d p = th.segment<3>(6 * (r - first));
      m[r].x = p.x();
      m[r].y = p.y();
      m[r].z = p.z();
      m[r].theta_u = logSO3(s.truth[r].rotation() * expSO3<double>(Eigen::Vector3d(th.segment<3>(6 * (r - first) + 3))));
    }
    return std::make_pair(m, pointsIn(th, nl, np));
  };
  auto h = [&](const Eigen::VectorXd &th) {
    const auto [m, P] = unpack(th);
    std::vector<double> z;
    for (int i = 0; i < np; ++i)
      for (const Observation &ob : s.tracks[i].observations) {
        addWhitenedPixel(z, camera, toIsometry(wMc(rig, m[rowOfFrame(s, ob.frame)])).inverse() * P[i], n.sigma_px);
      }
    for (int r = 0; absolute && r < rows; ++r) {
      const Eigen::Vector3d d = m[r].position() - s.truth[r].position();
      const Eigen::Vector3d e = logSO3(s.truth[r].rotation().transpose() * m[r].rotation());
      for (int k = 0; k < 3; ++k)
        z.push_back(d(k) / n.sigma_odom);
      for (int k = 0; k < 3; ++k)
        z.push_back(e(k) / n.sigma_rot);
    }
    for (int r = 1; !absolute && r < rows; ++r) {
      const Eigen::Matrix3d Rp = m[r - 1].rotation();
      const Eigen::Vector3d d = Rp.transpose() * (m[r].position() - m[r - 1].position());
      const Eigen::Matrix3d dRt = s.truth[r - 1].rotation().transpose() * s.truth[r].rotation();
      const Eigen::Vector3d e = logSO3(dRt.transpose() * Rp.transpose() * m[r].rotation());
      for (int k = 0; k < 3; ++k)
        z.push_back(d(k) / n.sigma_odom);
      for (int k = 0; k < 3; ++k)
        z.push_back(e(k) / n.sigma_rot);
    }
    return Eigen::Map<Eigen::VectorXd>(z.data(), z.size()).eval();
  };
  Eigen::VectorXd th = Eigen::VectorXd::Zero(nth);
  for (int r = first; r < rows; ++r)
    th.segment<3>(6 * (r - first)) = s.truth[r].position();
  for (int i = 0; i < np; ++i)
    th.segment<3>(nl + 3 * i) = s.w_points[i];
  auto zc = [&](int i, const Eigen::VectorXd &t) { // Zc at the last observation: its row's pose and the point
    const auto [m, P] = unpack(t);
    return (toIsometry(wMc(rig, m[rowOfFrame(s, s.tracks[i].observations.back().frame)])).inverse() * P[i]).z();
  };
  return boundsFromFisher(h, zc, th, 1e-7, np);
}

} // namespace

TEST_CASE_METHOD(ArmSetup, "depthCramerRao on 6-DoF scenes matches a brute-force Fisher information", "[refine][crlb][6dof]")
{
  for (ArmPath path : kArmPaths) {
    const Scene s = armScene(path, 23, false, 4, 5);
    checkJointBound(camera, rig, s.truth, s.tracks, s.w_points, noise, bruteForceCrlb6(camera, rig, s, noise), true);
  }
}

TEST_CASE("per-pose motion noise: the bound matches a brute-force Fisher information, refine is exact without noise",
          "[refine][crlb][6dof]")
{
  const CameraModel camera = armCamera();
  const YawRig rig = armRig();
  const NoiseModel noise = perPoseNoise();
  for (ArmPath path : kArmPaths) {
    INFO("path " << static_cast<int>(path));
    const Scene s = armScene(path, 29, false, 4, 5);
    checkJointBound(camera, rig, s.truth, s.tracks, s.w_points, noise, bruteForceCrlb6(camera, rig, s, noise), false);
    if (!refineAvailable())
      continue;
    // Noise-free: the truth, with every pose (row 0 too) at its measurement.
    const Scene f = armScene(path, 31, false);
    RefineOptions opt;
    opt.noise = noise;
    const RefineResult r = refineWindow(camera, rig, f.measured, f.tracks, {}, opt);
    REQUIRE(r.motion.size() == f.truth.size());
    for (std::size_t k = 0; k < f.truth.size(); ++k)
      CHECK((r.motion[k].position() - f.truth[k].position()).norm() < 1e-7);
    for (std::size_t i = 0; i < f.tracks.size(); ++i) {
      if (f.tracks[i].observations.size() < 2)
        continue;
      REQUIRE(r.points[i].ok());
      CHECK((r.points[i].c_P - truePoint(f, rig, i)).norm() < 1e-6 * truePoint(f, rig, i).norm());
    }
  }
  // The pose prior's residual: zero at the measurement, linear with slope 1 / sigma.
  refine_detail::PosePrior prior;
  const double pose[6] = {0.1, -0.2, 0.3, 0.01, -0.02, 0.03};
  std::copy(pose, pose + 6, prior.value);
  for (int i = 0; i < 6; ++i)
    prior.inv_sigma[i] = 10.0 * (i + 1);
  double r0[6], r1[6], moved[6];
  refine_detail::posePriorResidual<6>(pose, prior, r0);
  for (int i = 0; i < 6; ++i) {
    CHECK(r0[i] == 0.0);
    std::copy(pose, pose + 6, moved);
    moved[i] += 1e-3;
    refine_detail::posePriorResidual<6>(moved, prior, r1);
    CHECK(r1[i] == Approx(1e-3 * prior.inv_sigma[i]).epsilon(1e-9));
  }
}

TEST_CASE("refine with per-pose motion noise is efficient and honest (Monte Carlo against the joint bound)",
          "[refine][montecarlo][6dof]")
{
  if (unavailableChecked())
    return;
  const NoiseModel noise = perPoseNoise();
  constexpr int kTrials = 15;
  Stats pooled;
  for (ArmPath path : kArmPaths) {
    for (int trial = 0; trial < kTrials; ++trial) // each pose errs about the truth
      armTrial(armScene(path, 3000 + trial, true, 10, 30, noise), noise, pooled);
  }
  std::printf("refine MC arm, per-pose noise, pooled: RMSE/CRLB %.3f, 2-sigma coverage %.3f over %d depths, %d failed\n",
              pooled.ratio(), pooled.coverage(), pooled.n, pooled.failed);
  CHECK(pooled.failed <= pooled.n / 100);
  checkPooledAgainstCrlb(pooled);
}

TEST_CASE("refine on arm scenes is efficient and honest (Monte Carlo against the joint bound)", "[refine][montecarlo][6dof]")
{
  if (unavailableChecked())
    return;
  const NoiseModel noise = armNoise();
  constexpr int kTrials = 20;
  Stats pooled;
  for (ArmPath path : kArmPaths) {
    Stats st;
    for (int trial = 0; trial < kTrials; ++trial)
      armTrial(armScene(path, 2000 + trial, true), noise, st, &pooled);
    std::printf("refine MC arm %d: RMSE/CRLB %.3f, 2-sigma coverage %.3f, failed %d of %d\n", static_cast<int>(path),
                st.ratio(), st.coverage(), st.failed, st.n + st.failed);
    CHECK(st.ratio() <= 1.25);
    CHECK(st.coverage() >= 0.85);
  }
  std::printf("refine MC arm pooled: RMSE/CRLB %.3f, 2-sigma coverage %.3f over %d depths\n", pooled.ratio(),
              pooled.coverage(), pooled.n);
  checkPooledAgainstCrlb(pooled);
}

#ifdef YAWDEPTH_TEST_CHAIN_COSTS
/* The functor's residual, by operator() and by the Ceres cost function its Create makes, against
   (r_k - a r_prev) / sqrt(1 - a^2) from the plain residuals. */
template <class Functor>
void checkInnovation(const Functor &f, ceres::CostFunction *cost, const std::vector<const double *> &blocks,
                     const double *r_cur, const double *r_prev, double a)
{
  constexpr double kExact = 1e-12; // relative: the same arithmetic but for the order of its rounding
  std::unique_ptr<ceres::CostFunction> owned(cost);
  double by_functor[2], by_ceres[2];
  if constexpr (std::is_invocable_r_v<bool, Functor, const double *, const double *, const double *, double *>)
    REQUIRE(f(blocks[0], blocks[1], blocks[2], by_functor));
  else
    REQUIRE(f(blocks[0], blocks[1], blocks[2], blocks[3], by_functor));
  REQUIRE(owned->Evaluate(blocks.data(), by_ceres, nullptr));
  for (int i = 0; i < 2; ++i) {
    const double by_hand = (r_cur[i] - a * r_prev[i]) / std::sqrt(1.0 - a * a);
    CHECK(std::abs(by_functor[i] - by_hand) <= kExact * (1.0 + std::abs(by_hand)));
    CHECK(std::abs(by_ceres[i] - by_hand) <= kExact * (1.0 + std::abs(by_hand)));
  }
}

TEST_CASE("refine's innovation functors are the AR(1) innovation of the plain residuals", "[refine][correlated]")
{
  using namespace refine_detail;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double t0[3] = {-0.1503, 0.01, 0.02};
  Mount mount;
  mount.R0 = expSO3<double>(Eigen::Vector3d(0.1, -0.2, 1.5));
  mount.t0 = Eigen::Vector3d(0.05, -0.03, -0.04);
  for (int trial = 0; trial < 10; ++trial) {
    const double a = 0.9 * (0.5 + 0.5 * std::abs(U(rng))); // phi^gap
    const ChainCoefficient c(a);
    const WhitenedObservation wp = randomWhitening(500, 520, U, rng), wk = randomWhitening(480, 510, U, rng);
    const double point[3] = {0.1 * U(rng), 0.1 * U(rng), 0.5 + 0.3 * U(rng)};
    // Planar frames (x, y, z, heading, yaw): the anchor's, the previous observation's, the current one's.
    double fa[5], fp[5], fk[5];
    for (double *f : {fa, fp, fk})
      for (int i = 0; i < 5; ++i)
        f[i] = (i == 1 ? 0.01 : 0.1) * U(rng);
    double r_anchor[2], r_prev[2], r_cur[2];
    anchorResidual(point, wp, r_anchor);
    REQUIRE(reprojectionResidual(fa, fa + 4, fp, fp + 4, point, t0, wp, r_prev));
    REQUIRE(reprojectionResidual(fa, fa + 4, fk, fk + 4, point, t0, wk, r_cur));
    checkInnovation(InnovationAfterAnchorCost(wp, wk, t0, c), InnovationAfterAnchorCost::Create(wp, wk, t0, c),
                    {fa, fk, point}, r_cur, r_anchor, a);
    checkInnovation(InnovationCost(wp, wk, t0, c), InnovationCost::Create(wp, wk, t0, c), {fa, fp, fk, point}, r_cur,
                    r_prev, a);

    // General frames (x, y, z, dx, dy, dz, yaw) about their rows' reference orientations.
    const Eigen::Matrix3d Ra = expSO3<double>(Eigen::Vector3d(U(rng), U(rng), U(rng)));
    const Eigen::Matrix3d Rp = Ra * expSO3<double>(Eigen::Vector3d(0.1 * U(rng), 0.1 * U(rng), 0.1 * U(rng)));
    const Eigen::Matrix3d Rk = Ra * expSO3<double>(Eigen::Vector3d(0.1 * U(rng), 0.1 * U(rng), 0.1 * U(rng)));
    double ga[7], gp[7], gk[7];
    for (double *g : {ga, gp, gk})
      for (int i = 0; i < 7; ++i)
        g[i] = (i < 3 ? 0.02 : 0.01) * U(rng);
    double point_g[3] = {point[0], point[1], 1.5 + 0.3 * U(rng)};
    anchorResidual(point_g, wp, r_anchor);
    REQUIRE(reprojectionResidualGeneral(ga, Ra, gp, Rp, point_g, mount, wp, r_prev));
    REQUIRE(reprojectionResidualGeneral(ga, Ra, gk, Rk, point_g, mount, wk, r_cur));
    checkInnovation(InnovationAfterAnchorCostGeneral(wp, wk, Ra, Rk, mount, c),
                    InnovationAfterAnchorCostGeneral::Create(wp, wk, Ra, Rk, mount, c), {ga, gk, point_g}, r_cur,
                    r_anchor, a);
    checkInnovation(InnovationCostGeneral(wp, wk, Ra, Rp, Rk, mount, c),
                    InnovationCostGeneral::Create(wp, wk, Ra, Rp, Rk, mount, c), {ga, gp, gk, point_g}, r_cur, r_prev, a);
  }
}
#endif

TEST_CASE_METHOD(PaperSetup, "refine models the tracker's correlated errors (AR(1)): honest where independence is not",
                 "[refine][montecarlo][correlated]")
{
  if (unavailableChecked())
    return;
  constexpr double kPhi = 0.9, kSigmaPx = 1.0; // the pixels' errors dominate the odometry's here
  constexpr int kTrials = 30;
  constexpr double kMinCoverage = 0.86, kMaxCoverage = 0.995; // 2-sigma coverage with the model
  constexpr double kHonestCoverage = 0.90; // docs/method.md's band is 0.90 to 0.98
  constexpr double kRmseAllowance = 1.02;  // the right weights cost no accuracy
  Stats white, modelled;
  double sum_sq_white = 0, sum_sq_modelled = 0;
  for (int t = 0; t < kTrials; ++t) {
    const Scene s = trackerErrorScene(camera, rig, kSigmaPx, kPhi, 300 + static_cast<std::uint64_t>(t));
    const std::vector<double> crlb = depthCramerRao(camera, rig, s.truth, s.tracks, s.w_points, noise, true);
    RefineOptions o;
    o.noise = noise;
    o.noise.sigma_px = kSigmaPx;
    const RefineResult w = refineWindow(camera, rig, s.measured, s.tracks, {}, o);
    o.noise.pixel_correlation = kPhi;
    const RefineResult m = refineWindow(camera, rig, s.measured, s.tracks, {}, o);
    for (std::size_t i = 0; i < s.tracks.size(); ++i) {
      if (!w.points[i].ok() || !m.points[i].ok() || !(crlb[i] > 0) || !std::isfinite(crlb[i]))
        continue;
      const double z = truePoint(s, rig, i).z();
      white.add(w.points[i].c_P.z() - z, crlb[i], w.points[i].sigmaZ());
      modelled.add(m.points[i].c_P.z() - z, crlb[i], m.points[i].sigmaZ());
      sum_sq_white += std::pow(w.points[i].c_P.z() - z, 2);
      sum_sq_modelled += std::pow(m.points[i].c_P.z() - z, 2);
    }
  }
  INFO("independent model: coverage " << white.coverage() << "; AR(1) model: coverage " << modelled.coverage()
                                       << ", RMSE " << std::sqrt(sum_sq_modelled / modelled.n) << " against "
                                       << std::sqrt(sum_sq_white / white.n) << " over " << modelled.n << " points");
  std::printf("refine AR(1) MC: coverage %.3f (independent model %.3f), RMSE %.4g m (independent model %.4g m) over %d "
              "depths\n",
              modelled.coverage(), white.coverage(), std::sqrt(sum_sq_modelled / modelled.n),
              std::sqrt(sum_sq_white / white.n), modelled.n);
  REQUIRE(modelled.n > 400);
  CHECK(white.coverage() < kHonestCoverage); // the independent model is overconfident on these errors
  CHECK(modelled.coverage() > kMinCoverage);
  CHECK(modelled.coverage() < kMaxCoverage);
  CHECK(sum_sq_modelled <= kRmseAllowance * kRmseAllowance * sum_sq_white);
}
