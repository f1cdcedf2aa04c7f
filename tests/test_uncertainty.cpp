// First-order uncertainty of the two-view estimators: finite-difference check of the propagation
// and Monte Carlo agreement with the empirical spread in front, oblique and side views.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <limits>
#include <random>
#include <yawdepth/estimation/two_view.h>

#include "two_view_detail.h" // private to yawdepth::estimation

using namespace yawdepth;

namespace {

constexpr double kFdRelTol = 1e-5;        // central differences vs forward-mode derivatives
constexpr double kMonteCarloRelTol = 0.10; // docs/method.md: predicted sigma within 10 % of the spread
constexpr int kTrials = 20000;             // std of a std estimate: 1/sqrt(2N) = 0.5 %

struct Case {
  const char *name;
  double yaw;   // camera yaw (rad)
  double step;  // forward increment (m)
  Eigen::Vector3d c_P_cur;
  bool six_dof = false; // an arm: 6-DoF rows, a tilted hand-eye mount, the camera moving sideways and turning
};

struct Setup {
  CameraModel camera = CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
  YawRig rig{Eigen::Vector3d(-0.1503, 0.0, 0.0)};
  MotionSample prev, cur;
  Eigen::Vector2d uv_prev, uv_cur;
};

Setup makeSetup(const Case &c)
{
  Setup s;
  if (c.six_dof) {
    s.rig = YawRig(vpHomogeneousMatrix(0.058, -0.034, -0.042, 0.002, 0.009, 1.58));
    s.prev = MotionSample::fromPose(0, vpHomogeneousMatrix(0.4, 0.1, 0.3, 2.2, -2.2, 0.02), c.yaw);
    // The camera moves mostly along its own X, turning a little.
    const Eigen::Vector3d v_d = s.rig.vRc(c.yaw) * Eigen::Vector3d(c.step, 0.2 * c.step, 0.3 * c.step);
    const Eigen::Matrix3d dR = expSO3<double>(Eigen::Vector3d(0.01, 0.02, -0.015));
    const vpHomogeneousMatrix wMv_cur = wMv(s.prev) * toVisp(dR, v_d);
    s.cur = MotionSample::fromPose(1, wMv_cur, c.yaw);
  } else {
  s.prev.frame = 0;
  s.prev.heading = 0.1;
  s.prev.yaw = c.yaw;
  s.cur = s.prev;
  s.cur.frame = 1;
  const Eigen::Vector3d w_d = rotY(s.prev.heading) * Eigen::Vector3d(0.0, 0.0, c.step);
  s.cur.x += w_d.x();
  s.cur.z += w_d.z();
  }
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(curMprev(s.rig, s.prev, s.cur), R, t);
  const Eigen::Vector3d c_P_prev = R.transpose() * (c.c_P_cur - t);
  s.uv_cur = s.camera.project(c.c_P_cur.head<2>() / c.c_P_cur.z());
  s.uv_prev = s.camera.project(c_P_prev.head<2>() / c_P_prev.z());
  return s;
}

/* Apply a perturbation vector in the estimators' input order to a setup. */
void perturb(const Setup &s, const Eigen::Matrix<double, kTwoViewInputs, 1> &d, MotionSample &prev, MotionSample &cur,
             Eigen::Vector2d &uv_prev, Eigen::Vector2d &uv_cur)
{
  prev = s.prev;
  cur = s.cur;
  uv_prev = s.uv_prev + d.segment<2>(0);
  uv_cur = s.uv_cur + d.segment<2>(2);
  const Eigen::Vector3d w_dd = s.prev.rotation() * d.segment<3>(4);
  cur.x += w_dd.x();
  cur.y += w_dd.y();
  cur.z += w_dd.z();
  if (!cur.six_dof && d(7) == 0 && d(9) == 0) {
    cur.heading += d(8);
  } else { // a rotation off the heading axis: as a 6-DoF row
    cur.theta_u = logSO3(cur.rotation() * expSO3<double>(Eigen::Vector3d(d.segment<3>(7))));
    cur.six_dof = true;
  }
  prev.yaw += d(10);
  cur.yaw += d(11);
}

const Case kCases[] = {
    {"front", 0.0, 0.10, Eigen::Vector3d(0.14, 0.09, 0.8)},
    {"oblique", M_PI / 4, 0.02, Eigen::Vector3d(0.05, -0.03, 1.0)},
    {"side", M_PI / 2, 0.02, Eigen::Vector3d(-0.04, 0.06, 1.2)},
    {"arm", 0.0, 0.02, Eigen::Vector3d(0.03, -0.05, 0.6), true},
};

using Estimator = PointEstimate (*)(const CameraModel &, const YawRig &, const MotionSample &, const MotionSample &,
                                    const Eigen::Vector2d &, const Eigen::Vector2d &, const TwoViewOptions &);

} // namespace

