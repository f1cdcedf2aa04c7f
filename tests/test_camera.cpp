// Tests of the camera module: distortion models, exact undistortion, camera files.
#include <catch2/catch.hpp>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <string>
#include <unistd.h>
#include <vector>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpMeterPixelConversion.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/error.h>

using yawdepth::CameraModel;
using Distortion = yawdepth::CameraModel::Distortion;

namespace {

constexpr unsigned kSeed = 20240607u;
constexpr int kRandomPoints = 500;
// Round trip project -> undistort -> project, noise-free (pixels).
constexpr double kRoundTripTolPx = 1e-9;
// Recovered normalised point vs the true one (normalised units).
constexpr double kNormalisedTol = 1e-12;
// Central finite differences: steps and relative tolerances.
constexpr double kFdStepNormalised = 1e-6;
constexpr double kFdStepPixel = 1e-3;
constexpr double kDistortJacobianTol = 1e-8; // relative to max(1, |J|)
constexpr double kUndistortJacobianTol = 1e-7; // relative to |J|
// Agreement with ViSP's and OpenCV's own projection (pixels).
constexpr double kReferenceTolPx = 1e-9;

// Kannala-Brandt: agreement with cv::fisheye::distortPoints (px), with cv::fisheye::undistortPoints
// (normalised, relative to max(1, |m|): OpenCV stops its Newton iterations at 1e-8 or after 10),
// and recovered normalised points (relative to max(1, |m|): toward 90 degrees |m| = tan(theta)
// grows as 1/cos^2 of the angle's rounding).
constexpr double kFisheyeReferenceTolPx = 1e-9;
constexpr double kFisheyeOpenCvUndistortTol = 1e-7;
constexpr double kFisheyeNormalisedRelTol = 1e-12;
// Largest ray angle of the random fisheye points (radians, 85 degrees).
constexpr double kFisheyeMaxTestAngle = 85.0 * M_PI / 180.0;
// Pixel step of the fisheye undistortion's central differences: toward 85 degrees the inverse
// curves strongly (|m| = tan(theta)), so the step is smaller than kFdStepPixel.
constexpr double kFdStepPixelFisheye = 1e-4;
// cv::fisheye::undistortPoints converged on a point when its result reprojects within this (px).
constexpr double kOpenCvConvergedPx = 1e-6;

const std::string kData = std::string(YAWDEPTH_TEST_DATA_DIR) + "/camera/";
const std::string kCalib = std::string(YAWDEPTH_CALIB_DIR) + "/";

/*! Temporary folder removed at the end of the test case. */
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() /
           ("yawdepth_test_camera_" + std::to_string(static_cast<long>(::getpid())));
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string file(const std::string &name) const { return (path / name).string(); }
};

struct NamedCamera {
  std::string name;
  CameraModel cam;
};

std::vector<NamedCamera> distortedCameras() {
  vpCameraParameters kud;
  kud.initPersProjWithDistortion(600.0, 602.0, 321.5, 238.25, -0.2, 0.21);
  vpCameraParameters kud_pin;
  kud_pin.initPersProjWithDistortion(800.0, 799.0, 320.0, 240.0, 0.15, -0.14);
  return {
      {"Brown 4 (paper)", CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480)},
      {"Brown 4 wide", CameraModel::brown(500.0, 505.0, 322.0, 236.0, {-0.3, 0.09, 0.002, -0.001}, 640, 480)},
      {"Brown 5", CameraModel::brown(900.5, 901.5, 640.25, 360.75, {-0.25, 0.1, 0.001, -0.002, -0.03}, 1280, 720)},
      {"Brown 8 rational", CameraModel::brown(1100.0, 1102.0, 400.5, 300.5, {0.12, -0.05, 0.001, -0.0015, 0.02, 0.3, -0.04, 0.01}, 800, 600)},
      {"ViSP kud barrel", CameraModel(kud, 640, 480)},
      {"ViSP kud pincushion", CameraModel(kud_pin, 640, 480)},
  };
}

/*! Random undistorted normalised point whose pinhole projection lies in the image. */
Eigen::Vector2d randomNormalised(const CameraModel &cam, std::mt19937 &rng) {
  std::uniform_real_distribution<double> U(0.0, cam.width()), V(0.0, cam.height());
  return Eigen::Vector2d((U(rng) - cam.u0()) / cam.kx(), (V(rng) - cam.v0()) / cam.ky());
}

/*! Loading must fail with a one-line yawdepth::Error naming the file and containing `needle`. */
void requireRejected(const std::string &path, const std::string &name, const std::string &needle) {
  INFO("file " << path << ", camera name '" << name << "'");
  bool thrown = false;
  try {
    (void)yawdepth::loadCameraFile(path, name);
  } catch (const yawdepth::Error &e) {
    thrown = true;
    const std::string msg = e.what();
    INFO("message: " << msg);
    CHECK(msg.find(path) != std::string::npos);
    CHECK(msg.find('\n') == std::string::npos);
    CHECK(msg.find(needle) != std::string::npos);
  } catch (...) {
    FAIL("not a yawdepth::Error");
  }
  REQUIRE(thrown);
}

} // namespace

TEST_CASE("camera: default camera is identity-like", "[camera]") {
  const CameraModel cam;
  REQUIRE(cam.distortion() == Distortion::None);
  REQUIRE(cam.kx() == 1.0);
  REQUIRE(cam.ky() == 1.0);
  REQUIRE(cam.u0() == 0.0);
  REQUIRE(cam.v0() == 0.0);
  REQUIRE(cam.brownCoefficients().size() == 8);
  const Eigen::Vector2d p = cam.project(Eigen::Vector2d(0.3, -0.7));
  REQUIRE(p.x() == 0.3);
  REQUIRE(p.y() == -0.7);
}

TEST_CASE("camera: round trip project -> undistort -> project", "[camera]") {
  std::mt19937 rng(kSeed);
  for (const auto &nc : distortedCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst_px = 0, worst_m = 0;
    int failures = 0;
    for (int i = 0; i < kRandomPoints; ++i) {
      const Eigen::Vector2d m = randomNormalised(cam, rng);
      const Eigen::Vector2d uv = cam.project(m);
      Eigen::Vector2d m2;
      if (!cam.undistort(uv, m2)) {
        ++failures;
        continue;
      }
      worst_px = std::max(worst_px, (cam.project(m2) - uv).norm());
      worst_m = std::max(worst_m, (m2 - m).norm());
      Eigen::Vector2d uv_undist;
      REQUIRE(cam.undistortPixel(uv, uv_undist));
      REQUIRE((uv_undist - Eigen::Vector2d(cam.u0() + cam.kx() * m.x(), cam.v0() + cam.ky() * m.y())).norm() <
              1e-6);
    }
    CHECK(failures == 0);
    CHECK(worst_px < kRoundTripTolPx);
    CHECK(worst_m < kNormalisedTol);
  }
}

TEST_CASE("camera: Brown model matches OpenCV projectPoints / undistortPoints", "[camera]") {
  // Reference values computed once with cv::projectPoints (OpenCV 4.6) for these models.
  struct Ref {
    double x, y, u, v;
  };
  const CameraModel c8 =
      CameraModel::brown(1100, 1102, 400.5, 300.5, {0.12, -0.05, 0.001, -0.0015, 0.02, 0.3, -0.04, 0.01});
  const Ref r8[] = {{0.1, -0.2, 509.36246149625396, 82.269013511142049},
                    {-0.3, 0.25, 78.518246918125783, 569.26396495926167},
                    {0.35, 0.3, 770.98120747755047, 619.16795114825516},
                    {-0.02, 0.01, 378.49939475802859, 311.5204409212057}};
  const CameraModel c5 = CameraModel::brown(1100, 1102, 400.5, 300.5, {-0.25, 0.1, 0.001, -0.002, -0.03});
  const Ref r5[] = {{0.1, -0.2, 508.95408750000001, 83.032146499999982},
                    {-0.3, 0.25, 81.452404873437445, 566.74436471929687},
                    {0.35, 0.3, 765.89906025390621, 614.90426544140632},
                    {-0.02, 0.01, 378.49944945008252, 311.52027577545869}};
  REQUIRE(c8.distortion() == Distortion::Brown);
  for (const auto &[cam, refs] : {std::make_pair(&c8, r8), std::make_pair(&c5, r5)}) {
    for (int i = 0; i < 4; ++i) {
      const Ref &r = refs[i];
      const Eigen::Vector2d uv = cam->project(Eigen::Vector2d(r.x, r.y));
      CHECK(std::abs(uv.x() - r.u) < kReferenceTolPx);
      CHECK(std::abs(uv.y() - r.v) < kReferenceTolPx);
      Eigen::Vector2d m;
      REQUIRE(cam->undistort(Eigen::Vector2d(r.u, r.v), m));
      CHECK((m - Eigen::Vector2d(r.x, r.y)).norm() < kNormalisedTol);
    }
  }
}

