// The two-view estimators: exactness on noise-free data, the paper's eq. (5) and its bias, gates.
#include <catch2/catch.hpp>

#include <random>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/estimation/two_view.h>

#include "two_view_detail.h" // private to yawdepth::estimation

using namespace yawdepth;

namespace {

constexpr double kPinholeRelTol = 1e-9;   // docs/method.md's exactness: 1e-9 relative (pinhole)
constexpr double kDistortedRelTol = 1e-6; // and 1e-6 with distortion

CameraModel paperPinhole() { return CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {}, 640, 480); }
CameraModel paperDistorted()
{
  return CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
}
CameraModel rationalDistorted()
{
  return CameraModel::brown(800, 790, 330, 235, {-0.3, 0.12, 0.001, -0.0005, -0.02, 0.05, 0.01, 0.002}, 640, 480);
}
CameraModel vispDistorted()
{
  vpCameraParameters cam;
  cam.initPersProjWithDistortion(600, 605, 322, 244, -0.18, 0.19);
  return CameraModel(cam, 640, 480);
}

struct TwoViewScene {
  YawRig rig;
  MotionSample prev, cur;
  Eigen::Vector3d c_P_cur, c_P_prev; // truth
  Eigen::Vector2d uv_prev, uv_cur;
};

/* A random rig, pose pair and point that both cameras see inside the image. */
bool randomScene(std::mt19937_64 &rng, const CameraModel &camera, TwoViewScene &s)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0), uni(0.0, 1.0);
  s.rig = YawRig(Eigen::Vector3d(0.2 * u(rng), 0.02 * u(rng), 0.1 * u(rng)));
  s.prev.frame = 3;
  s.prev.x = u(rng);
  s.prev.y = 0.01 * u(rng);
  s.prev.z = u(rng);
  s.prev.heading = M_PI * u(rng);
  s.prev.yaw = 1.7 * u(rng);
  s.cur = s.prev;
  s.cur.frame = 4;
  // Increment: anything from 1 mm to 0.4 m, heading and yaw changes up to 0.2 rad.
  const double len = std::pow(10.0, -3.0 + 2.6 * uni(rng));
  Eigen::Vector3d d(u(rng), 0.05 * u(rng), u(rng));
  d = len * d.normalized();
  const Eigen::Vector3d w_d = rotY(s.prev.heading) * d;
  s.cur.x += w_d.x();
  s.cur.y += w_d.y();
  s.cur.z += w_d.z();
  s.cur.heading += 0.2 * u(rng);
  s.cur.yaw += 0.2 * u(rng);
  // Point: random pixel and depth in the current frame.
  Eigen::Vector2d m;
  if (!camera.undistort(Eigen::Vector2d(20 + 600 * uni(rng), 20 + 440 * uni(rng)), m))
    return false;
  const double Z = 0.3 + 4.0 * uni(rng);
  s.c_P_cur = Z * Eigen::Vector3d(m.x(), m.y(), 1.0);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(curMprev(s.rig, s.prev, s.cur), R, t);
  s.c_P_prev = R.transpose() * (s.c_P_cur - t);
  if (s.c_P_prev.z() < 0.1)
    return false;
  s.uv_cur = camera.project(m);
  s.uv_prev = camera.project(s.c_P_prev.head<2>() / s.c_P_prev.z());
  return s.uv_prev.x() > 0 && s.uv_prev.x() < 640 && s.uv_prev.y() > 0 && s.uv_prev.y() < 480;
}

