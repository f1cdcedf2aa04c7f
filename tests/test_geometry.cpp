// Rig geometry: eq. (1), (4), (7), world poses and relative motion.
#include <catch2/catch.hpp>

#include <Eigen/LU>
#include <random>
#include <visp3/core/vpPoseVector.h>
#include <visp3/core/vpThetaUVector.h>
#include <cmath>
#include <yawdepth/error.h>
#include <yawdepth/geometry/rig.h>

using namespace yawdepth;

namespace {
constexpr double kRoundOff = 1e-12; // exact maths on metre-scale numbers

double maxAbsDiff(const vpHomogeneousMatrix &A, const vpHomogeneousMatrix &B)
{
  double m = 0;
  for (unsigned i = 0; i < 4; ++i)
    for (unsigned j = 0; j < 4; ++j)
      m = std::max(m, std::abs(A[i][j] - B[i][j]));
  return m;
}

MotionSample randomSample(std::mt19937_64 &rng, long frame)
{
  std::uniform_real_distribution<double> pos(-2.0, 2.0), ang(-M_PI, M_PI);
  MotionSample s;
  s.frame = frame;
  s.x = pos(rng);
  s.y = 0.1 * pos(rng);
  s.z = pos(rng);
  s.heading = ang(rng);
  s.yaw = ang(rng);
  return s;
}
} // namespace

TEST_CASE("rotY turns the optical axis toward +X for positive yaw", "[geometry]")
{
  const Eigen::Vector3d z = rotY(0.3) * Eigen::Vector3d::UnitZ();
  CHECK(z.x() == Approx(std::sin(0.3)).margin(kRoundOff));
  CHECK(z.z() == Approx(std::cos(0.3)).margin(kRoundOff));
  CHECK(z.y() == 0.0);
  const Eigen::Matrix3d R = rotY(1.234);
  CHECK((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() < kRoundOff);
  CHECK(R.determinant() == Approx(1.0).margin(kRoundOff));
  // Side view: at yaw 90 degrees the optical axis is the vision frame's +X.
  CHECK((rotY(M_PI / 2) * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm() < kRoundOff);
}

TEST_CASE("vMc follows eq. (1) and cMv is its inverse", "[geometry]")
{
  const YawRig rig(Eigen::Vector3d(-0.1503, 0.0, 0.0));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ang(-M_PI, M_PI);
  for (int k = 0; k < 200; ++k) {
    const double yaw = ang(rng);
    const vpHomogeneousMatrix vMc = rig.vMc(yaw);
    const Eigen::Matrix3d R = rotY(yaw);
    const Eigen::Vector3d t = R * rig.cameraOffset();
    for (unsigned i = 0; i < 3; ++i) {
      for (unsigned j = 0; j < 3; ++j)
        REQUIRE(vMc[i][j] == Approx(R(i, j)).margin(kRoundOff));
      REQUIRE(vMc[i][3] == Approx(t(i)).margin(kRoundOff));
    }
    REQUIRE(maxAbsDiff(rig.cMv(yaw) * vMc, vpHomogeneousMatrix()) < kRoundOff);
  }
  // At yaw 0 the optical centre is at t0: the paper's vision origin is Lb along the camera's +X.
  const vpHomogeneousMatrix vMc0 = rig.vMc(0.0);
  CHECK(vMc0[0][3] == Approx(-0.1503));
}

TEST_CASE("eq. (7) round trip and eq. (4) increment", "[geometry]")
{
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0), ang(-M_PI, M_PI);
  for (int k = 0; k < 200; ++k) {
    const YawRig rig(Eigen::Vector3d(0.2 * u(rng), 0.05 * u(rng), 0.2 * u(rng)));
    const double yaw = ang(rng);
    vpColVector c_P(3);
    c_P[0] = u(rng);
    c_P[1] = u(rng);
    c_P[2] = 2 + u(rng);
    const vpColVector v_P = rig.toVision(yaw, c_P);
    // Same as the homogeneous product vTc [Xc Yc Zc 1]^T.
    const vpColVector v_P_h = rig.vMc(yaw) * vpColVector({c_P[0], c_P[1], c_P[2], 1.0});
    for (unsigned i = 0; i < 3; ++i)
      REQUIRE(v_P[i] == Approx(v_P_h[i]).margin(kRoundOff));
    const vpColVector back = rig.toCamera(yaw, v_P);
    for (unsigned i = 0; i < 3; ++i)
      REQUIRE(back[i] == Approx(c_P[i]).margin(kRoundOff));
    // eq. (4): the increment rotates with cRv.
    vpColVector v_d(3);
    v_d[0] = u(rng);
    v_d[1] = 0.0;
    v_d[2] = u(rng);
    const vpColVector c_d = rig.cameraIncrement(yaw, v_d);
    const Eigen::Vector3d expect = rotY(yaw).transpose() * Eigen::Vector3d(v_d[0], v_d[1], v_d[2]);
    for (unsigned i = 0; i < 3; ++i)
      REQUIRE(c_d[i] == Approx(expect(i)).margin(kRoundOff));
  }
}

TEST_CASE("paper's increments for forward motion: dXc = -dz sin(theta), dZc = dz cos(theta)", "[geometry]")
{
  const YawRig rig(Eigen::Vector3d(-0.1503, 0, 0));
  for (double theta : {0.0, M_PI / 4, M_PI / 2}) {
    const vpColVector c_d = rig.cameraIncrement(theta, vpColVector({0.0, 0.0, 0.02}));
    CHECK(c_d[0] == Approx(-0.02 * std::sin(theta)).margin(kRoundOff));
    CHECK(c_d[2] == Approx(0.02 * std::cos(theta)).margin(kRoundOff));
  }
}

TEST_CASE("relative motion equals the composition of world poses", "[geometry]")
{
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int k = 0; k < 300; ++k) {
    const YawRig rig(Eigen::Vector3d(u(rng), 0.1 * u(rng), u(rng)));
    const MotionSample a = randomSample(rng, 1), b = randomSample(rng, 2);
    const vpHomogeneousMatrix expect = wMc(rig, b).inverse() * wMc(rig, a);
    REQUIRE(maxAbsDiff(curMprev(rig, a, b), expect) < 1e-12);
  }
}