/* Relative error of distortNormalized()'s Jacobian at normalised point m against central finite
   differences (the value with and without the Jacobian must be identical). */
static double distortJacobianError(const CameraModel &cam, const Eigen::Vector2d &m) {
  Eigen::Matrix2d J;
  const Eigen::Vector2d d = cam.distortNormalized(m, &J);
  REQUIRE((d - cam.distortNormalized(m)).norm() == 0.0);
  Eigen::Matrix2d Jfd;
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector2d h = Eigen::Vector2d::Zero();
    h[k] = kFdStepNormalised;
    Jfd.col(k) = (cam.distortNormalized(m + h) - cam.distortNormalized(m - h)) / (2 * kFdStepNormalised);
  }
  return (J - Jfd).cwiseAbs().maxCoeff() / std::max(1.0, J.cwiseAbs().maxCoeff());
}

TEST_CASE("camera: distortNormalized Jacobian matches central differences", "[camera]") {
  std::mt19937 rng(kSeed + 1);
  for (const auto &nc : distortedCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst = 0;
    for (int i = 0; i < kRandomPoints; ++i) {
      worst = std::max(worst, distortJacobianError(cam, randomNormalised(cam, rng)));
    }
    CHECK(worst < kDistortJacobianTol);
  }
}

/* The largest difference, relative to the Jacobian's largest entry, between undistort()'s
   Jacobian at pixel uv and central differences of step `step` (px); every undistortion must succeed. */
static double undistortJacobianError(const CameraModel &cam, const Eigen::Vector2d &uv, double step) {
  Eigen::Vector2d m;
  Eigen::Matrix2d J;
  REQUIRE(cam.undistort(uv, m, &J));
  Eigen::Matrix2d Jfd;
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector2d h = Eigen::Vector2d::Zero();
    h[k] = step;
    Eigen::Vector2d mp, mm;
    REQUIRE(cam.undistort(uv + h, mp));
    REQUIRE(cam.undistort(uv - h, mm));
    Jfd.col(k) = (mp - mm) / (2 * step);
  }
  return (J - Jfd).cwiseAbs().maxCoeff() / J.cwiseAbs().maxCoeff();
}

TEST_CASE("camera: undistort Jacobian matches central differences", "[camera]") {
  std::mt19937 rng(kSeed + 2);
  for (const auto &nc : distortedCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst = 0;
    for (int i = 0; i < kRandomPoints; ++i) {
      worst = std::max(worst, undistortJacobianError(cam, cam.project(randomNormalised(cam, rng)), kFdStepPixel));
    }
    CHECK(worst < kUndistortJacobianTol);
  }
}

TEST_CASE("camera: ViSP kud model matches vpMeterPixelConversion", "[camera]") {
  std::mt19937 rng(kSeed + 3);
  std::uniform_real_distribution<double> kud_dist(-0.4, 0.4);
  std::uniform_real_distribution<double> xy(-0.6, 0.6);
  for (int c = 0; c < 20; ++c) {
    vpCameraParameters vp;
    const double kud = kud_dist(rng);
    vp.initPersProjWithDistortion(700.0 + c, 705.0 - c, 315.0 + c, 245.0 - c, kud, -kud);
    const CameraModel cam(vp, 640, 480);
    REQUIRE(cam.distortion() == Distortion::ViSP);
    REQUIRE(cam.parameters().get_projModel() == vpCameraParameters::perspectiveProjWithDistortion);
    REQUIRE(cam.parameters().get_kud() == kud);
    REQUIRE(cam.parameters().get_kdu() == -kud);
    REQUIRE(cam.brownCoefficients()[0] == kud);
    for (int i = 0; i < 50; ++i) {
      const double x = xy(rng), y = xy(rng);
      double u = 0, v = 0;
      vpMeterPixelConversion::convertPoint(vp, x, y, u, v);
      const Eigen::Vector2d uv = cam.project(Eigen::Vector2d(x, y));
      CHECK(std::abs(uv.x() - u) < kReferenceTolPx);
      CHECK(std::abs(uv.y() - v) < kReferenceTolPx);
      // The exact inverse, through the ViSP-typed entry point too.
      double xm = 0, ym = 0;
      cam.pixelToMeter(vpImagePoint(v, u), xm, ym); // vpImagePoint(i = v, j = u)
      CHECK(std::abs(xm - x) < kNormalisedTol);
      CHECK(std::abs(ym - y) < kNormalisedTol);
    }
  }
}

TEST_CASE("camera: no distortion is exact division, parameters() is the pinhole", "[camera]") {
  vpCameraParameters vp;
  vp.initPersProjWithoutDistortion(1000.0, 1001.0, 320.5, 240.5);
  const CameraModel a(vp, 640, 480);
  const CameraModel b = CameraModel::brown(1000.0, 1001.0, 320.5, 240.5, {});
  for (const CameraModel *cam : {&a, &b}) {
    REQUIRE(cam->distortion() == Distortion::None);
    Eigen::Vector2d m;
    Eigen::Matrix2d J;
    REQUIRE(cam->undistort(Eigen::Vector2d(100.0, 400.0), m, &J));
    REQUIRE(m.x() == (100.0 - 320.5) / 1000.0);
    REQUIRE(m.y() == (400.0 - 240.5) / 1001.0);
    REQUIRE(J(0, 0) == 1.0 / 1000.0);
    REQUIRE(J(1, 1) == 1.0 / 1001.0);
    REQUIRE(J(0, 1) == 0.0);
    REQUIRE(J(1, 0) == 0.0);
    REQUIRE(cam->parameters().get_projModel() == vpCameraParameters::perspectiveProjWithoutDistortion);
  }
  const CameraModel c = CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035});
  REQUIRE(c.parameters().get_projModel() == vpCameraParameters::perspectiveProjWithoutDistortion);
  REQUIRE(c.parameters().get_px() == 1734.1);
  REQUIRE(c.parameters().get_py() == 1734.5);
  REQUIRE(c.parameters().get_u0() == 319.2);
  REQUIRE(c.parameters().get_v0() == 241.4);
}

TEST_CASE("camera: invalid parameters are rejected", "[camera]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  using yawdepth::Error;
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 1000, 320, 240, {0.1, 0.2, 0.3}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 1000, 320, 240, std::vector<double>(6, 0.0)), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 1000, 320, 240, std::vector<double>(12, 0.0)), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(-1000, 1000, 320, 240, {}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 0, 320, 240, {}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(nan, 1000, 320, 240, {}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(inf, 1000, 320, 240, {}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 1000, nan, 240, {}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 1000, 320, inf, {}), Error);
  REQUIRE_THROWS_AS(CameraModel::brown(1000, 1000, 320, 240, {0.1, nan, 0, 0}), Error);
  REQUIRE_NOTHROW(CameraModel::brown(1000, 1000, 320, 240, {0.1, 0.0, 0, 0, 0.01}));
  try {
    (void)CameraModel::brown(1000, 1000, 320, 240, {0.1, 0.2, 0.3});
    FAIL("no exception");
  } catch (const Error &e) {
    REQUIRE(std::string(e.what()).find('\n') == std::string::npos);
    REQUIRE(std::string(e.what()).find("3 distortion coefficients") != std::string::npos);
  }
  vpCameraParameters kb;
  kb.initProjWithKannalaBrandtDistortion(500, 500, 320, 240, {0.1, 0.01, 0.0, 0.0});
  REQUIRE_THROWS_AS(CameraModel(kb), Error);
  vpCameraParameters neg;
  neg.initPersProjWithoutDistortion(-500, 500, 320, 240);
  REQUIRE_THROWS_AS(CameraModel(neg), Error);
}