void checkExactness(const CameraModel &camera, double tol, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  TwoViewOptions opt;
  int tested = 0, ok = 0;
  double worst = 0;
  for (int k = 0; k < 5000 && tested < 400; ++k) {
    TwoViewScene s;
    if (!randomScene(rng, camera, s))
      continue;
    ++tested;
    const PointEstimate e = estimateExact(camera, s.rig, s.prev, s.cur, s.uv_prev, s.uv_cur, opt);
    if (e.status == Status::Degenerate) // tiny parallax (feature near the focus of expansion)
      continue;
    REQUIRE(e.status == Status::Ok);
    ++ok;
    const double rel = (e.c_P - s.c_P_cur).norm() / s.c_P_cur.norm();
    worst = std::max(worst, rel);
    REQUIRE(rel < tol);
    // eq. (7): the vision-frame point is vTc(yaw) of the camera point.
    const Eigen::Vector3d v_P = rotY(s.cur.yaw) * (s.c_P_cur + s.rig.cameraOffset());
    REQUIRE((e.v_P - v_P).norm() < tol * v_P.norm() + 1e-12);
  }
  INFO("worst relative error " << worst);
  CHECK(tested >= 400);
  CHECK(ok >= 390);
}

/* The pixel of the camera-frame point P. */
Eigen::Vector2d pixelOf(const CameraModel &camera, const Eigen::Vector3d &P) { return camera.project(P.head<2>() / P.z()); }

/* Frames 0 and 1 of the paper's pinhole camera on its rig; a test sets their motion. */
struct TwoFrames {
  const CameraModel camera = paperPinhole();
  const YawRig rig{Eigen::Vector3d(-0.1503, 0, 0)};
  MotionSample prev, cur;
  TwoFrames()
  {
    prev.frame = 0;
    cur.frame = 1;
  }
};

} // namespace

TEST_CASE("exact is exact on noise-free data, pinhole, any increment, heading and yaw change", "[exact]")
{
  checkExactness(paperPinhole(), kPinholeRelTol, 21);
}

TEST_CASE("exact is exact on noise-free data with Brown distortion", "[exact]")
{
  checkExactness(paperDistorted(), kDistortedRelTol, 22);
  checkExactness(rationalDistorted(), kDistortedRelTol, 23);
}

TEST_CASE("exact is exact on noise-free data with ViSP's kud distortion", "[exact]")
{
  checkExactness(vispDistorted(), kDistortedRelTol, 24);
}

TEST_CASE("the u-row and v-row depth formulas are the finite-increment forms of docs/method.md", "[exact]")
{
  // Pure translation: t = -(dXc, dYc, dZc).
  const double dX = 0.028, dY = 0.001, dZ = -0.028, Z = 0.62;
  const Eigen::Vector3d P_prev(0.05, 0.03, Z + 0.0), t(-dX, -dY, -dZ);
  const Eigen::Vector3d P_cur = P_prev + t;
  const Eigen::Vector2d m_prev = P_prev.head<2>() / P_prev.z(), m_cur = P_cur.head<2>() / P_cur.z();
  const double Zk = (m_prev.x() * dZ - dX) / (m_cur.x() - m_prev.x());
  CHECK(Zk == Approx(P_cur.z()).epsilon(1e-12));
  // The rows estimateExact solves (depthRows, through rowCoefficients).
  const DepthRows<double> rows = depthRows<double>(m_prev, m_cur, Eigen::Matrix3d::Identity(), t);
  CHECK(rows.b_u / rows.a_u == Approx(P_cur.z()).epsilon(1e-12));
  CHECK(rows.b_v / rows.a_v == Approx(P_cur.z()).epsilon(1e-10));
}