TEST_CASE("exact: the covariance is J Sigma J^T with J checked by finite differences", "[uncertainty]")
{
  for (const Case &c : kCases) {
    INFO(c.name);
    const Setup s = makeSetup(c);
    TwoViewOptions opt;
    const PointEstimate e = estimateExact(s.camera, s.rig, s.prev, s.cur, s.uv_prev, s.uv_cur, opt);
    REQUIRE(e.ok());
    const double steps[kTwoViewInputs] = {1e-4, 1e-4, 1e-4, 1e-4, 1e-7, 1e-7, 1e-7, 1e-8, 1e-8, 1e-8, 1e-8, 1e-8};
    TwoViewOptions no_cov = opt;
    no_cov.compute_covariance = false;
    Eigen::Matrix<double, 3, kTwoViewInputs> J;
    for (int i = 0; i < kTwoViewInputs; ++i) {
      Eigen::Matrix<double, kTwoViewInputs, 1> d = Eigen::Matrix<double, kTwoViewInputs, 1>::Zero();
      d(i) = steps[i];
      MotionSample p, q;
      Eigen::Vector2d a, b;
      perturb(s, d, p, q, a, b);
      const PointEstimate plus = estimateExact(s.camera, s.rig, p, q, a, b, no_cov);
      perturb(s, -d, p, q, a, b);
      const PointEstimate minus = estimateExact(s.camera, s.rig, p, q, a, b, no_cov);
      REQUIRE(plus.ok());
      REQUIRE(minus.ok());
      J.col(i) = (plus.c_P - minus.c_P) / (2 * steps[i]);
    }
    const Eigen::Matrix3d cov_fd = J * twoViewInputVariances(opt.noise, 1, c.six_dof).asDiagonal() * J.transpose();
    REQUIRE((cov_fd - e.c_cov).norm() < kFdRelTol * cov_fd.norm());
  }
}

TEST_CASE("predicted sigma_zc matches the Monte Carlo spread within 10 %", "[uncertainty][montecarlo]")
{
  const std::pair<const char *, Estimator> estimators[] = {{"exact", estimateExact}, {"paper", estimatePaper}};
  for (const auto &[name, estimate] : estimators) {
    for (const Case &c : kCases) {
      INFO(name << " " << c.name);
      const Setup s = makeSetup(c);
      const TwoViewOptions opt; // defaults: 0.3 px, 1 mm, 0.05 deg, 0.05 deg
      const PointEstimate e0 = estimate(s.camera, s.rig, s.prev, s.cur, s.uv_prev, s.uv_cur, opt);
      REQUIRE(e0.ok());
      const Eigen::Matrix<double, kTwoViewInputs, 1> sd = twoViewInputVariances(opt.noise, 1, c.six_dof).cwiseSqrt();
      TwoViewOptions fast = opt;
      fast.compute_covariance = false;
      std::mt19937_64 rng(42);
      std::normal_distribution<double> g(0.0, 1.0);
      double sum = 0, sum2 = 0;
      int n = 0;
      for (int k = 0; k < kTrials; ++k) {
        Eigen::Matrix<double, kTwoViewInputs, 1> d;
        for (int i = 0; i < kTwoViewInputs; ++i)
          d(i) = sd(i) * g(rng);
        MotionSample p, q;
        Eigen::Vector2d a, b;
        perturb(s, d, p, q, a, b);
        const PointEstimate e = estimate(s.camera, s.rig, p, q, a, b, fast);
        if (!e.ok())
          continue;
        sum += e.c_P.z();
        sum2 += e.c_P.z() * e.c_P.z();
        ++n;
      }
      REQUIRE(n > kTrials * 0.99);
      const double mean = sum / n, spread = std::sqrt(sum2 / n - mean * mean);
      INFO("predicted " << e0.sigmaZ() << " empirical " << spread << " relative sigma " << spread / c.c_P_cur.z());
      CHECK(std::abs(e0.sigmaZ() / spread - 1.0) < kMonteCarloRelTol);
    }
  }
}

