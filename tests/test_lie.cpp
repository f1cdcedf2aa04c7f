// Properties of the hand-written rotation helpers (in the style of Sophus's and manif's tests):
// expSO3, logSO3, skew, rotY, wrapAngle and interpolateMotion (geometry/rig.h), and the window
// model's right Jacobian rightJacobianSO3 (window_model.h, private to the window estimator).
// Seeded random points, plus the corners: angles near zero and near pi.
#include <catch2/catch.hpp>

#include "window_model.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>
#include <vector>
#include <yawdepth/geometry/rig.h>

using namespace yawdepth;

namespace {

constexpr double kRoundOff = 1e-12;       // matrix entries of order 1, a few dozen operations
constexpr double kRelRoundOff = 1e-9;     // a rotation vector back from its matrix, relative to its angle
constexpr double kFiniteDifferenceTol = 1e-7; // central differences, step kStep: O(kStep^2) + roundoff / kStep
constexpr double kStep = 1e-5;
constexpr int kRandomPoints = 200;
constexpr unsigned kSeed = 20261205;

Eigen::Vector3d randomAxis(std::mt19937_64 &rng)
{
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d a;
  do
    a = Eigen::Vector3d(n(rng), n(rng), n(rng));
  while (a.norm() < 1e-3);
  return a.normalized();
}

// A rotation vector of the given angle about a random axis.
Eigen::Vector3d randomRotationVector(std::mt19937_64 &rng, double angle) { return angle * randomAxis(rng); }

// A random rotation (uniform quaternion).
Eigen::Matrix3d randomRotation(std::mt19937_64 &rng)
{
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

double maxAbs(const Eigen::MatrixXd &M) { return M.cwiseAbs().maxCoeff(); }

// The angles of the corner cases and a spread of random ones in [0, pi).
std::vector<double> testAngles(std::mt19937_64 &rng)
{
  std::vector<double> angles = {0.0, 1e-12, 1e-9, 1e-8, 1.0001e-8, 1e-6, 1e-5, 1.0001e-5, 1e-3, 0.5, 1.0, 2.0, 3.0,
                                M_PI - 1e-3, M_PI - 1e-6};
  std::uniform_real_distribution<double> u(0.0, M_PI - 1e-6);
  for (int i = 0; i < kRandomPoints; ++i)
    angles.push_back(u(rng));
  return angles;
}

void requireRotation(const Eigen::Matrix3d &R)
{
  INFO("R =\n" << R);
  CHECK(maxAbs(R.transpose() * R - Eigen::Matrix3d::Identity()) < kRoundOff);
  CHECK(std::abs(R.determinant() - 1.0) < kRoundOff);
}

} // namespace

TEST_CASE("expSO3 gives rotations: orthonormal, determinant 1", "[lie]")
{
  std::mt19937_64 rng(kSeed);
  for (double angle : testAngles(rng)) {
    INFO("angle " << angle);
    requireRotation(expSO3<double>(randomRotationVector(rng, angle)));
  }
  // Beyond pi too (a rotation vector of any length is a rotation).
  for (double angle : {M_PI, M_PI + 1e-6, 4.0, 2 * M_PI, 10.0}) {
    INFO("angle " << angle);
    requireRotation(expSO3<double>(randomRotationVector(rng, angle)));
  }
}

TEST_CASE("expSO3 agrees with Eigen's AngleAxis", "[lie]")
{
  std::mt19937_64 rng(kSeed + 1);
  for (double angle : testAngles(rng)) {
    const Eigen::Vector3d axis = randomAxis(rng);
    INFO("angle " << angle);
    CHECK(maxAbs(expSO3<double>(Eigen::Vector3d(angle * axis)) - Eigen::AngleAxisd(angle, axis).toRotationMatrix()) <
          kRoundOff);
  }
}

TEST_CASE("log(exp(w)) = w for |w| < pi, near zero included", "[lie]")
{
  std::mt19937_64 rng(kSeed + 2);
  for (double angle : testAngles(rng)) {
    const Eigen::Vector3d w = randomRotationVector(rng, angle);
    const Eigen::Vector3d back = logSO3(expSO3<double>(w));
    INFO("angle " << angle << ", w " << w.transpose() << ", log(exp(w)) " << back.transpose());
    CHECK((back - w).norm() <= kRelRoundOff * std::max(angle, 1e-3));
  }
}

TEST_CASE("exp(log(R)) = R for random rotations and rotations near the identity and near pi", "[lie]")
{
  std::mt19937_64 rng(kSeed + 3);
  std::vector<Eigen::Matrix3d> rotations;
  for (int i = 0; i < kRandomPoints; ++i)
    rotations.push_back(randomRotation(rng));
  for (double angle : {1e-9, 1e-6, M_PI - 1e-6, M_PI})
    rotations.push_back(Eigen::AngleAxisd(angle, randomAxis(rng)).toRotationMatrix());
  for (const Eigen::Matrix3d &R : rotations) {
    const Eigen::Vector3d w = logSO3(R);
    INFO("R =\n" << R << "\nlog(R) " << w.transpose());
    CHECK(w.norm() <= M_PI + kRoundOff);
    CHECK(maxAbs(expSO3<double>(w) - R) < kRoundOff);
  }
}

TEST_CASE("log at exactly pi: w or -w, the same rotation", "[lie]")
{
  std::mt19937_64 rng(kSeed + 4);
  const std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                             Eigen::Vector3d::UnitZ(), randomAxis(rng),
                                             randomAxis(rng),          randomAxis(rng)};
  for (const Eigen::Vector3d &axis : axes) {
    const Eigen::Vector3d w = M_PI * axis;
    const Eigen::Matrix3d R = expSO3<double>(w);
    const Eigen::Vector3d back = logSO3(R);
    INFO("w " << w.transpose() << ", log(exp(w)) " << back.transpose());
    CHECK(std::abs(back.norm() - M_PI) < kRelRoundOff);
    CHECK(std::min((back - w).norm(), (back + w).norm()) < kRelRoundOff);
    CHECK(maxAbs(expSO3<double>(back) - R) < kRoundOff);
  }
}