TEST_CASE("camera: undistort fails outside the valid range of a strong model", "[camera]") {
  // x_d = x (1 - 0.5 r^2) folds at r = sqrt(2/3), where x_d reaches 0.5443.
  const CameraModel cam = CameraModel::brown(500, 500, 320, 240, {-0.5, 0, 0, 0});
  Eigen::Vector2d m;
  // Inside: fine, and exact.
  REQUIRE(cam.undistort(cam.project(Eigen::Vector2d(0.3, -0.2)), m));
  REQUIRE((m - Eigen::Vector2d(0.3, -0.2)).norm() < kNormalisedTol);
  // Distorted radius 5 (far outside; the cubic has only a mirrored root on the folded branch).
  REQUIRE_FALSE(cam.undistort(Eigen::Vector2d(320 + 500 * 5.0, 240), m));
  REQUIRE_FALSE(cam.undistort(Eigen::Vector2d(320 + 500 * 3.0, 240 + 500 * 4.0), m));
  // Just past the fold.
  REQUIRE_FALSE(cam.undistort(Eigen::Vector2d(320 + 500 * 0.6, 240), m));
  // Distorted radius 0.5 has three roots (0.618, 1, -1.618): only the one on the valid branch.
  REQUIRE(cam.undistort(Eigen::Vector2d(320 + 500 * 0.5, 240), m));
  REQUIRE(std::abs(m.x() - (std::sqrt(5.0) - 1) / 2) < kNormalisedTol);
  // Non-finite input.
  REQUIRE_FALSE(cam.undistort(Eigen::Vector2d(std::numeric_limits<double>::quiet_NaN(), 240), m));
  double x = 0, y = 0;
  REQUIRE_THROWS_AS(cam.pixelToMeter(vpImagePoint(240, 320 + 500 * 5.0), x, y), yawdepth::Error);
  REQUIRE_NOTHROW(cam.pixelToMeter(vpImagePoint(250, 330), x, y));
}

TEST_CASE("camera: paper camera files", "[camera][file]") {
  for (const std::string name : {"paper", ""}) {
    const CameraModel xml = yawdepth::loadCameraFile(kCalib + "paper_camera.xml", name);
    REQUIRE(xml.distortion() == Distortion::None);
    REQUIRE(xml.kx() == 1734.1);
    REQUIRE(xml.ky() == 1734.5);
    REQUIRE(xml.u0() == 319.2);
    REQUIRE(xml.v0() == 241.4);
    REQUIRE(xml.width() == 640);
    REQUIRE(xml.height() == 480);
  }
  const CameraModel yaml = yawdepth::loadCameraFile(kCalib + "paper_camera.yaml");
  REQUIRE(yaml.distortion() == Distortion::Brown);
  REQUIRE(yaml.kx() == 1734.1);
  REQUIRE(yaml.ky() == 1734.5);
  REQUIRE(yaml.u0() == 319.2);
  REQUIRE(yaml.v0() == 241.4);
  REQUIRE(yaml.width() == 640);
  REQUIRE(yaml.height() == 480);
  const std::vector<double> k{-0.11042, 0.43607, -0.00084, 0.00035, 0, 0, 0, 0};
  REQUIRE(yaml.brownCoefficients() == k);
}

TEST_CASE("camera: other camera files load", "[camera][file]") {
  SECTION("ViSP XML prefers the model with distortion") {
    const CameraModel c = yawdepth::loadCameraFile(kData + "visp_kud.xml", "kudcam");
    REQUIRE(c.distortion() == Distortion::ViSP);
    REQUIRE(c.kx() == 1190);
    REQUIRE(c.ky() == 1191);
    REQUIRE(c.u0() == 312);
    REQUIRE(c.v0() == 232);
    REQUIRE(c.parameters().get_kud() == -0.2);
    REQUIRE(c.parameters().get_kdu() == 0.21);
    REQUIRE(c.width() == 640);
    REQUIRE(yawdepth::loadCameraFile(kData + "visp_kud.xml").distortion() == Distortion::ViSP);
  }
  SECTION("ViSP XML with two cameras, picked by name") {
    const CameraModel a = yawdepth::loadCameraFile(kData + "two_cameras.xml", "a");
    REQUIRE(a.distortion() == Distortion::ViSP);
    REQUIRE(a.kx() == 1000);
    REQUIRE(a.parameters().get_kud() == -0.1);
    const CameraModel b = yawdepth::loadCameraFile(kData + "two_cameras.xml", "b");
    REQUIRE(b.distortion() == Distortion::None);
    REQUIRE(b.kx() == 800);
    REQUIRE(b.ky() == 801);
  }
  SECTION("ViSP XML camera without a name") {
    const CameraModel c = yawdepth::loadCameraFile(kData + "unnamed_camera.xml");
    REQUIRE(c.kx() == 500);
    REQUIRE(c.width() == 320);
    REQUIRE(c.height() == 240);
  }
  SECTION("OpenCV YAML, 5 coefficients as a column") {
    const CameraModel c = yawdepth::loadCameraFile(kData + "five_coeffs_column.yaml");
    REQUIRE(c.distortion() == Distortion::Brown);
    REQUIRE(c.kx() == 900.5);
    REQUIRE(c.v0() == 360.75);
    REQUIRE(c.brownCoefficients()[4] == -0.03);
    REQUIRE(c.width() == 1280);
    REQUIRE(c.height() == 720);
  }
  SECTION("OpenCV XML, 8 coefficients") {
    const CameraModel c = yawdepth::loadCameraFile(kData + "eight_coeffs.xml");
    REQUIRE(c.distortion() == Distortion::Brown);
    REQUIRE(c.kx() == 1100);
    REQUIRE(c.ky() == 1102);
    REQUIRE(c.brownCoefficients()[7] == 0.01);
    REQUIRE(c.width() == 800);
  }
  SECTION("YAML without header, plain sequences, no distortion key") {
    const CameraModel c = yawdepth::loadCameraFile(kData + "no_header_sequences.yaml");
    REQUIRE(c.distortion() == Distortion::None);
    REQUIRE(c.kx() == 700);
    REQUIRE(c.ky() == 710);
    REQUIRE(c.width() == 0);
  }
}

TEST_CASE("camera: loading does not print", "[camera][file]") {
  // vpXmlParserCamera::parse prints "Found camera with name ..." on std::cout; we silence it.
  std::ostringstream out, err;
  std::streambuf *old_out = std::cout.rdbuf(out.rdbuf());
  std::streambuf *old_err = std::cerr.rdbuf(err.rdbuf());
  try {
    (void)yawdepth::loadCameraFile(kCalib + "paper_camera.xml", "paper");
    (void)yawdepth::loadCameraFile(kData + "two_cameras.xml", "a");
    for (const char *bad : {"visp_without_model.xml", "malformed.xml", "visp_zero_focal.xml", "two_cameras.xml",
                            "garbage.txt", "nan_camera_matrix.yaml", "three_coeffs.yaml", "missing.yaml"}) {
      try {
        (void)yawdepth::loadCameraFile(kData + bad, "");
      } catch (const yawdepth::Error &) {
      }
    }
    {
      const TempDir tmp;
      try {
        yawdepth::saveCameraYaml(tmp.file("no_such_dir/x.yaml"), CameraModel());
      } catch (const yawdepth::Error &) {
      }
    }
  } catch (...) {
    std::cout.rdbuf(old_out);
    std::cerr.rdbuf(old_err);
    throw;
  }
  std::cout.rdbuf(old_out);
  std::cerr.rdbuf(old_err);
  REQUIRE(out.str().empty());
  REQUIRE(err.str().empty());
  // And the streams work again afterwards.
  REQUIRE(std::cout.good());
}

TEST_CASE("camera: malformed camera files are rejected", "[camera][file]") {
  requireRejected(kData + "does_not_exist.yaml", "", "not found");
  requireRejected(kData, "", "directory");
  requireRejected(kData + "empty.yaml", "", "empty");
  requireRejected(kData + "garbage.txt", "", "not a camera file");
  requireRejected(kData + "no_camera_matrix.yaml", "", "camera_matrix");
  requireRejected(kData + "nan_camera_matrix.yaml", "", "non-finite");
  requireRejected(kData + "inf_camera_matrix.yaml", "", "non-finite");
  requireRejected(kData + "three_coeffs.yaml", "", "3 distortion coefficients");
  requireRejected(kData + "negative_focal.yaml", "", "fx");
  requireRejected(kData + "negative_width.yaml", "", "image_width");
  requireRejected(kData + "two_cameras.xml", "zz", "'zz'");
  requireRejected(kData + "two_cameras.xml", "", "several cameras");
  requireRejected(kData + "two_cameras.xml", "", "(a, b)");
  requireRejected(kCalib + "paper_camera.xml", "nope", "'nope'");
  requireRejected(kData + "malformed.xml", "bad", "bad");
  requireRejected(kData + "visp_without_model.xml", "broken", "broken");
  requireRejected(kData + "visp_zero_focal.xml", "zero", "zero");
}