TEST_CASE("increment perturbations act on the odometry increment and the yaw readings", "[geometry]")
{
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int k = 0; k < 100; ++k) {
    const YawRig rig(Eigen::Vector3d(u(rng), 0.0, u(rng)));
    const MotionSample a = randomSample(rng, 1), b = randomSample(rng, 2);
    IncrementPerturbation<double> p;
    p.d_translation = Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.d_rotation.y() = u(rng);
    p.d_yaw_prev = u(rng);
    p.d_yaw_cur = u(rng);
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    relativeMotion(rig, a, b, p, R, t);
    // The same motion from explicitly perturbed motion-log rows.
    MotionSample a2 = a, b2 = b;
    const Eigen::Vector3d w_dd = rotY(a.heading) * p.d_translation;
    b2.x += w_dd.x();
    b2.y += w_dd.y();
    b2.z += w_dd.z();
    b2.heading += p.d_rotation.y();
    a2.yaw += p.d_yaw_prev;
    b2.yaw += p.d_yaw_cur;
    REQUIRE(maxAbsDiff(toVisp(R, t), curMprev(rig, a2, b2)) < 1e-12);
  }
}

namespace {
/* A random 6-DoF row: wMv from ViSP's pose vector, any orientation. */
MotionSample randomPoseSample(std::mt19937_64 &rng, long frame)
{
  std::uniform_real_distribution<double> pos(-2.0, 2.0), ang(-1.7, 1.7), yaw(-M_PI, M_PI);
  return MotionSample::fromPose(frame, vpHomogeneousMatrix(pos(rng), pos(rng), pos(rng), ang(rng), ang(rng), ang(rng)),
                                yaw(rng));
}
vpHomogeneousMatrix randomMount(std::mt19937_64 &rng)
{
  std::uniform_real_distribution<double> off(-0.1, 0.1), ang(-1.7, 1.7);
  return vpHomogeneousMatrix(off(rng), off(rng), off(rng), ang(rng), ang(rng), ang(rng));
}
} // namespace