TEST_CASE("exp(-w) is the inverse of exp(w), exp(a u) exp(b u) = exp((a + b) u)", "[lie]")
{
  std::mt19937_64 rng(kSeed + 5);
  std::uniform_real_distribution<double> u(-M_PI, M_PI);
  for (int i = 0; i < kRandomPoints; ++i) {
    const Eigen::Vector3d axis = randomAxis(rng);
    const double a = u(rng), b = u(rng);
    const Eigen::Vector3d w = a * axis;
    CHECK(maxAbs(expSO3<double>(w) * expSO3<double>(Eigen::Vector3d(-w)) - Eigen::Matrix3d::Identity()) < kRoundOff);
    CHECK(maxAbs(expSO3<double>(w) * expSO3<double>(Eigen::Vector3d(b * axis)) -
                 expSO3<double>(Eigen::Vector3d((a + b) * axis))) < kRoundOff);
  }
}

TEST_CASE("skew(a) b = a x b, skew is antisymmetric, skew(a) a = 0", "[lie]")
{
  std::mt19937_64 rng(kSeed + 6);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int i = 0; i < kRandomPoints; ++i) {
    const Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    const Eigen::Matrix3d S = skew(a);
    CHECK((S * b - a.cross(b)).norm() < kRoundOff * a.norm() * b.norm());
    CHECK(maxAbs(S + S.transpose()) == 0.0);
    CHECK((S * a).norm() < kRoundOff * a.squaredNorm());
  }
}

TEST_CASE("rightJacobianSO3: Exp(w + e) = Exp(w) Exp(Jr(w) e) to first order (central differences)", "[lie]")
{
  std::mt19937_64 rng(kSeed + 7);
  std::vector<double> angles = {0.0, 1e-9, 1e-6, 9.99e-6, 1.0001e-5, 1e-3, 0.5, 1.5, 3.0, M_PI - 1e-3};
  std::uniform_real_distribution<double> u(0.0, M_PI - 1e-3);
  for (int i = 0; i < 50; ++i)
    angles.push_back(u(rng));
  for (double angle : angles) {
    const Eigen::Vector3d w = randomRotationVector(rng, angle);
    const Eigen::Matrix3d Rt = expSO3<double>(w).transpose();
    Eigen::Matrix3d numeric;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d h = kStep * Eigen::Vector3d::Unit(k);
      numeric.col(k) = (logSO3(Rt * expSO3<double>(Eigen::Vector3d(w + h))) -
                        logSO3(Rt * expSO3<double>(Eigen::Vector3d(w - h)))) /
                       (2 * kStep);
    }
    const Eigen::Matrix3d Jr = window_detail::rightJacobianSO3(w);
    INFO("angle " << angle << "\nJr =\n" << Jr << "\nnumeric =\n" << numeric);
    CHECK(maxAbs(Jr - numeric) < kFiniteDifferenceTol);
  }
}