TEST_CASE("camera: saveCameraYaml round trip", "[camera][file]") {
  const TempDir tmp;
  vpCameraParameters kud;
  kud.initPersProjWithDistortion(600.0, 602.0, 321.5, 238.25, -0.2, 0.21);
  const std::vector<NamedCamera> cams = {
      {"none", CameraModel::brown(1000.25, 1001.5, 320.125, 240.0625, {}, 640, 480)},
      {"brown4", CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480)},
      {"brown5", CameraModel::brown(900.5, 901.5, 640.25, 360.75, {-0.25, 0.1, 0.001, -0.002, -0.03}, 1280, 720)},
      {"brown8", CameraModel::brown(1100, 1102, 400.5, 300.5, {0.12, -0.05, 0.001, -0.0015, 0.02, 0.3, -0.04, 0.01})},
      {"visp", CameraModel(kud, 640, 480)},
  };
  std::mt19937 rng(kSeed + 4);
  for (const auto &nc : cams) {
    INFO(nc.name);
    const std::string path = tmp.file(nc.name + ".yaml");
    yawdepth::saveCameraYaml(path, nc.cam);
    const CameraModel c = yawdepth::loadCameraFile(path);
    REQUIRE(c.kx() == nc.cam.kx());
    REQUIRE(c.ky() == nc.cam.ky());
    REQUIRE(c.u0() == nc.cam.u0());
    REQUIRE(c.v0() == nc.cam.v0());
    REQUIRE(c.width() == nc.cam.width());
    REQUIRE(c.height() == nc.cam.height());
    REQUIRE(c.brownCoefficients() == nc.cam.brownCoefficients());
    REQUIRE((c.distortion() == Distortion::None) == (nc.cam.distortion() == Distortion::None));
    // Same projection (the ViSP kud model is saved as Brown k1 = kud).
    std::uniform_real_distribution<double> xy(-0.3, 0.3);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector2d m(xy(rng), xy(rng));
      REQUIRE((c.project(m) - nc.cam.project(m)).norm() < kReferenceTolPx);
    }
  }
  REQUIRE_THROWS_AS(yawdepth::saveCameraYaml(tmp.file("no_such_dir/x.yaml"), cams[0].cam), yawdepth::Error);
}

// Inputs that once crashed fuzz_camera_file (tests/data/regress/camera_file/): each is rejected
// with a one-line yawdepth::Error, never anything else.
TEST_CASE("camera file: fuzzer regressions are rejected cleanly", "[camera][file][regress]") {
  const std::string dir = std::string(YAWDEPTH_TEST_DATA_DIR) + "/regress/camera_file/";
  // A stray byte before `rows`' value made OpenCV size the matrix at 48 GB.
  requireRejected(dir + "huge_matrix_rows.yaml", "", "camera_matrix is not a matrix");
  // An indented first key, a line "--", then "-": OpenCV's YAML parser looped forever.
  requireRejected(dir + "yaml_endless_loop.yaml", "", "top level must be a map");
  // NUL bytes in an OpenCV XML file: OpenCV dereferenced a null pointer.
  requireRejected(dir + "xml_nul_bytes.xml", "", "NUL byte");
  std::size_t n = 0;
  for (const auto &entry : std::filesystem::directory_iterator(dir)) {
    ++n;
    for (const char *name : {"", "paper"})
      requireRejected(entry.path().string(), name, "");
  }
  REQUIRE(n >= 1);
}