TEST_CASE("odometry noise per metre and per radian: the same as per-increment noise of that size", "[uncertainty]")
{
  constexpr double kRoundOff = 1e-12;
  for (const Case &c : kCases) {
    INFO(c.name);
    const Setup s = makeSetup(c);
    const double distance = (s.cur.position() - s.prev.position()).norm();
    const double angle = Eigen::AngleAxisd(s.prev.rotation().transpose() * s.cur.rotation()).angle();
    // Distance-scaled terms only ...
    TwoViewOptions scaled;
    scaled.noise.sigma_odom = 0.0;
    scaled.noise.sigma_heading = 0.0;
    scaled.noise.sigma_rot = 0.0;
    scaled.noise.odom_per_metre = 0.03;
    scaled.noise.rot_per_radian = 0.05;
    scaled.noise.rot_per_metre = 0.02;
    // ... against per-increment sigmas of the same size.
    TwoViewOptions fixed = scaled;
    fixed.noise.odom_per_metre = fixed.noise.rot_per_radian = fixed.noise.rot_per_metre = 0.0;
    fixed.noise.sigma_odom = 0.03 * distance;
    const double rot = std::hypot(0.05 * angle, 0.02 * distance);
    fixed.noise.sigma_heading = fixed.noise.sigma_rot = rot;
    REQUIRE(distance > 0.01);
    const PointEstimate a = estimateExact(s.camera, s.rig, s.prev, s.cur, s.uv_prev, s.uv_cur, scaled);
    const PointEstimate b = estimateExact(s.camera, s.rig, s.prev, s.cur, s.uv_prev, s.uv_cur, fixed);
    REQUIRE(a.ok());
    REQUIRE(b.ok());
    CHECK((a.c_cov - b.c_cov).norm() <= kRoundOff * b.c_cov.norm());
    CHECK(a.sigmaZ() > 0);
    // Two increments sharing the motion: n sigma^2 + (k d)^2 / n.
    scaled.increments = 2;
    const auto v2 = twoViewInputVariances(scaled.noise, 2, c.six_dof, distance, angle);
    CHECK(v2(4) == Approx(0.03 * 0.03 * distance * distance / 2).epsilon(kRoundOff));
    CHECK(v2(8) == Approx(rot * rot / 2).epsilon(kRoundOff));
  }
  NoiseModel bad;
  bad.odom_per_metre = -0.01;
  CHECK_THROWS(bad.validate());
  bad = NoiseModel();
  bad.rot_per_radian = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS(bad.validate());
  bad = NoiseModel();
  bad.rot_per_metre = -1;
  CHECK_THROWS(bad.validate());
  for (double phi : {-0.1, 0.995, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    bad = NoiseModel();
    bad.pixel_correlation = phi;
    CHECK_THROWS(bad.validate());
  }
  bad = NoiseModel();
  bad.pixel_correlation = kMaxPixelCorrelation;
  CHECK_NOTHROW(bad.validate());
}