TEST_CASE("rightJacobianSO3 is continuous across its small-angle branch and Jr(w) w = w", "[lie]")
{
  std::mt19937_64 rng(kSeed + 8);
  const Eigen::Vector3d axis = randomAxis(rng);
  // The branch switches at |w|^2 = 1e-10.
  const Eigen::Matrix3d below = window_detail::rightJacobianSO3(Eigen::Vector3d(0.99999e-5 * axis));
  const Eigen::Matrix3d above = window_detail::rightJacobianSO3(Eigen::Vector3d(1.00001e-5 * axis));
  CHECK(maxAbs(below - above) < kFiniteDifferenceTol);
  CHECK(maxAbs(window_detail::rightJacobianSO3(Eigen::Vector3d::Zero()) - Eigen::Matrix3d::Identity()) == 0.0);
  for (double angle : {1e-9, 1e-6, 0.5, 2.0, M_PI - 1e-6}) {
    const Eigen::Vector3d w = randomRotationVector(rng, angle);
    CHECK((window_detail::rightJacobianSO3(w) * w - w).norm() < kRoundOff);
  }
}

TEST_CASE("rotY is exp of a rotation about +Y, a one-parameter group", "[lie]")
{
  std::mt19937_64 rng(kSeed + 9);
  std::uniform_real_distribution<double> u(-2 * M_PI, 2 * M_PI);
  for (int i = 0; i < kRandomPoints; ++i) {
    const double a = u(rng), b = u(rng);
    requireRotation(rotY(a));
    CHECK(maxAbs(rotY(a) - expSO3<double>(Eigen::Vector3d(0.0, a, 0.0))) < kRoundOff);
    CHECK(maxAbs(rotY(a) * rotY(b) - rotY(a + b)) < kRoundOff);
    CHECK(maxAbs(rotY(a).transpose() - rotY(-a)) < kRoundOff);
  }
}

TEST_CASE("the model's rotation helpers: rotateY, rotateYT and yawedRotation against their matrices", "[lie]")
{
  std::mt19937_64 rng(kSeed + 13);
  std::uniform_real_distribution<double> u(-2 * M_PI, 2 * M_PI);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < kRandomPoints; ++i) {
    const double a = u(rng);
    const Eigen::Vector3d v(g(rng), g(rng), g(rng));
    Eigen::Vector3d out, back;
    refine_detail::rotateY(std::cos(a), std::sin(a), v.data(), out.data());
    CHECK((out - rotY(a) * v).norm() < kRoundOff * (1 + v.norm()));
    refine_detail::rotateYT(std::cos(a), std::sin(a), out.data(), back.data());
    CHECK((back - v).norm() < kRoundOff * (1 + v.norm()));
    // Rref Exp(d) Ry(yaw): a rotation, and each factor where it should be.
    const Eigen::Matrix3d Rref = randomRotation(rng);
    const Eigen::Vector3d d = randomRotationVector(rng, std::abs(u(rng)) / 2);
    const double frame[7] = {g(rng), g(rng), g(rng), d.x(), d.y(), d.z(), a};
    const Eigen::Matrix3d V = refine_detail::yawedRotation<double>(Rref, frame);
    requireRotation(V);
    CHECK(maxAbs(V - Rref * expSO3<double>(d) * rotY(a)) < kRoundOff);
  }
}

TEST_CASE("wrapAngle: in (-pi, pi], the same direction", "[lie]")
{
  std::mt19937_64 rng(kSeed + 10);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<double> angles = {0.0, M_PI, -M_PI, 3 * M_PI, -3 * M_PI, 2 * M_PI, M_PI - 1e-12, -M_PI + 1e-12};
  for (int i = 0; i < kRandomPoints; ++i)
    angles.push_back(u(rng));
  for (double a : angles) {
    const double w = wrapAngle(a);
    INFO("angle " << a << " -> " << w);
    CHECK(w > -M_PI);
    CHECK(w <= M_PI);
    CHECK(std::abs(std::cos(w) - std::cos(a)) < kRoundOff);
    CHECK(std::abs(std::sin(w) - std::sin(a)) < kRoundOff);
  }
}

TEST_CASE("interpolateMotion's rotation: the endpoints, and the geodesic's midpoint", "[lie]")
{
  std::mt19937_64 rng(kSeed + 11);
  for (int i = 0; i < 50; ++i) {
    MotionSample a, b;
    a.six_dof = b.six_dof = true;
    a.theta_u = logSO3(randomRotation(rng));
    b.theta_u = logSO3(randomRotation(rng));
    const Eigen::Matrix3d Ra = a.rotation(), Rb = b.rotation();
    CHECK(maxAbs(interpolateMotion(a, b, 0.0).rotation() - Ra) < kRoundOff);
    CHECK(maxAbs(interpolateMotion(a, b, 1.0).rotation() - Rb) < kRoundOff);
    // The midpoint is as far from both ends.
    const Eigen::Matrix3d Rm = interpolateMotion(a, b, 0.5).rotation();
    requireRotation(Rm);
    CHECK(std::abs(logSO3(Ra.transpose() * Rm).norm() - logSO3(Rm.transpose() * Rb).norm()) < kRelRoundOff);
  }
}
