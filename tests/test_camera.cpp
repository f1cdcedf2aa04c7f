// Tests of the camera module: distortion models, exact undistortion, camera files.
#include <catch2/catch.hpp>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
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

TEST_CASE("camera: distortNormalized Jacobian matches central differences", "[camera]") {
  std::mt19937 rng(kSeed + 1);
  for (const auto &nc : distortedCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst = 0;
    for (int i = 0; i < kRandomPoints; ++i) {
      const Eigen::Vector2d m = randomNormalised(cam, rng);
      Eigen::Matrix2d J;
      const Eigen::Vector2d d = cam.distortNormalized(m, &J);
      REQUIRE((d - cam.distortNormalized(m)).norm() == 0.0);
      Eigen::Matrix2d Jfd;
      for (int k = 0; k < 2; ++k) {
        Eigen::Vector2d h = Eigen::Vector2d::Zero();
        h[k] = kFdStepNormalised;
        Jfd.col(k) = (cam.distortNormalized(m + h) - cam.distortNormalized(m - h)) / (2 * kFdStepNormalised);
      }
      worst = std::max(worst, (J - Jfd).cwiseAbs().maxCoeff() / std::max(1.0, J.cwiseAbs().maxCoeff()));
    }
    CHECK(worst < kDistortJacobianTol);
  }
}

TEST_CASE("camera: undistort Jacobian matches central differences", "[camera]") {
  std::mt19937 rng(kSeed + 2);
  for (const auto &nc : distortedCameras()) {
    INFO(nc.name);
    const CameraModel &cam = nc.cam;
    double worst = 0;
    for (int i = 0; i < kRandomPoints; ++i) {
      const Eigen::Vector2d uv = cam.project(randomNormalised(cam, rng));
      Eigen::Vector2d m;
      Eigen::Matrix2d J;
      REQUIRE(cam.undistort(uv, m, &J));
      Eigen::Matrix2d Jfd;
      for (int k = 0; k < 2; ++k) {
        Eigen::Vector2d h = Eigen::Vector2d::Zero();
        h[k] = kFdStepPixel;
        Eigen::Vector2d mp, mm;
        REQUIRE(cam.undistort(uv + h, mp));
        REQUIRE(cam.undistort(uv - h, mm));
        Jfd.col(k) = (mp - mm) / (2 * kFdStepPixel);
      }
      worst = std::max(worst, (J - Jfd).cwiseAbs().maxCoeff() / J.cwiseAbs().maxCoeff());
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