// OpenCV's parsers recurse once per nesting level without a limit: deep nesting is rejected
// before they see it (it would overflow the stack).
TEST_CASE("camera file: deep nesting is rejected before OpenCV parses it", "[camera][file][regress]") {
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("yawdepth_test_nesting_" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(dir);
  const std::size_t n = 200000;
  const std::vector<std::pair<std::string, std::string>> files = {
      {"flow.yaml", "%YAML:1.0\ncamera_matrix: " + std::string(n, '[') + "1" + std::string(n, ']') + "\n"},
      {"block.yaml", "%YAML:1.0\ncamera_matrix:\n  " + [&] {
         std::string s;
         for (std::size_t i = 0; i < n; ++i)
           s += "- ";
         return s + "1\n";
       }()},
      {"deep.xml", "<?xml version=\"1.0\"?>\n<opencv_storage>\n" + [&] {
         std::string s;
         for (std::size_t i = 0; i < n; ++i)
           s += "<a>";
         return s + "1";
       }() + "\n</opencv_storage>\n"},
  };
  for (const auto &[name, text] : files) {
    const std::string path = dir + "/" + name;
    std::ofstream(path, std::ios::binary) << text;
    requireRejected(path, "", "nested more than 16 levels deep");
  }
  // Nesting as deep as a real file is fine.
  const std::string ok = dir + "/ok.yaml";
  std::ofstream(ok, std::ios::binary) << "%YAML:1.0\ncamera_matrix: !!opencv-matrix { rows: 3, cols: 3, dt: d, data: [ 1734.1, 0, 319.2, 0, 1734.5, 241.4, 0, 0, 1 ] }\n";
  CHECK_NOTHROW(yawdepth::loadCameraFile(ok));
  std::filesystem::remove_all(dir);
}

TEST_CASE("camera files: implausible cameras are refused with the reason", "[camera][io]") {
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("yawdepth_implausible_" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(dir);
  auto camera = [&](const std::string &name, const std::string &K, const std::string &D, int w = 640, int h = 480) {
    const std::string path = dir + "/" + name + ".yaml";
    std::ofstream(path, std::ios::binary)
        << "%YAML:1.0\nimage_width: " << w << "\nimage_height: " << h
        << "\ncamera_matrix: !!opencv-matrix { rows: 3, cols: 3, dt: d, data: [ " << K
        << " ] }\ndistortion_coefficients: !!opencv-matrix { rows: 1, cols: 4, dt: d, data: [ " << D << " ] }\n";
    return path;
  };
  const std::string K = "600, 0, 320, 0, 600, 240, 0, 0, 1";
  // Real lenses, strong barrel distortion included, load.
  CHECK_NOTHROW(yawdepth::loadCameraFile(camera("ok", K, "-0.11042, 0.43607, -0.00084, 0.00035")));
  CHECK_NOTHROW(yawdepth::loadCameraFile(camera("barrel", K, "-0.35, 0.12, 0.001, -0.001")));
  CHECK_NOTHROW(yawdepth::loadCameraFile(YAWDEPTH_CALIB_DIR "/paper_camera.yaml"));
  CHECK_NOTHROW(yawdepth::loadCameraFile(YAWDEPTH_CALIB_DIR "/paper_camera.xml"));
  // k1 = 1e6 squeezes the whole image into a 1 degree field; k1 = -1e6 folds it back.
  requireRejected(camera("k1_big", K, "1e6, 0, 0, 0"), "", "implausible camera: the distortion maps pixel");
  requireRejected(camera("k1_negative", K, "-1e6, 0, 0, 0"), "", "implausible camera: the distortion");
  requireRejected(camera("k1_folds", K, "-2, 0, 0, 0"), "", "implausible camera: the distortion");
  requireRejected(camera("fx_huge", "1e308, 0, 320, 0, 600, 240, 0, 0, 1", "0, 0, 0, 0"), "", "focal length 1e+308");
  requireRejected(camera("aspect", "6000, 0, 320, 0, 60, 240, 0, 0, 1", "0, 0, 0, 0"), "", "differ by more than 10x");
  requireRejected(camera("u0_far", "600, 0, 1e7, 0, 600, 240, 0, 0, 1", "0, 0, 0, 0"), "", "principal point");
  requireRejected(camera("wide", K, "0, 0, 0, 0", 2147483647, 480), "", "image size 2147483647x480");
  std::filesystem::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Kannala-Brandt (fisheye) model

namespace {

std::vector<NamedCamera> fisheyeCameras() {
  return {
      // A RealSense T265-like lens (848x800, about 163 degrees across).
      {"KB T265-like", CameraModel::kannalaBrandt(286.2, 286.4, 423.7, 400.1, {-0.0073, 0.0446, -0.0420, 0.0077}, 848, 800)},
      // 1280x800 at 330 px: the corners are beyond 90 degrees (outside the image circle).
      {"KB wide 1280x800", CameraModel::kannalaBrandt(330, 330, 640, 400, {0.02, -0.01, 0.003, -0.0005}, 1280, 800)},
      // 190 degrees along the diagonal.
      {"KB 190 diagonal", CameraModel::kannalaBrandt(480, 481, 639.5, 479.5, {-0.01, 0.003, -0.0005, 0.00002}, 1280, 960)},
      // A narrow lens with strong coefficients.
      {"KB strong", CameraModel::kannalaBrandt(700, 702, 320.5, 240.5, {0.1, 0.05, -0.02, 0.003}, 640, 480)},
  };
}

/*! Random ray within kFisheyeMaxTestAngle (and the model's range) as a normalised point. */
Eigen::Vector2d randomRay(const CameraModel &cam, std::mt19937 &rng) {
  std::uniform_real_distribution<double> T(0.0, std::min(kFisheyeMaxTestAngle, 0.98 * cam.maxRayAngle()));
  std::uniform_real_distribution<double> P(-M_PI, M_PI);
  const double t = T(rng), p = P(rng);
  return std::tan(t) * Eigen::Vector2d(std::cos(p), std::sin(p));
}

cv::Matx33d cvK(const CameraModel &c) { return cv::Matx33d(c.kx(), 0, c.u0(), 0, c.ky(), c.v0(), 0, 0, 1); }
cv::Vec4d cvD(const CameraModel &c) {
  const auto &k = c.kannalaBrandtCoefficients();
  return cv::Vec4d(k[0], k[1], k[2], k[3]);
}

} // namespace

TEST_CASE("camera: Kannala-Brandt matches cv::fisheye distortPoints / undistortPoints", "[camera][fisheye]") {
  std::mt19937 rng(kSeed + 10);
  for (const auto &nc : fisheyeCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    REQUIRE(cam.distortion() == Distortion::KannalaBrandt);
    std::vector<cv::Point2d> und, px;
    for (int i = 0; i < kRandomPoints; ++i) {
      const Eigen::Vector2d m = randomRay(cam, rng);
      und.emplace_back(m.x(), m.y());
    }
    cv::fisheye::distortPoints(und, px, cvK(cam), cvD(cam));
    std::vector<cv::Point2d> back;
    cv::fisheye::undistortPoints(px, back, cvK(cam), cvD(cam));
    // OpenCV's undistortion is 10 unguarded Newton steps: where it has not converged (its result
    // does not reproject onto the pixel; with the strong lens toward 85 degrees) it is no reference.
    std::vector<cv::Point2d> reproj;
    cv::fisheye::distortPoints(back, reproj, cvK(cam), cvD(cam));
    double worst_px = 0, worst_cv_m = 0;
    int compared = 0;
    for (std::size_t i = 0; i < und.size(); ++i) {
      const Eigen::Vector2d m(und[i].x, und[i].y);
      const Eigen::Vector2d uv = cam.project(m);
      worst_px = std::max(worst_px, (uv - Eigen::Vector2d(px[i].x, px[i].y)).norm());
      Eigen::Vector2d m2;
      REQUIRE(cam.undistort(uv, m2));
      if (std::hypot(reproj[i].x - px[i].x, reproj[i].y - px[i].y) > kOpenCvConvergedPx)
        continue;
      ++compared;
      worst_cv_m = std::max(worst_cv_m, (m2 - Eigen::Vector2d(back[i].x, back[i].y)).norm() / std::max(1.0, m.norm()));
    }
    INFO(compared << " of " << und.size() << " points where OpenCV's undistortion converged");
    CHECK(worst_px < kFisheyeReferenceTolPx);
    CHECK(worst_cv_m < kFisheyeOpenCvUndistortTol);
    CHECK(compared >= static_cast<int>(0.8 * und.size()));
  }
}

TEST_CASE("camera: Kannala-Brandt round trips", "[camera][fisheye]") {
  std::mt19937 rng(kSeed + 11);
  for (const auto &nc : fisheyeCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst_px = 0, worst_m = 0, worst_pix = 0;
    for (int i = 0; i < kRandomPoints; ++i) {
      // Ray -> pixel -> ray.
      const Eigen::Vector2d m = randomRay(cam, rng);
      const Eigen::Vector2d uv = cam.project(m);
      Eigen::Vector2d m2;
      REQUIRE(cam.undistort(uv, m2));
      worst_m = std::max(worst_m, (m2 - m).norm() / std::max(1.0, m.norm()));
      worst_px = std::max(worst_px, (cam.project(m2) - uv).norm());
      Eigen::Vector2d uv_undist;
      REQUIRE(cam.undistortPixel(uv, uv_undist));
      REQUIRE((uv_undist - Eigen::Vector2d(cam.u0() + cam.kx() * m2.x(), cam.v0() + cam.ky() * m2.y())).norm() == 0.0);
      // Pixel of the image -> ray -> pixel, where it has a ray below 90 degrees.
      std::uniform_real_distribution<double> U(-0.5, cam.width() - 0.5), V(-0.5, cam.height() - 0.5);
      const Eigen::Vector2d p(U(rng), V(rng));
      Eigen::Vector2d mp;
      if (cam.undistort(p, mp))
        worst_pix = std::max(worst_pix, (cam.project(mp) - p).norm());
    }
    CHECK(worst_m < kFisheyeNormalisedRelTol);
    CHECK(worst_px < kRoundTripTolPx);
    CHECK(worst_pix < kRoundTripTolPx);
    // The principal point is the axis, exactly; points very near it (the Taylor branch below
    // r = 1e-6 and the closed form above it) round-trip too.
    Eigen::Vector2d m0(1, 1);
    REQUIRE(cam.undistort(Eigen::Vector2d(cam.u0(), cam.v0()), m0));
    CHECK(m0.norm() == 0.0);
    // (Near the centre a pixel's rounding, 6e-14 px, is a large part of the radius: the check is
    // in normalised units, on distortNormalized() against theta_d(atan r) / r in long double.)
    const auto &k = cam.kannalaBrandtCoefficients();
    for (const double r : {1e-300, 1e-12, 9.9e-7, 1e-6, 1.01e-6, 1e-4}) {
      const Eigen::Vector2d m(0.6 * r, -0.8 * r);
      const long double t = std::atan(static_cast<long double>(r)), t2 = t * t;
      const long double s = t * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) / static_cast<long double>(r);
      const Eigen::Vector2d d = cam.distortNormalized(m);
      CHECK(std::abs(static_cast<long double>(d.x()) / static_cast<long double>(m.x()) - s) < kFisheyeNormalisedRelTol);
      Eigen::Vector2d m2;
      REQUIRE(cam.undistort(cam.project(m), m2));
      CHECK((m2 - m).norm() < kNormalisedTol);
    }
  }
}

TEST_CASE("camera: Kannala-Brandt Jacobians match central differences", "[camera][fisheye]") {
  std::mt19937 rng(kSeed + 12);
  for (const auto &nc : fisheyeCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst_d = 0, worst_u = 0;
    std::vector<Eigen::Vector2d> points;
    for (int i = 0; i < kRandomPoints; ++i)
      points.push_back(randomRay(cam, rng));
    // Around the centre: the Taylor branch, and the closed form just above it.
    for (const double r : {0.0, 3e-7, 1e-6, 2e-6, 1e-5})
      points.emplace_back(0.8 * r, 0.6 * r);
    for (const Eigen::Vector2d &m : points) {
      worst_d = std::max(worst_d, distortJacobianError(cam, m));

      worst_u = std::max(worst_u, undistortJacobianError(cam, cam.project(m), kFdStepPixelFisheye));
    }
    CHECK(worst_d < kDistortJacobianTol);
    CHECK(worst_u < kUndistortJacobianTol);
  }
}

TEST_CASE("camera: Kannala-Brandt rays at 90 degrees or beyond do not undistort", "[camera][fisheye]") {
  const CameraModel cam = CameraModel::kannalaBrandt(480, 481, 639.5, 479.5, {-0.01, 0.003, -0.0005, 0.00002}, 1280, 960);
  CHECK(cam.maxRayAngle() == Approx(M_PI / 2).epsilon(1e-15));
  const auto &k = cam.kannalaBrandtCoefficients();
  const auto thetaD = [&](double t) {
    return t * (1 + k[0] * t * t + k[1] * std::pow(t, 4) + k[2] * std::pow(t, 6) + k[3] * std::pow(t, 8));
  };
  // The corners of this 190-degree-diagonal lens are beyond 90 degrees.
  Eigen::Vector2d m;
  CHECK_FALSE(cam.undistort(Eigen::Vector2d(-0.5, -0.5), m));
  CHECK_FALSE(cam.undistort(Eigen::Vector2d(1279.5, 959.5), m));
  // 90 degrees (to the pixel's rounding), and beyond: no normalised point.
  CHECK_FALSE(cam.undistort(Eigen::Vector2d(cam.u0() + cam.kx() * thetaD(M_PI / 2) * (1 + 1e-12), cam.v0()), m));
  CHECK_FALSE(cam.undistort(Eigen::Vector2d(cam.u0() + cam.kx() * thetaD(M_PI / 2 + 1e-3), cam.v0()), m));
  // Just within: a ray at 89.9 degrees.
  const double t = 89.9 * M_PI / 180;
  REQUIRE(cam.undistort(Eigen::Vector2d(cam.u0(), cam.v0() + cam.ky() * thetaD(t)), m));
  CHECK(std::abs(std::atan(m.norm()) - t) < 1e-12);
  CHECK(std::abs(m.x()) < 1e-9 * m.norm());
  vpImagePoint ip(-0.5, -0.5);
  double x = 0, y = 0;
  REQUIRE_THROWS_AS(cam.pixelToMeter(ip, x, y), yawdepth::Error);

  // A fold: theta_d(theta) = theta (1 - 0.5 theta^2) stops increasing at theta = sqrt(2/3).
  const CameraModel fold = CameraModel::kannalaBrandt(300, 300, 320, 240, {-0.5, 0, 0, 0}, 640, 480);
  CHECK(fold.maxRayAngle() == Approx(std::sqrt(2.0 / 3.0)).epsilon(1e-12));
  const double td_max = std::sqrt(2.0 / 3.0) * (1 - 0.5 * 2.0 / 3.0);
  REQUIRE(fold.undistort(Eigen::Vector2d(320 + 300 * 0.99 * td_max, 240), m));
  CHECK(std::atan(m.norm()) < fold.maxRayAngle());
  CHECK_FALSE(fold.undistort(Eigen::Vector2d(320 + 300 * 1.001 * td_max, 240), m));
}

TEST_CASE("camera: Kannala-Brandt parameters are checked", "[camera][fisheye]") {
  CHECK_THROWS_WITH(CameraModel::kannalaBrandt(300, 300, 320, 240, {0.1, 0.2, 0.3}),
                    Catch::Matchers::Contains("3 Kannala-Brandt"));
  CHECK_THROWS_WITH(CameraModel::kannalaBrandt(300, 300, 320, 240, {0.1, 0.2, 0.3, 0.4, 0.5}),
                    Catch::Matchers::Contains("expected 4"));
  CHECK_THROWS_WITH(CameraModel::kannalaBrandt(300, 300, 320, 240, {0.1, std::nan(""), 0.3, 0.4}),
                    Catch::Matchers::Contains("k2"));
  CHECK_THROWS_WITH(CameraModel::kannalaBrandt(-300, 300, 320, 240, {0, 0, 0, 0}), Catch::Matchers::Contains("fx"));
  const CameraModel c = CameraModel::kannalaBrandt(300, 301, 320, 240, {0.1, 0.2, 0.3, 0.4}, 640, 480);
  CHECK(c.kannalaBrandtCoefficients() == std::vector<double>{0.1, 0.2, 0.3, 0.4});
  CHECK(c.brownCoefficients() == std::vector<double>(8, 0.0));
  CHECK(CameraModel::brown(300, 300, 320, 240, {0.1, 0, 0, 0}).kannalaBrandtCoefficients() == std::vector<double>(4, 0.0));
  CHECK(c.parameters().get_projModel() == vpCameraParameters::perspectiveProjWithoutDistortion);
}

TEST_CASE("camera: plausibility of fisheye cameras", "[camera][fisheye]") {
  for (const auto &nc : fisheyeCameras()) {
    INFO(nc.name);
    CHECK_NOTHROW(yawdepth::checkCameraPlausible(nc.cam, nc.name));
  }
  // Over 180 degrees across the width (the corners outside the image circle) is a real lens.
  CHECK_NOTHROW(yawdepth::checkCameraPlausible(
      CameraModel::kannalaBrandt(330, 330, 640, 400, {0.02, -0.01, 0.003, -0.0005}, 1280, 800), "wide"));
  // A fold inside the image is refused; the same lens on a narrow field (all within the fold) is not.
  const auto refused = [](const CameraModel &c, const std::string &needle) {
    try {
      yawdepth::checkCameraPlausible(c, "lens.yaml");
    } catch (const yawdepth::Error &e) {
      const std::string msg = e.what();
      INFO(msg);
      CHECK(msg.find("lens.yaml: implausible camera: ") == 0);
      CHECK(msg.find('\n') == std::string::npos);
      return msg.find(needle) != std::string::npos;
    }
    return false;
  };
  CHECK(refused(CameraModel::kannalaBrandt(300, 300, 320, 240, {-0.5, 0, 0, 0}, 640, 480), "not monotonic"));
  CHECK(refused(CameraModel::kannalaBrandt(300, 300, 320, 240, {-0.5, 0, 0, 0}, 640, 480), "stops increasing at 46.7"));
  CHECK_NOTHROW(yawdepth::checkCameraPlausible(
      CameraModel::kannalaBrandt(2000, 2000, 320, 240, {-0.5, 0, 0, 0}, 640, 480), "narrow"));
  // A lens that squeezes the whole image into a degree is refused by the field rule.
  CHECK(refused(CameraModel::kannalaBrandt(300, 300, 320, 240, {1e4, 0, 0, 0}, 640, 480), "as far from the centre"));
}

// ---------------------------------------------------------------------------------------------
// ROS camera_info and Kalibr camchain files

namespace {

std::string readText(const std::string &path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const std::string &path, const std::string &text) { std::ofstream(path, std::ios::binary) << text; }

/*! `text` with the first `from` replaced by `to` (which must be there). */
std::string replaced(std::string text, const std::string &from, const std::string &to) {
  const std::size_t p = text.find(from);
  REQUIRE(p != std::string::npos);
  return text.replace(p, from.size(), to);
}

void requireSameCamera(const CameraModel &a, const CameraModel &b) {
  REQUIRE(a.kx() == b.kx());
  REQUIRE(a.ky() == b.ky());
  REQUIRE(a.u0() == b.u0());
  REQUIRE(a.v0() == b.v0());
  REQUIRE(a.width() == b.width());
  REQUIRE(a.height() == b.height());
  REQUIRE(a.brownCoefficients() == b.brownCoefficients());
  REQUIRE(a.kannalaBrandtCoefficients() == b.kannalaBrandtCoefficients());
  REQUIRE((a.distortion() == Distortion::KannalaBrandt) == (b.distortion() == Distortion::KannalaBrandt));
}

std::vector<NamedCamera> cameraKinds() {
  vpCameraParameters kud;
  kud.initPersProjWithDistortion(600.0, 602.0, 321.5, 238.25, -0.2, 0.21);
  return {
      {"none", CameraModel::brown(1000.25, 1001.5, 320.125, 240.0625, {}, 640, 480)},
      {"brown4", CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480)},
      {"brown5", CameraModel::brown(900.5, 901.5, 640.25, 360.75, {-0.25, 0.1, 0.001, -0.002, -0.03}, 1280, 720)},
      {"brown8", CameraModel::brown(1100, 1102, 400.5, 300.5, {0.12, -0.05, 0.001, -0.0015, 0.02, 0.3, -0.04, 0.01}, 800, 600)},
      {"visp", CameraModel(kud, 640, 480)},
      {"fisheye", CameraModel::kannalaBrandt(286.18099975585938, 286.3909912109375, 423.6910095214844, 400.1029968261719,
                                             {-0.007315, 0.044596, -0.042005, 0.007709}, 848, 800)},
  };
}

} // namespace

TEST_CASE("camera file: ROS camera_info YAML as ROS writes it", "[camera][file][ros]") {
  // As ROS camera_calibration writes ost.yaml (numpy's layout of the matrices).
  const CameraModel ost = yawdepth::loadCameraFile(kData + "ros_ost_plumb_bob.yaml");
  CHECK(ost.distortion() == Distortion::Brown);
  CHECK(ost.kx() == 505.77957);
  CHECK(ost.ky() == 506.47113);
  CHECK(ost.u0() == 319.70004);
  CHECK(ost.v0() == 229.83474);
  CHECK(ost.width() == 640);
  CHECK(ost.height() == 480);
  CHECK(ost.brownCoefficients() == std::vector<double>{0.090497, -0.189416, -0.003258, 0.001565, 0, 0, 0, 0});
  // The projection matrix (a rectified camera) is not the one used: camera_matrix is.
  CHECK(yawdepth::loadCameraFile(kData + "ros_ost_plumb_bob.yaml", "narrow_stereo").kx() == 505.77957);
  // As camera_info_manager writes it (camera_calibration_parsers' writer: its own output).
  const CameraModel rat = yawdepth::loadCameraFile(kData + "ros_rational_polynomial.yaml");
  CHECK(rat.distortion() == Distortion::Brown);
  CHECK(rat.brownCoefficients() ==
        std::vector<double>{0.5157, -2.659, 0.0002, -0.0002, 1.5279, 0.3929, -2.4934, 1.4574});
  // A fisheye calibration (camera_calibration --camera_model fisheye): equidistant.
  const CameraModel eq = yawdepth::loadCameraFile(kData + "ros_equidistant.yaml");
  CHECK(eq.distortion() == Distortion::KannalaBrandt);
  CHECK(eq.kannalaBrandtCoefficients() == std::vector<double>{0.02, -0.01, 0.003, -0.0005});
  CHECK(eq.width() == 1280);
  CHECK(eq.kx() == 330.12345);
  CHECK(eq.v0() == 399.26511);
}

TEST_CASE("camera file: Kalibr camchain YAML", "[camera][file][kalibr]") {
  const CameraModel c0 = yawdepth::loadCameraFile(kData + "kalibr_camchain.yaml");
  CHECK(c0.distortion() == Distortion::Brown);
  CHECK(c0.kx() == 458.6548807207614);
  CHECK(c0.ky() == 457.2966964634893);
  CHECK(c0.u0() == 367.2158039615726);
  CHECK(c0.v0() == 248.37534060980727);
  CHECK(c0.width() == 752);
  CHECK(c0.height() == 480);
  // radtan k1 k2 r1 r2 is OpenCV's k1 k2 p1 p2.
  CHECK(c0.brownCoefficients() == std::vector<double>{-0.28340811217847, 0.07395907389290132, 0.00019359502856909603,
                                                      1.7618711454538528e-05, 0, 0, 0, 0});
  requireSameCamera(yawdepth::loadCameraFile(kData + "kalibr_camchain.yaml", "cam0"), c0);
  const CameraModel c1 = yawdepth::loadCameraFile(kData + "kalibr_camchain.yaml", "cam1");
  CHECK(c1.distortion() == Distortion::KannalaBrandt);
  CHECK(c1.kannalaBrandtCoefficients() == std::vector<double>{-0.013721808247486035, 0.020727425669427896,
                                                              -0.012786476702685545, 0.0025242267320687625});
  CHECK(c1.kx() == 457.587);
  const CameraModel single = yawdepth::loadCameraFile(kData + "kalibr_single_none.yaml");
  CHECK(single.distortion() == Distortion::None);
  CHECK(single.kx() == 612.5);
  CHECK(single.width() == 640);
}

TEST_CASE("camera file: ROS camera_info round trip", "[camera][file][ros]") {
  const TempDir tmp;
  std::mt19937 rng(kSeed + 13);
  for (const auto &nc : cameraKinds()) {
    INFO(nc.name);
    const std::string path = tmp.file(nc.name + "_ros.yaml");
    yawdepth::saveRosCameraInfoYaml(path, nc.cam, "left_" + nc.name);
    const std::string text = readText(path);
    // ost.yaml's layout, key by key.
    std::size_t at = 0;
    for (const char *key : {"image_width: ", "\nimage_height: ", "\ncamera_name: left_", "\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [",
                            "\ndistortion_model: ", "\ndistortion_coefficients:\n  rows: 1\n  cols: ",
                            "\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1.0, 0.0, 0.0,",
                            "\nprojection_matrix:\n  rows: 3\n  cols: 4\n  data: ["}) {
      const std::size_t p = text.find(key, at);
      INFO(key);
      REQUIRE(p != std::string::npos);
      at = p;
    }
    const std::string model = nc.name == "fisheye" ? "equidistant" : nc.name == "brown8" ? "rational_polynomial" : "plumb_bob";
    CHECK(text.find("distortion_model: " + model + "\n") != std::string::npos);
    const CameraModel c = yawdepth::loadCameraFile(path);
    const CameraModel named = yawdepth::loadCameraFile(path, "left_" + nc.name);
    requireSameCamera(c, nc.cam);
    requireSameCamera(named, nc.cam);
    std::uniform_real_distribution<double> xy(-0.3, 0.3);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector2d m(xy(rng), xy(rng));
      REQUIRE((c.project(m) - nc.cam.project(m)).norm() < kReferenceTolPx);
    }
  }
  // A name that is not a plain YAML word is quoted, and reads back.
  const std::string odd = tmp.file("odd.yaml");
  yawdepth::saveRosCameraInfoYaml(odd, cameraKinds()[1].cam, "my cam: \"left\"");
  CHECK(readText(odd).find("camera_name: \"my cam: \\\"left\\\"\"\n") != std::string::npos);
  CHECK(yawdepth::loadCameraFile(odd, "my cam: \"left\"").kx() == 1734.1);
  CHECK(yawdepth::rosCameraInfoYamlText(cameraKinds()[1].cam, "").find("camera_name: camera\n") != std::string::npos);
  REQUIRE_THROWS_AS(yawdepth::saveRosCameraInfoYaml(tmp.file("no_such_dir/x.yaml"), cameraKinds()[0].cam, "c"),
                    yawdepth::Error);
}