TEST_CASE("6-DoF rows and a fixed camera_pose mount: poses and relative motion are ViSP's compositions", "[geometry]")
{
  std::mt19937_64 rng(21);
  for (int k = 0; k < 300; ++k) {
    const vpHomogeneousMatrix vMc0 = randomMount(rng);
    const YawRig rig(vMc0);
    const MotionSample a = randomPoseSample(rng, 1), b = randomPoseSample(rng, 2);
    // The row is ViSP's pose vector (tx, ty, tz, tux, tuy, tuz).
    const vpHomogeneousMatrix wMv_a(vpPoseVector(a.x, a.y, a.z, a.theta_u.x(), a.theta_u.y(), a.theta_u.z()));
    REQUIRE(maxAbsDiff(wMv(a), wMv_a) < kRoundOff);
    // vMc(yaw) = [Ry(yaw) | 0] vMc0: the pan joint turns the mount about the vision frame's +Y.
    const vpHomogeneousMatrix yawJoint = toVisp(rotY(a.yaw), Eigen::Vector3d::Zero());
    REQUIRE(maxAbsDiff(rig.vMc(a.yaw), yawJoint * vMc0) < kRoundOff);
    REQUIRE(maxAbsDiff(rig.cMv(a.yaw), (yawJoint * vMc0).inverse()) < kRoundOff);
    const vpHomogeneousMatrix expect = (wMv(b) * rig.vMc(b.yaw)).inverse() * (wMv(a) * rig.vMc(a.yaw));
    REQUIRE(maxAbsDiff(curMprev(rig, a, b), expect) < kRoundOff);
    // Points: eq. (7) and its inverse with the mount.
    const Eigen::Vector3d c_P(0.1, -0.2, 1.3);
    const Eigen::Vector3d v_P = rig.visionPoint(a.yaw, c_P);
    const vpColVector v_expect = rig.vMc(a.yaw) * vpColVector({c_P.x(), c_P.y(), c_P.z(), 1.0});
    for (int i = 0; i < 3; ++i)
      REQUIRE(v_P(i) == Approx(v_expect[i]).margin(kRoundOff));
    REQUIRE((rig.cameraPoint(a.yaw, v_P) - c_P).norm() < kRoundOff);
    // A planar row is the 6-DoF row of rotation (0, heading, 0).
    const MotionSample p = randomSample(rng, 3);
    const MotionSample q = MotionSample::fromPose(3, wMv(p), p.yaw);
    REQUIRE(maxAbsDiff(wMv(q), wMv(p)) < kRoundOff);
    REQUIRE(maxAbsDiff(curMprev(rig, p, b), curMprev(rig, q, b)) < kRoundOff);
  }
}

TEST_CASE("6-DoF rotation perturbations act on the right of the increment's rotation", "[geometry]")
{
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int k = 0; k < 100; ++k) {
    const YawRig rig(randomMount(rng));
    const MotionSample a = randomPoseSample(rng, 1), b = randomPoseSample(rng, 2);
    IncrementPerturbation<double> p;
    p.d_translation = Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.d_rotation = Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.d_yaw_prev = u(rng);
    p.d_yaw_cur = u(rng);
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    relativeMotion(rig, a, b, p, R, t);
    // The same from explicitly perturbed rows: the later vision frame's pose in the earlier one
    // becomes [dR Exp(d_rotation) | d + d_translation].
    const Eigen::Matrix3d Ra = a.rotation();
    const Eigen::Matrix3d dR = Ra.transpose() * b.rotation() * expSO3<double>(p.d_rotation);
    const Eigen::Vector3d d = Ra.transpose() * (b.position() - a.position()) + p.d_translation;
    MotionSample a2 = a;
    a2.yaw += p.d_yaw_prev;
    const MotionSample b2 = MotionSample::fromPose(2, toVisp(Ra * dR, a.position() + Ra * d), b.yaw + p.d_yaw_cur);
    REQUIRE(maxAbsDiff(toVisp(R, t), curMprev(rig, a2, b2)) < 1e-12);
  }
}

TEST_CASE("expSO3 and logSO3 are ViSP's theta-u, and expSO3's derivative at zero is the skew matrix", "[geometry]")
{
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> ang(-1.7, 1.7);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d w(ang(rng), ang(rng), ang(rng));
    const vpRotationMatrix R(vpThetaUVector(w.x(), w.y(), w.z()));
    const Eigen::Matrix3d E = expSO3<double>(w);
    for (unsigned i = 0; i < 3; ++i)
      for (unsigned j = 0; j < 3; ++j)
        REQUIRE(E(i, j) == Approx(R[i][j]).margin(kRoundOff));
    REQUIRE((logSO3(E) - w).norm() < 1e-9);
  }
  // Central differences at zero: dExp/dw_i = [e_i]x; and the small-angle branch is continuous.
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e(i) = h;
    const Eigen::Matrix3d D = (expSO3<double>(e) - expSO3<double>(Eigen::Vector3d(-e))) / (2 * h);
    Eigen::Matrix3d K = Eigen::Matrix3d::Zero();
    K(1, 2) = i == 0 ? -1 : 0;
    K(2, 1) = i == 0 ? 1 : 0;
    K(0, 2) = i == 1 ? 1 : 0;
    K(2, 0) = i == 1 ? -1 : 0;
    K(0, 1) = i == 2 ? -1 : 0;
    K(1, 0) = i == 2 ? 1 : 0;
    REQUIRE((D - K).norm() < 1e-9);
  }
  const Eigen::Vector3d tiny(3e-9, -2e-9, 1e-9);
  const vpRotationMatrix Rt(vpThetaUVector(tiny.x(), tiny.y(), tiny.z()));
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j)
      REQUIRE(expSO3<double>(tiny)(i, j) == Approx(Rt[i][j]).margin(1e-16));
}