TEST_CASE("paperDepth is eq. (5) through vpFeaturePoint's interaction matrix", "[paper]")
{
  // Hand-computed: kx = 1700, x = 0.1, increment (dXc, dZc) = (0.028, 0.028), du = 5 px:
  // Zc = 1700 * (0.1 * 0.028 - 0.028) / 5 = -8.568
  CHECK(paperDepth(0.1, 0.0, 5.0, 1700.0, Eigen::Vector3d(0.028, 0.0, 0.028)) == Approx(-8.568).epsilon(1e-14));
  // Side view, eq. (9) at theta = 90 deg: Z = dz kx / du. dz = 20 mm, du = 68 px -> 0.5 m.
  CHECK(paperDepth(0.0, 0.0, 68.0, 1700.0, Eigen::Vector3d(-0.02, 0.0, 0.0)) == Approx(0.5).epsilon(1e-14));
  // Front view, eq. (9) at theta = 0: Z = dz (u - u0) / du.  u - u0 = 10 px, du = 0.4 px -> 0.5 m.
  CHECK(paperDepth(10.0 / 1700.0, 0.0, 0.4, 1700.0, Eigen::Vector3d(0.0, 0.0, 0.02)) == Approx(0.5).epsilon(1e-12));
  // The y coordinate does not enter the u-row's translational part.
  CHECK(paperDepth(0.1, 0.3, 5.0, 1700.0, Eigen::Vector3d(0.028, 0.05, 0.028)) == Approx(-8.568).epsilon(1e-14));
}

TEST_CASE_METHOD(TwoFrames, "paper returns the previous frame's depth: its bias is dZc/Z", "[paper]")
{
  // The paper's experiment: 620 mm away, camera increment (+40, 0, -40) mm in the camera frame
  // (the board moved by (-40, 0, 40) mm), pure translation.
  prev.yaw = cur.yaw = 0.0;
  cur.x = 0.04;
  cur.z = -0.04;
  const Eigen::Vector3d P_prev(-0.02, 0.015, 0.62);
  const Eigen::Vector3d P_cur = P_prev - Eigen::Vector3d(0.04, 0.0, -0.04);
  const Eigen::Vector2d uv_prev = pixelOf(camera, P_prev);
  const Eigen::Vector2d uv_cur = pixelOf(camera, P_cur);
  const PointEstimate paper = estimatePaper(camera, rig, prev, cur, uv_prev, uv_cur);
  const PointEstimate exact = estimateExact(camera, rig, prev, cur, uv_prev, uv_cur);
  REQUIRE(paper.ok());
  REQUIRE(exact.ok());
  CHECK(paper.c_P.z() == Approx(P_prev.z()).epsilon(1e-10)); // exactly Z_{k-1}
  CHECK(exact.c_P.z() == Approx(P_cur.z()).epsilon(1e-10));  // exactly Z_k
  const double bias = (paper.c_P.z() - P_cur.z()) / P_cur.z();
  CHECK(bias == Approx(-0.04 / P_cur.z()).epsilon(1e-10)); // -dZc/Z: 40 mm at 660 mm
  CHECK(std::abs(bias) > 0.06);
}

TEST_CASE_METHOD(TwoFrames, "paper removes a small known rotation to first order", "[paper]")
{
  prev.yaw = M_PI / 2;
  cur.yaw = M_PI / 2 + 0.002; // the camera pans during the increment
  cur.z = 0.02;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(curMprev(rig, prev, cur), R, t);
  const Eigen::Vector3d P_cur(0.1, 0.05, 1.0), P_prev = R.transpose() * (P_cur - t);
  const Eigen::Vector2d uv_prev = pixelOf(camera, P_prev);
  const Eigen::Vector2d uv_cur = pixelOf(camera, P_cur);
  const PointEstimate paper = estimatePaper(camera, rig, prev, cur, uv_prev, uv_cur);
  REQUIRE(paper.ok());
  // Rotation of 0.002 rad moves the image by ~3.5 px against ~34 px of parallax: ignoring it
  // would cost ~10 %; the first-order removal leaves the paper's own first-order error.
  CHECK(paper.c_P.z() == Approx(1.0).epsilon(0.02));
}