TEST_CASE("camera file: OpenCV YAML of a fisheye camera round-trips", "[camera][file][fisheye]") {
  const TempDir tmp;
  const CameraModel kb = cameraKinds().back().cam;
  REQUIRE(kb.distortion() == Distortion::KannalaBrandt);
  const std::string path = tmp.file("fisheye.yaml");
  yawdepth::saveCameraYaml(path, kb);
  CHECK(readText(path).find("distortion_model: equidistant") != std::string::npos);
  requireSameCamera(yawdepth::loadCameraFile(path), kb);
  // `fisheye` is the same model; plumb_bob and rational_polynomial are the Brown model.
  const std::string text = readText(path);
  writeText(tmp.file("fisheye_word.yaml"), replaced(text, "equidistant", "fisheye"));
  requireSameCamera(yawdepth::loadCameraFile(tmp.file("fisheye_word.yaml")), kb);
  writeText(tmp.file("plumb_bob.yaml"), replaced(text, "equidistant", "plumb_bob"));
  CHECK(yawdepth::loadCameraFile(tmp.file("plumb_bob.yaml")).distortion() == Distortion::Brown);
  writeText(tmp.file("unknown_model.yaml"), replaced(text, "equidistant", "omni"));
  requireRejected(tmp.file("unknown_model.yaml"), "", "distortion_model 'omni' is not supported (known: plumb_bob");
  // The Brown models' OpenCV YAML is as before (no distortion_model key).
  CHECK(yawdepth::cameraYamlText(cameraKinds()[1].cam).find("distortion_model") == std::string::npos);
}