TEST_CASE("panJointFrame: +Y on the joint's axis; a joint turn is yawdepth's yaw about the vision frame's +Y",
          "[geometry]")
{
  const Eigen::Vector3d origin(0.1, -0.02, 0.3);
  for (const Eigen::Vector3d &axis : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -2), Eigen::Vector3d(0, 1, 0),
                                      Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(1, 1, 1)}) {
    const vpHomogeneousMatrix bMv = panJointFrame(axis, origin);
    const Eigen::Vector3d a = axis.normalized();
    for (unsigned i = 0; i < 3; ++i) {
      CHECK(std::abs(bMv[i][1] - a[i]) < 1e-12); // the vision frame's +Y is the axis
      CHECK(std::abs(bMv[i][3] - origin[i]) < 1e-12);
    }
    // A camera at pan q: bMv R_y(q) vMc(0) = (the body's right-handed rotation by q about the axis,
    // through the origin) bMc(0).
    const double q = 0.4;
    const YawRig rig(Eigen::Vector3d(-0.05, 0.01, 0.02));
    const vpHomogeneousMatrix turned = bMv * rig.vMc(q);
    vpHomogeneousMatrix about(vpTranslationVector(origin[0], origin[1], origin[2]),
                              vpThetaUVector(q * a[0], q * a[1], q * a[2]));
    const vpHomogeneousMatrix expected =
        about * vpHomogeneousMatrix(vpTranslationVector(-origin[0], -origin[1], -origin[2]), vpThetaUVector(0, 0, 0)) *
        bMv * rig.vMc(0);
    for (unsigned i = 0; i < 3; ++i)
      for (unsigned j = 0; j < 4; ++j)
        CHECK(std::abs(turned[i][j] - expected[i][j]) < 1e-12);
  }
  CHECK_THROWS_AS(panJointFrame(Eigen::Vector3d::Zero(), origin), Error);
  CHECK_THROWS_AS(panJointFrame(Eigen::Vector3d(0, 0, std::nan("")), origin), Error);
  CHECK_THROWS_AS(panJointFrame(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, INFINITY)), Error);
}

TEST_CASE("TurnAxis: a frame turning about its +Y is on the pan axis; about another axis, or barely, it is not",
          "[geometry]")
{
  auto turnAbout = [](const Eigen::Vector3d &axis, double step, int steps) {
    TurnAxis t;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    t.add(R);
    for (int k = 0; k < steps; ++k) {
      const double sway = k % 2 ? 1.0 : -0.5; // back and forth: the sign alignment keeps one axis
      R = R * Eigen::AngleAxisd(sway * step, axis.normalized()).toRotationMatrix();
      t.add(R);
    }
    return t;
  };
  const TurnAxis about_y = turnAbout(Eigen::Vector3d(0, 1, 0), 0.05, 40); // every turn a step (> kKeyStep)
  CHECK(std::abs(about_y.turned() - 40 * 0.75 * 0.05) < 1e-9);
  CHECK(about_y.sum().normalized().cwiseAbs().isApprox(Eigen::Vector3d(0, 1, 0), 1e-9));
  CHECK_FALSE(about_y.offPanAxis());
  CHECK_FALSE(turnAbout(Eigen::Vector3d(0.2, 1, 0), 0.05, 40).offPanAxis()); // 11 degrees off: a floor's tilt
  CHECK(turnAbout(Eigen::Vector3d(0, 0, 1), 0.05, 40).offPanAxis());          // a z-up body read with +Y
  CHECK(turnAbout(Eigen::Vector3d(0.5, 1, 0), 0.05, 40).offPanAxis());        // 27 degrees off
  CHECK_FALSE(turnAbout(Eigen::Vector3d(0, 0, 1), 0.001, 40).offPanAxis());   // under a step each: nothing to say
  // A frame at rest with jitter (1e-4 rad per axis, roll and pitch larger, 10 s at 100 Hz): no steps,
  // no warning, whatever the jitter's axes.
  std::mt19937 rng(7);
  std::normal_distribution<double> jitter(0.0, 1e-4);
  TurnAxis rest;
  for (int k = 0; k < 1000; ++k)
    rest.add(expSO3<double>(Eigen::Vector3d(3 * jitter(rng), jitter(rng), 3 * jitter(rng))));
  CHECK(rest.turned() == 0.0);
  CHECK_FALSE(rest.offPanAxis());
}