TEST_CASE_METHOD(TwoFrames, "gates: no motion, focus of expansion, behind, too few frames", "[gates]")
{
  const Eigen::Vector2d centre(319.2, 241.4);

  SECTION("no motion")
  {
    for (auto f : {estimateExact, estimatePaper}) {
      const PointEstimate e = f(camera, rig, prev, cur, Eigen::Vector2d(100, 100), Eigen::Vector2d(100, 100), {});
      CHECK(e.status == Status::NoMotion);
      CHECK(std::isnan(e.c_P.z()));
    }
    // A pure yaw about the axis still moves the optical centre (offset Lb): that is motion.
    cur.yaw = 0.1;
    const PointEstimate e = estimateExact(camera, rig, prev, cur, Eigen::Vector2d(100, 100), Eigen::Vector2d(100, 100), {});
    CHECK(e.status != Status::NoMotion);
  }
  SECTION("feature at the focus of expansion")
  {
    cur.z = 0.02; // front view, forward motion: the FOE is the principal point
    for (auto f : {estimateExact, estimatePaper}) {
      const PointEstimate e = f(camera, rig, prev, cur, centre, centre, {});
      CHECK(e.status == Status::Degenerate);
      CHECK(std::isnan(e.c_P.z()));
    }
  }
  SECTION("point behind the camera")
  {
    cur.z = 0.02;
    // Image motion toward the centre while moving forward: only a point behind explains it.
    const PointEstimate e =
        estimateExact(camera, rig, prev, cur, Eigen::Vector2d(419.2, 241.4), Eigen::Vector2d(417.2, 241.4), {});
    CHECK(e.status == Status::Behind);
    const PointEstimate p =
        estimatePaper(camera, rig, prev, cur, Eigen::Vector2d(419.2, 241.4), Eigen::Vector2d(417.2, 241.4), {});
    CHECK(p.status == Status::Behind);
  }
  SECTION("one frame only")
  {
    Track track;
    track.id = 5;
    track.observations.push_back({0, 100.0, 100.0});
    const PointEstimate e = estimateTrack(camera, rig, {prev, cur}, track);
    CHECK(e.status == Status::TooFewFrames);
    CHECK(std::string(toString(e.status)) == "too_few_frames");
  }
  SECTION("thresholds are settable")
  {
    cur.z = 0.02;
    // 1 px of parallax passes the default gate and fails a 2 px gate.
    const Eigen::Vector2d a(419.2, 241.4), b(420.2, 241.4);
    CHECK(estimateExact(camera, rig, prev, cur, a, b, {}).ok());
    TwoViewOptions strict;
    strict.gates.min_parallax_px = 2.0;
    CHECK(estimateExact(camera, rig, prev, cur, a, b, strict).status == Status::Degenerate);
  }
}

TEST_CASE("estimateTrack uses the last two observations and reports at the last frame", "[track]")
{
  const CameraModel camera = paperPinhole();
  const YawRig rig(Eigen::Vector3d(-0.1503, 0, 0));
  std::vector<MotionSample> motion(4);
  for (int k = 0; k < 4; ++k) {
    motion[k].frame = 10 + k;
    motion[k].z = 0.02 * k;
    motion[k].yaw = M_PI / 2;
  }
  const Eigen::Vector3d v_P(0.9, 0.05, 0.3); // in the vision frame of frame 0 (= world here)
  Track track;
  track.id = 1;
  for (int k : {0, 1, 3}) { // frame 12 missing: the last increment spans two rows
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    fromVisp(wMc(rig, motion[k]).inverse(), R, t);
    const Eigen::Vector3d c_P = R * v_P + t;
    const Eigen::Vector2d uv = pixelOf(camera, c_P);
    track.observations.push_back({motion[k].frame, uv.x(), uv.y()});
  }
  const PointEstimate e = estimateTrack(camera, rig, motion, track);
  REQUIRE(e.ok());
  CHECK(e.frame == 13);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(wMc(rig, motion[3]).inverse(), R, t);
  CHECK((e.c_P - (R * v_P + t)).norm() < 1e-9);
  // An observation in a frame the motion log does not have is an error, not a silent guess.
  track.observations.back().frame = 99;
  CHECK_THROWS(estimateTrack(camera, rig, motion, track));
}