TEST_CASE("camera file: ROS camera_info YAML is read by ROS's own parser", "[camera][file][ros]") {
  // camera_calibration_parsers is the parser camera_info_manager loads calibration files with
  // (Debian: python3-camera-calibration-parsers, the ROS 1 package's Python binding of it).
  const char *python = "/usr/bin/python3";
  if (std::system("/usr/bin/python3 -c 'import camera_calibration_parsers' >/dev/null 2>&1") != 0)
    FAIL("ROS's camera_calibration_parsers is not installed: apt-get install python3-camera-calibration-parsers");
  const TempDir tmp;
  for (const auto &nc : cameraKinds()) {
    INFO(nc.name);
    const std::string path = tmp.file(nc.name + "_for_ros.yaml");
    yawdepth::saveRosCameraInfoYaml(path, nc.cam, "cam_" + nc.name);
    const std::string cmd = std::string(python) +
                            " -c 'import sys, camera_calibration_parsers as p\n"
                            "r = p.readCalibration(sys.argv[1])\n"
                            "n, c = r\n"
                            "print(\"YAWDEPTH\", n, c.width, c.height, c.distortion_model, len(c.D), "
                            "\" \".join(repr(float(v)) for v in list(c.K) + list(c.D) + list(c.R) + list(c.P)))' " +
                            path + " 2>/dev/null";
    FILE *pipe = ::popen(cmd.c_str(), "r");
    REQUIRE(pipe != nullptr);
    std::string out;
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;)
      out.append(buf, n);
    const int status = ::pclose(pipe);
    INFO("ROS parser output: " << out);
    REQUIRE(WIFEXITED(status));
    REQUIRE(WEXITSTATUS(status) == 0);
    const std::size_t at = out.find("YAWDEPTH ");
    REQUIRE(at != std::string::npos);
    std::istringstream in(out.substr(at + 9));
    std::string name, model;
    unsigned w = 0, h = 0;
    std::size_t nd = 0;
    in >> name >> w >> h >> model >> nd;
    std::vector<double> v;
    for (double x; in >> x;)
      v.push_back(x);
    CHECK(name == "cam_" + nc.name);
    CHECK(w == nc.cam.width());
    CHECK(h == nc.cam.height());
    const std::string expected_model =
        nc.name == "fisheye" ? "equidistant" : nc.name == "brown8" ? "rational_polynomial" : "plumb_bob";
    CHECK(model == expected_model);
    REQUIRE(v.size() == 9 + nd + 9 + 12);
    CHECK(v[0] == nc.cam.kx());
    CHECK(v[2] == nc.cam.u0());
    CHECK(v[4] == nc.cam.ky());
    CHECK(v[5] == nc.cam.v0());
    CHECK(v[8] == 1.0);
    const std::vector<double> &k = nc.name == "fisheye" ? nc.cam.kannalaBrandtCoefficients() : nc.cam.brownCoefficients();
    for (std::size_t i = 0; i < nd; ++i)
      CHECK(v[9 + i] == k[i]);
    CHECK(v[9 + nd] == 1.0); // R = I
    CHECK(v[9 + nd + 9] == nc.cam.kx()); // P = [K | 0]
    CHECK(v[9 + nd + 9 + 3] == 0.0);
  }
}

TEST_CASE("camera file: bad ROS camera_info and Kalibr files are refused naming the key", "[camera][file][ros][kalibr]") {
  const TempDir tmp;
  const std::string ros = readText(kData + "ros_ost_plumb_bob.yaml");
  const std::string fish = readText(kData + "ros_equidistant.yaml");
  const std::string kalibr = readText(kData + "kalibr_camchain.yaml");
  const auto file = [&](const std::string &name, const std::string &text) {
    const std::string path = tmp.file(name);
    writeText(path, text);
    return path;
  };
  // Missing keys.
  requireRejected(file("no_d.yaml", replaced(ros, "distortion_coefficients:", "distortion_coefficients_:")), "",
                  "missing distortion_coefficients");
  requireRejected(file("no_w.yaml", replaced(ros, "image_width:", "width:")), "", "missing image_width");
  requireRejected(file("no_data.yaml", replaced(ros, "  data: [505.77957", "  dat: [505.77957")), "",
                  "camera_matrix has no data");
  requireRejected(file("no_k.yaml", replaced(ros, "camera_matrix:", "cam_matrix:")), "", "missing camera_matrix");
  // Wrong sizes.
  requireRejected(file("k_3x4.yaml", replaced(ros, "  rows: 3\n  cols: 3\n  data: [505", "  rows: 3\n  cols: 4\n  data: [505")), "",
                  "camera_matrix is 3x4; expected 3x3");
  requireRejected(file("k_8.yaml", replaced(ros, "  0.     ,   0.     ,   1.     ]\ndistortion_model", "  0.     ,   0.     ]\ndistortion_model")),
                  "", "camera_matrix.data holds 8 numbers");
  requireRejected(file("d_cols.yaml", replaced(ros, "cols: 5", "cols: 4")), "", "distortion_coefficients.data holds 5");
  requireRejected(file("r_2x2.yaml", replaced(ros, "rectification_matrix:\n  rows: 3\n  cols: 3", "rectification_matrix:\n  rows: 2\n  cols: 2")),
                  "", "rectification_matrix is 2x2; expected 3x3");
  requireRejected(file("p_3x3.yaml", replaced(ros, "projection_matrix:\n  rows: 3\n  cols: 4", "projection_matrix:\n  rows: 3\n  cols: 3")),
                  "", "projection_matrix is 3x3; expected 3x4");
  requireRejected(file("k_skew.yaml", replaced(ros, "[505.77957,   0.     ,", "[505.77957,   2.     ,")), "",
                  "camera_matrix has a non-zero skew");
  // Unknown model, wrong coefficient counts.
  requireRejected(file("fov.yaml", replaced(ros, "plumb_bob", "fov")), "",
                  "distortion_model 'fov' is not supported (known: plumb_bob, rational_polynomial, equidistant)");
  requireRejected(file("d_3.yaml", replaced(replaced(ros, "cols: 5", "cols: 3"), ", 0.001565, 0.000000]", "]")), "",
                  "distortion_coefficients holds 3 coefficients for plumb_bob");
  requireRejected(file("eq_5.yaml", replaced(replaced(fish, "cols: 4", "cols: 5"), "-0.000500]", "-0.000500, 0.0]")), "",
                  "distortion_coefficients holds 5 coefficients for equidistant (expected 4");
  // 14 values (OpenCV's thin prism and tilt terms) only when those are zero.
  const std::string d14 = replaced(replaced(ros, "cols: 5", "cols: 14"), "0.000000]", "0.000000, 0, 0, 0, 0, 0, 0, 0, 0, 0]");
  CHECK(yawdepth::loadCameraFile(file("d14.yaml", d14)).brownCoefficients()[0] == 0.090497);
  requireRejected(file("d14_prism.yaml", replaced(d14, "0, 0, 0, 0, 0, 0, 0, 0, 0]", "0, 0, 0, 0.01, 0, 0, 0, 0, 0]")), "",
                  "distortion_coefficients coefficient 9");
  // Non-finite and non-numbers.
  requireRejected(file("k_nan.yaml", replaced(ros, "[505.77957,", "[.nan,")), "", "camera_matrix.data[0] = nan is not finite");
  requireRejected(file("d_inf.yaml", replaced(ros, "[0.090497,", "[.inf,")), "", "distortion_coefficients.data[0] = inf is not finite");
  requireRejected(file("d_text.yaml", replaced(ros, "-0.189416", "abc")), "", "distortion_coefficients.data[1] = 'abc' is not a number");
  requireRejected(file("w_text.yaml", replaced(ros, "image_width: 640", "image_width: wide")), "", "image_width = 'wide' must be an integer");
  requireRejected(file("h_neg.yaml", replaced(ros, "image_height: 480", "image_height: -480")), "", "image_height = -480");
  requireRejected(file("dup.yaml", ros + "image_width: 320\n"), "", "key image_width is given twice");
  // The camera asked for must be the file's.
  requireRejected(kData + "ros_ost_plumb_bob.yaml", "left", "camera_name is 'narrow_stereo', not 'left'");
  // Not YAML at all.
  requireRejected(file("broken.yaml", replaced(ros, "data: [0.090497,", "data: [0.090497,, {")), "", "not valid YAML");

  // Kalibr.
  requireRejected(kData + "kalibr_camchain.yaml", "cam7", "no camera cam7 (cameras: cam0, cam1)");
  requireRejected(file("k_no_cam0.yaml", replaced(kalibr, "cam0:", "cam2:")), "", "no camera cam0 (the default)");
  requireRejected(file("k_omni.yaml", replaced(kalibr, "camera_model: pinhole", "camera_model: omni")), "",
                  "cam0.camera_model 'omni' is not supported (only pinhole");
  requireRejected(file("k_fov.yaml", replaced(kalibr, "distortion_model: radtan", "distortion_model: fov")), "",
                  "cam0.distortion_model 'fov' is not supported (known: radtan, equidistant, none)");
  requireRejected(file("k_d5.yaml", replaced(kalibr, "1.7618711454538528e-05]", "1.7618711454538528e-05, 0.1]")), "",
                  "cam0.distortion_coeffs holds 5 coefficients for radtan (expected 4: k1 k2 r1 r2)");
  requireRejected(file("k_in3.yaml", replaced(kalibr, ", 248.37534060980727]", "]")), "", "cam0.intrinsics holds 3 numbers");
  requireRejected(file("k_no_res.yaml", replaced(kalibr, "  resolution: [752, 480]\n  rostopic: /cam0", "  rostopic: /cam0")), "",
                  "missing cam0.resolution");
  requireRejected(file("k_res.yaml", replaced(kalibr, "resolution: [752, 480]", "resolution: [752]")), "",
                  "cam0.resolution must be [width, height]");
  requireRejected(file("k_nan.yaml", replaced(kalibr, "[458.6548807207614,", "[.nan,")), "", "cam0.intrinsics[0] = nan is not finite");
  requireRejected(file("k_fx.yaml", replaced(kalibr, "[458.6548807207614,", "[-458.6548807207614,")), "", "cam0: focal length fx");
  requireRejected(file("k_cam1_d.yaml", replaced(kalibr, "distortion_coeffs: [-0.013721808247486035,", "distortion_coeffs: [")), "cam1",
                  "cam1.distortion_coeffs holds 3 coefficients for equidistant");
  // A fisheye whose theta_d folds inside the image.
  requireRejected(file("fold.yaml", replaced(fish, "[0.020000, -0.010000, 0.003000, -0.000500]", "[-0.5, 0, 0, 0]")), "",
                  "implausible camera: the fisheye distortion is not monotonic");
}
