// `calibration`: camera calibration (OpenCV Brown model, ViSP's two models) and yaw-rig calibration
// on images rendered with known truth (renderBoard: exact through the camera's distortion, blur,
// noise); rejection of bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>
#include <map>
#include <unistd.h>
#include <opencv2/calib3d.hpp>
#include <yawdepth/calibration/camera_calibration.h>
#include <yawdepth/calibration/hand_eye.h>
#include <yawdepth/calibration/rig_calibration.h>
#include <yawdepth/calibration/time_offset.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/io/files.h>
#include <yawdepth/io/recording.h>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <yawdepth/render/renderer.h>

using namespace yawdepth;

namespace {

constexpr double kDeg = M_PI / 180.0;

CameraModel paperCamera()
{
  return CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
}
/*! A wide camera (74 deg across) with barrel distortion, for the rig: the board stays in view over +-25 deg. */
CameraModel wideCamera()
{
  return CameraModel::brown(420.0, 421.0, 322.0, 238.5, {-0.25, 0.07, 0.0004, -0.0002}, 640, 480);
}

BoardLayout chessboard(int cols, int rows, double square)
{
  BoardLayout b;
  b.pattern.kind = PatternSpec::Kind::Chessboard;
  b.pattern.cols = cols;
  b.pattern.rows = rows;
  b.pattern.square = square;
  return b;
}

RenderOptions renderOptions(std::uint64_t seed)
{
  RenderOptions o;
  o.blur_sigma_px = 0.7;
  o.noise_sigma = 2.0;
  o.seed = seed;
  return o;
}

/*! Render the board at pose cMb (camera frame): identity rig and motion sample, so wMc = I. */
cv::Mat renderAt(const CameraModel &camera, const BoardLayout &board, const Eigen::Isometry3d &cMb, std::uint64_t seed)
{
  return renderBoard(camera, YawRig(), MotionSample(), board, cMb, renderOptions(seed));
}

/*! True when the board's squares (corners +- one square) all project inside the image with a margin. */
bool boardInside(const CameraModel &camera, const BoardLayout &board, const Eigen::Isometry3d &cMb, double margin)
{
  const double s = board.pattern.square;
  const double xs[2] = {-s, board.pattern.cols * s}, ys[2] = {-s, board.pattern.rows * s};
  for (int k = 0; k <= 20; ++k)
    for (int e = 0; e < 4; ++e) {
      const double t = k / 20.0;
      Eigen::Vector3d P;
      if (e == 0)
        P = {xs[0] + t * (xs[1] - xs[0]), ys[0], 0};
      else if (e == 1)
        P = {xs[0] + t * (xs[1] - xs[0]), ys[1], 0};
      else if (e == 2)
        P = {xs[0], ys[0] + t * (ys[1] - ys[0]), 0};
      else
        P = {xs[1], ys[0] + t * (ys[1] - ys[0]), 0};
      const Eigen::Vector3d c = cMb * P;
      if (c.z() <= 0.05)
        return false;
      const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(c.x() / c.z(), c.y() / c.z()));
      if (uv.x() < margin || uv.y() < margin || uv.x() > camera.width() - 1 - margin ||
          uv.y() > camera.height() - 1 - margin)
        return false;
    }
  return true;
}

/*! A random calibration view: tilt in [tmin, tmax] about a random in-plane axis, anywhere in the image. */
Eigen::Isometry3d randomView(std::mt19937_64 &rng, const CameraModel &camera, const BoardLayout &board, double tmin,
                             double tmax, double zmin, double zmax)
{
  std::uniform_real_distribution<double> U(0, 1);
  const Eigen::Vector3d centre(0.5 * (board.pattern.cols - 1) * board.pattern.square,
                               0.5 * (board.pattern.rows - 1) * board.pattern.square, 0);
  for (int attempt = 0; attempt < 5000; ++attempt) {
    const double phi = 2 * M_PI * U(rng), tilt = tmin + (tmax - tmin) * U(rng);
    const double gamma = (U(rng) - 0.5) * 40 * kDeg;
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    M.linear() = (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(phi), std::sin(phi), 0)) *
                  Eigen::AngleAxisd(gamma, Eigen::Vector3d::UnitZ()))
                     .toRotationMatrix();
    const double Z = zmin + (zmax - zmin) * U(rng);
    const double u = camera.width() * (0.1 + 0.8 * U(rng)), v = camera.height() * (0.1 + 0.8 * U(rng));
    const Eigen::Vector3d P(Z * (u - camera.u0()) / camera.kx(), Z * (v - camera.v0()) / camera.ky(), Z);
    M.translation() = P - M.linear() * centre;
    if (boardInside(camera, board, M, 4))
      return M;
  }
  FAIL("no random view found");
  return Eigen::Isometry3d::Identity();
}

std::string tempDir(const std::string &tag)
{
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("yawdepth_calib_" + tag + "_" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(dir);
  return dir;
}

/*! Rendered calibration set of the paper camera, shared by the camera tests (rendered once). */
struct CameraSet {
  CameraModel truth = paperCamera();
  BoardLayout board = chessboard(7, 5, 0.015);
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  std::vector<Eigen::Isometry3d> poses;
};
/* The first `n` views of the calibration set (rendering dominates these tests' time). */
CameraSet cameraViews(int n)
{
  CameraSet s;
  std::mt19937_64 rng(7);
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d M = randomView(rng, s.truth, s.board, 20 * kDeg, 45 * kDeg, 0.42, 0.65);
    s.poses.push_back(M);
    s.images.push_back(renderAt(s.truth, s.board, M, 100 + static_cast<std::uint64_t>(i)));
    s.names.push_back("view" + std::to_string(i) + ".png");
  }
  return s;
}

const CameraSet &cameraSet()
{
  static const CameraSet set = cameraViews(14);
  return set;
}

/* The fit's covariance (poses marginalised) against OpenCV's own standard deviations of the same fit. */
void checkCovarianceAgainstOpenCv(const CameraSet &set, const CalibrationDetections &det, const CameraCalibration &cal)
{
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> img;
  const BoardLayout &b = set.board;
  const auto features = b.features();
  const std::map<long, Eigen::Vector3d> pts(features.begin(), features.end());
  for (const auto &v : det.views) {
    obj.emplace_back();
    img.emplace_back();
    for (const auto &f : v.features) {
      const Eigen::Vector3d &P = pts.at(f.id);
      obj.back().emplace_back(static_cast<float>(P.x()), static_cast<float>(P.y()), 0.f);
      img.back().emplace_back(static_cast<float>(f.u), static_cast<float>(f.v));
    }
  }
  cv::Mat K, D, sdi, sde, pve;
  std::vector<cv::Mat> rv, tv;
  cv::calibrateCamera(obj, img, cv::Size(640, 480), K, D, rv, tv, sdi, sde, pve, cv::CALIB_FIX_K3,
                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-15));
  // OpenCV divides the squared residuals (2 per point) by points - parameters, not by
  // 2 points - parameters: its deviations are sqrt(~2) too large by that factor alone.
  double n = 0;
  for (const auto &v : img)
    n += static_cast<double>(v.size());
  const double params = 8 + 6.0 * static_cast<double>(img.size());
  const double opencv_scale = std::sqrt((2 * n - params) / (n - params));
  for (int i = 0; i < 8; ++i) {
    INFO("parameter " << i << ": " << cal.std_devs[static_cast<std::size_t>(i)] << " against OpenCV's " << sdi.at<double>(i));
    CHECK(std::abs(cal.std_devs[static_cast<std::size_t>(i)] * opencv_scale / sdi.at<double>(i) - 1) < 0.01);
  }
}

/* The fitted model `c` maps the truth `t`'s rays to its pixels: the distortion is right (up to the
   small intrinsics error it trades with), over the whole image. */
void checkFittedMapping(const CameraModel &c, const CameraModel &t)
{
  double worst = 0;
  for (int v = 20; v < 480; v += 40)
    for (int u = 20; u < 640; u += 40) {
      Eigen::Vector2d m;
      REQUIRE(t.undistort(Eigen::Vector2d(u, v), m));
      // Compare the shape of the mapping: pixel offsets from the principal point, scaled by focal.
      const Eigen::Vector2d a = c.project(m), b(u, v);
      worst = std::max(worst, (a - b).norm());
    }
  INFO("worst pixel difference of the fitted mapping " << worst);
  CHECK(worst < 1.5);
}

/* ViSP's two models: both fitted, the one with distortion better, both close to the truth `t`. */
void checkVispModels(const CameraCalibration &cal, const CameraModel &t)
{
  REQUIRE(cal.visp_fitted);
  INFO("ViSP without " << cal.visp_without.get_px() << " " << cal.visp_without.get_py() << " rms "
                       << cal.visp_rms_without << "; with " << cal.visp_with.get_px() << " kud "
                       << cal.visp_with.get_kud() << " kdu " << cal.visp_with.get_kdu() << " rms "
                       << cal.visp_rms_with << " kdu rms " << cal.visp_rms_kdu);
  CHECK(cal.visp_with.get_projModel() == vpCameraParameters::perspectiveProjWithDistortion);
  CHECK(cal.visp_rms_with < cal.visp_rms_without);
  CHECK(cal.visp_rms_with < 0.5);
  CHECK(cal.visp_rms_kdu < 1.0);
  CHECK(std::abs(cal.visp_with.get_px() / t.kx() - 1) < 0.01);
  CHECK(std::abs(cal.visp_with.get_u0() - t.u0()) < 3.0);
}

/* Files: OpenCV YAML, ViSP XML with both models, coverage picture; they read back. */
void checkCalibrationFiles(const CameraCalibration &cal, const CalibrationDetections &det)
{
  const CameraModel &c = cal.camera;
  const std::string dir = tempDir("camera");
  saveCameraYaml(dir + "/cam.yaml", cal.camera);
  saveVispCameraXml(dir + "/cam.xml", cal, "MyCam");
  writeCoverageImage(dir + "/cov.png", cal, det.views);
  const CameraModel y = loadCameraFile(dir + "/cam.yaml");
  CHECK(std::abs(y.kx() - c.kx()) < 1e-6);
  const CameraModel x = loadCameraFile(dir + "/cam.xml", "MyCam");
  CHECK(x.distortion() == CameraModel::Distortion::ViSP);
  CHECK(std::abs(x.kx() - cal.visp_with.get_px()) < 1e-3);
  std::ifstream xin(dir + "/cam.xml");
  const std::string xml((std::istreambuf_iterator<char>(xin)), std::istreambuf_iterator<char>());
  CHECK(xml.find("perspectiveProjWithoutDistortion") != std::string::npos);
  CHECK(xml.find("perspectiveProjWithDistortion") != std::string::npos);
  CHECK(xml.find("<kud>") != std::string::npos);
  CHECK(xml.find("<kdu>") != std::string::npos);
  CHECK(xml.find("<image_width>640</image_width>") != std::string::npos);
  CHECK(std::filesystem::file_size(dir + "/cov.png") > 1000);
  CHECK(cal.coverage > 0.5);
  std::filesystem::remove_all(dir);
}

} // namespace

TEST_CASE("calibrate-camera recovers the paper's camera from rendered chessboard views", "[calibration][slow]")
{
  const CameraSet &set = cameraSet();
  const CalibrationDetections det = detectCalibrationViews(set.board, set.names, set.images);
  REQUIRE(det.views.size() == set.images.size());
  REQUIRE(det.width == 640);
  REQUIRE(det.height == 480);

  const CameraCalibration cal = calibrateCamera(set.board, det.views, det.width, det.height);
  const CameraModel &c = cal.camera;
  const CameraModel &t = set.truth;
  INFO("fx " << c.kx() << " fy " << c.ky() << " u0 " << c.u0() << " v0 " << c.v0() << " k1 "
             << c.brownCoefficients()[0] << " k2 " << c.brownCoefficients()[1] << " rms " << cal.rms_px);
  // docs/calibration.md ("The camera") quotes these: fx, fy within 0.04 %, the principal point within
  // 0.36 px, RMS 0.013 px. Measured (Release, seeded): fx +0.0384 %, fy +0.0332 %, u0 -0.354 px,
  // v0 +0.079 px, RMS 0.01337 px; the bounds sit just above.
  constexpr double kFocalTol = 0.0005;  // relative (0.05 %)
  constexpr double kCentreTolPx = 0.45;
  constexpr double kRmsTolPx = 0.017;
  CHECK(std::abs(c.kx() / t.kx() - 1) < kFocalTol);
  CHECK(std::abs(c.ky() / t.ky() - 1) < kFocalTol);
  CHECK(std::abs(c.u0() - t.u0()) < kCentreTolPx);
  CHECK(std::abs(c.v0() - t.v0()) < kCentreTolPx);
  CHECK(cal.rms_px < kRmsTolPx);
  CHECK(cal.views_used == 14);
  CHECK(cal.std_devs.size() == 12);
  CHECK(cal.std_devs[0] > 0);
  // The truth has k1 k2 p1 p2: the held-out comparison keeps the 4-coefficient model.
  REQUIRE(cal.models.size() == 3);
  INFO(cal.model_reason);
  CHECK(cal.models[0].chosen);
  CHECK(cal.std_devs[8] == 0); // k3 fixed
  for (const auto &m : cal.models) {
    CHECK(m.heldout_rms_px > 0);
    CHECK(m.heldout_rms_px >= 0.9 * m.rms_px); // left-out views are not fitted better than fitted ones
  }
  // The covariance (poses marginalised) against OpenCV's own standard deviations of the same fit.
  checkCovarianceAgainstOpenCv(set, det, cal);
  // Projection uncertainty: everywhere finite and positive, small where the corners were.
  REQUIRE(cal.uncertainty_grid.size() == 48);
  for (double u : cal.uncertainty_grid) {
    CHECK(std::isfinite(u));
    CHECK(u > 0);
  }
  CHECK(projectionUncertainty(cal, 320, 240) < 0.05);
  for (const auto &v : cal.views) {
    CHECK_FALSE(v.outlier);
    CHECK(v.tilt > 15 * kDeg);
  }
  // The fitted model maps the true rays to the true pixels, over the whole image.
  checkFittedMapping(c, t);

  // ViSP's two models: both fitted, the one with distortion better, both close to the truth.
  checkVispModels(cal, t);

  // Files: OpenCV YAML, ViSP XML with both models, coverage picture; they read back.
  checkCalibrationFiles(cal, det);
}

namespace {

/* Board corners projected through `camera` at seeded random poses, with Gaussian pixel noise
   (sigma `noise_px`): the board tilted 20 to 50 degrees, its centre at a distance of zmin..zmax
   on the ray of a random pixel, wholly inside the image. */
std::vector<CalibrationView> projectedViews(const CameraModel &camera, const BoardLayout &board, int n, double zmin,
                                            double zmax, double noise_px, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, noise_px);
  std::vector<CalibrationView> views;
  std::uniform_real_distribution<double> U(0, 1);
  const Eigen::Vector3d centre(0.5 * (board.pattern.cols - 1) * board.pattern.square,
                               0.5 * (board.pattern.rows - 1) * board.pattern.square, 0);
  for (int i = 0; i < n; ++i) {
    // The board's centre on the ray of a random pixel (through the lens: a fisheye's edges too).
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    bool found = false;
    for (int attempt = 0; attempt < 5000 && !found; ++attempt) {
      const double phi = 2 * M_PI * U(rng), tilt = (20 + 30 * U(rng)) * kDeg, gamma = (U(rng) - 0.5) * 40 * kDeg;
      M.linear() = (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(phi), std::sin(phi), 0)) *
                    Eigen::AngleAxisd(gamma, Eigen::Vector3d::UnitZ()))
                       .toRotationMatrix();
      Eigen::Vector2d m;
      if (!camera.undistort(Eigen::Vector2d(camera.width() * (0.05 + 0.9 * U(rng)),
                                            camera.height() * (0.05 + 0.9 * U(rng))), m))
        continue;
      const Eigen::Vector3d ray = Eigen::Vector3d(m.x(), m.y(), 1).normalized();
      M.translation() = (zmin + (zmax - zmin) * U(rng)) * ray - M.linear() * centre;
      found = boardInside(camera, board, M, 4);
    }
    REQUIRE(found);
    CalibrationView v;
    v.name = "view" + std::to_string(i);
    for (const auto &f : board.features()) {
      const Eigen::Vector3d c = M * f.second;
      const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(c.x() / c.z(), c.y() / c.z()));
      v.features.push_back({f.first, uv.x() + noise(rng), uv.y() + noise(rng)});
    }
    views.push_back(v);
  }
  return views;
}

/* A wide fisheye lens (Kannala-Brandt, about 150 degrees across the diagonal of 640 x 480). */
CameraModel fisheyeCamera()
{
  return CameraModel::kannalaBrandt(300.0, 301.0, 321.5, 238.0, {-0.012, 0.004, -0.0015, 0.0002}, 640, 480);
}

} // namespace

TEST_CASE("calibrate-camera --distortion fisheye and auto+fisheye recover a Kannala-Brandt lens", "[calibration][fisheye]")
{
  const CameraModel truth = fisheyeCamera();
  const BoardLayout board = chessboard(9, 6, 0.03);
  constexpr double kNoisePx = 0.2;
  // 24 views: with 16, the fit's k1..k4 were left free enough beyond the corners seen that a build's
  // rounding (clang Debug against gcc Release) decided whether they fold inside the image.
  const std::vector<CalibrationView> views = projectedViews(truth, board, 24, 0.18, 0.45, kNoisePx, 31);
  double seen_angle = 0; // the largest angle from the optical axis of a corner the views saw (rad)
  for (const CalibrationView &v : views)
    for (const auto &f : v.features) {
      Eigen::Vector2d m;
      if (truth.undistort(Eigen::Vector2d(f.u, f.v), m))
        seen_angle = std::max(seen_angle, std::atan(m.norm()));
    }
  // Measured (Release, seeded): fx +0.19 % (1.6 sigma), fy +0.18 %, u0 -0.40 px, v0 +0.16 px, RMS
  // 0.277 px (the noise's 0.283 per point), k1..k4 within 0.022 of the truth, the fitted mapping
  // within 0.67 px of the true one over the image (its corners, beyond the board's reach); the
  // bounds sit above.
  constexpr double kFocalTol = 0.004;   // relative
  constexpr double kCentreTolPx = 1.0;
  constexpr double kCoefficientTol = 0.03; // k1..k4 trade with each other and with the focal length
  constexpr double kMappingTolPx = 1.0; // fitted against true pixel of the same ray, over the image
  constexpr double kSigmas = 4;         // the focal length's error against its standard deviation
  for (const bool automatic : {false, true}) {
    INFO((automatic ? "auto+fisheye" : "fisheye"));
    CameraCalibrationOptions o;
    o.distortion = automatic ? CameraCalibrationOptions::Distortion::Auto : CameraCalibrationOptions::Distortion::Fisheye;
    o.try_fisheye = automatic;
    o.fit_visp = false;
    const CameraCalibration cal = calibrateCamera(board, views, 640, 480, o);
    const CameraModel &c = cal.camera;
    INFO(cal.model_reason);
    REQUIRE(c.distortion() == CameraModel::Distortion::KannalaBrandt);
    INFO("fx " << c.kx() << " fy " << c.ky() << " u0 " << c.u0() << " v0 " << c.v0() << " rms " << cal.rms_px
               << " sigma fx " << cal.std_devs[0] << " u0 " << cal.std_devs[2] << " k " << c.kannalaBrandtCoefficients()[0]
               << " " << c.kannalaBrandtCoefficients()[1] << " " << c.kannalaBrandtCoefficients()[2] << " "
               << c.kannalaBrandtCoefficients()[3]);
    CHECK(std::abs(c.kx() - truth.kx()) < kSigmas * cal.std_devs[0]);
    CHECK(std::abs(c.kx() / truth.kx() - 1) < kFocalTol);
    CHECK(std::abs(c.ky() / truth.ky() - 1) < kFocalTol);
    CHECK(std::abs(c.u0() - truth.u0()) < kCentreTolPx);
    CHECK(std::abs(c.v0() - truth.v0()) < kCentreTolPx);
    for (std::size_t i = 0; i < 4; ++i)
      CHECK(std::abs(c.kannalaBrandtCoefficients()[i] - truth.kannalaBrandtCoefficients()[i]) < kCoefficientTol);
    CHECK(cal.rms_px < 1.5 * kNoisePx);
    CHECK(cal.std_devs[0] > 0);
    CHECK(cal.std_devs[8] == 0);
    REQUIRE(cal.uncertainty_grid.size() == 48);
    CHECK(std::isfinite(projectionUncertainty(cal, 320, 240)));
    // Over the rays the views saw (beyond them, a polynomial's extrapolation is the plausibility
    // rule's to judge, not a tolerance's).
    double worst = 0;
    for (int v = 40; v < 480; v += 40)
      for (int u = 40; u < 640; u += 40) {
        Eigen::Vector2d m;
        REQUIRE(truth.undistort(Eigen::Vector2d(u, v), m));
        if (std::atan(m.norm()) <= seen_angle)
          worst = std::max(worst, (c.project(m) - Eigen::Vector2d(u, v)).norm());
      }
    INFO("worst mapping error " << worst << " px; uncertainty at the centre " << projectionUncertainty(cal, 320, 240));
    CHECK(worst < kMappingTolPx);
    if (automatic) {
      // Every Brown model against it, on views left out: the fisheye's error is the noise's.
      REQUIRE(cal.models.size() == 4);
      CHECK(cal.models[3].fisheye);
      CHECK(cal.models[3].chosen);
      CHECK(cal.models[3].heldout_rms_px < 1.5 * kNoisePx);
      for (std::size_t i = 0; i < 3; ++i)
        CHECK((!cal.models[i].inadmissible.empty() || cal.models[i].score_px > cal.models[3].score_px));
    } else {
      REQUIRE(cal.models.size() == 1);
      CHECK(cal.models[0].fisheye);
    }
  }
  CameraCalibrationOptions aspect;
  aspect.distortion = CameraCalibrationOptions::Distortion::Fisheye;
  aspect.fix_aspect_ratio = true;
  CHECK_THROWS_AS(calibrateCamera(board, views, 640, 480, aspect), Error);
}

TEST_CASE("calibrate-camera auto+fisheye keeps a Brown model for a narrow lens, auto never tries fisheye", "[calibration][fisheye]")
{
  const CameraModel truth = wideCamera(); // 74 degrees across, barrel distortion: not a fisheye
  const BoardLayout board = chessboard(9, 6, 0.03);
  const std::vector<CalibrationView> views = projectedViews(truth, board, 14, 0.4, 0.8, 0.2, 32);
  CameraCalibrationOptions o;
  o.fit_visp = false;
  const CameraCalibration plain = calibrateCamera(board, views, 640, 480, o);
  CHECK(plain.models.size() == 3);
  for (const auto &m : plain.models)
    CHECK_FALSE(m.fisheye);
  o.try_fisheye = true;
  const CameraCalibration cal = calibrateCamera(board, views, 640, 480, o);
  INFO(cal.model_reason);
  REQUIRE(cal.models.size() == 4);
  CHECK(cal.models[3].fisheye);
  CHECK_FALSE(cal.models[3].chosen);
  CHECK(cal.camera.distortion() == CameraModel::Distortion::Brown);
  CHECK(cal.camera.kx() == Approx(plain.camera.kx()).epsilon(1e-12)); // the same Brown fit as auto's
}

TEST_CASE("calibrate-camera options: fixed aspect ratio and principal point", "[calibration][slow]")
{
  const CameraSet &set = cameraSet();
  const CalibrationDetections det = detectCalibrationViews(set.board, set.names, set.images);
  CameraCalibrationOptions o;
  o.fix_aspect_ratio = true;
  o.fix_principal_point = true;
  o.fit_visp = false;
  o.distortion = CameraCalibrationOptions::Distortion::K4; // the model's choice is tested above
  const CameraCalibration cal = calibrateCamera(set.board, det.views, det.width, det.height, o);
  CHECK(cal.camera.kx() == Approx(cal.camera.ky()).epsilon(1e-12));
  CHECK(cal.camera.u0() == Approx(319.5).margin(1e-9));
  CHECK(cal.camera.v0() == Approx(239.5).margin(1e-9));
  CHECK(std::abs(cal.camera.kx() / set.truth.kx() - 1) < 0.01);
  CHECK(cal.std_devs[2] == 0);
  CHECK_FALSE(cal.visp_fitted);
}

TEST_CASE("calibrate-camera flags and drops an outlier view", "[calibration][slow]")
{
  const CameraSet &set = cameraSet();
  CalibrationDetections det = detectCalibrationViews(set.board, set.names, set.images);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> N(0, 3.0);
  for (auto &f : det.views[4].features) {
    f.u += N(rng);
    f.v += N(rng);
  }
  CameraCalibrationOptions o;
  o.fit_visp = false;
  o.distortion = CameraCalibrationOptions::Distortion::K4; // the model's choice is tested above
  const CameraCalibration flagged = calibrateCamera(set.board, det.views, det.width, det.height, o);
  CHECK(flagged.views[4].outlier);
  CHECK(flagged.views[4].used);
  int n_outliers = 0;
  for (const auto &v : flagged.views)
    n_outliers += v.outlier ? 1 : 0;
  CHECK(n_outliers == 1);
  o.drop_outliers = true;
  const CameraCalibration dropped = calibrateCamera(set.board, det.views, det.width, det.height, o);
  CHECK_FALSE(dropped.views[4].used);
  CHECK(dropped.views_used == 13);
  CHECK(dropped.rms_px < 0.08);
  CHECK(std::abs(dropped.camera.kx() / set.truth.kx() - 1) < 0.005);
}

TEST_CASE("calibrate-camera rejects bad input with reasons", "[calibration]")
{
  const CameraSet set = cameraViews(2);

  SECTION("too few views")
  {
    const std::vector<cv::Mat> images(set.images.begin(), set.images.begin() + 2);
    const std::vector<std::string> names(set.names.begin(), set.names.begin() + 2);
    const CalibrationDetections det = detectCalibrationViews(set.board, names, images);
    REQUIRE(det.views.size() == 2);
    const std::vector<CalibrationView> two(det.views.begin(), det.views.begin() + 2);
    CHECK_THROWS_WITH(calibrateCamera(set.board, two, 640, 480), Catch::Contains("too few views"));
  }
  SECTION("all views fronto-parallel")
  {
    std::vector<cv::Mat> images;
    std::vector<std::string> names;
    std::mt19937_64 rng(11);
    for (int i = 0; i < 5; ++i) {
      const Eigen::Isometry3d M = randomView(rng, set.truth, set.board, 0.0, 0.3 * kDeg, 0.45, 0.65);
      images.push_back(renderAt(set.truth, set.board, M, 300 + static_cast<std::uint64_t>(i)));
      names.push_back("flat" + std::to_string(i));
    }
    const CalibrationDetections flat = detectCalibrationViews(set.board, names, images);
    REQUIRE(flat.views.size() == 5);
    CHECK_THROWS_WITH(calibrateCamera(set.board, flat.views, 640, 480), Catch::Contains("degenerate views"));
  }
  SECTION("images of different sizes")
  {
    const std::vector<cv::Mat> mixed = {set.images[0], cv::Mat(240, 320, CV_8UC1, cv::Scalar(128))};
    CHECK_THROWS_WITH(detectCalibrationViews(set.board, {"a", "b"}, mixed), Catch::Contains("same resolution"));
  }
}

// Apart from the test above: OpenCV's exhaustive chessboard search, which a failed detection runs
// on every image and every size it tries, takes seconds (tens under the sanitizers).
TEST_CASE("calibrate-camera names the pattern that is there, or says there is none", "[calibration][slow]")
{
  const CameraSet set = cameraViews(2);

  SECTION("wrong pattern size: says so, and names the size that is there")
  {
    const BoardLayout wrong = chessboard(8, 6, 0.015); // squares counted instead of inner corners
    const std::vector<cv::Mat> two(set.images.begin(), set.images.begin() + 2);
    const std::vector<std::string> names(set.names.begin(), set.names.begin() + 2);
    try {
      detectCalibrationViews(wrong, names, two);
      FAIL("no error");
    } catch (const Error &e) {
      const std::string what = e.what();
      INFO(what);
      CHECK(what.find("not found in any of the 2 images") != std::string::npos);
      CHECK(what.find("chessboard:7x5") != std::string::npos);
    }
  }
  SECTION("no pattern at all")
  {
    const std::vector<cv::Mat> blank(2, cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)));
    CHECK_THROWS_WITH(detectCalibrationViews(set.board, {"a", "b"}, blank), Catch::Contains("not found in any"));
  }
}

namespace {

// docs/calibration.md ("The rig: yawdepth calibrate-rig") quotes: on rendered sequences the offset within 0.12 mm
// and the yaw zero within 0.005 degree. Measured on the three scenes below (Release, seeded; board
// square / static at an angle / robot motion): offset x -0.074 / -0.062 / -0.112 mm, z +0.019 /
// +0.035 / +0.046 mm; yaw zero -0.0042 deg / (kept) / -0.0016 deg; axis 0.009 / 0.004 / 0.002 deg;
// RMS 0.031 to 0.032 px. The bounds sit just above.
constexpr double kRigOffsetTol = 0.15e-3; // m, per observable component (x, z)
constexpr double kRigYawZeroTol = 0.007 * kDeg;
constexpr double kRigAxisTol = 0.02 * kDeg;
constexpr double kRigRmsTolPx = 0.05;

struct RigTruth {
  Eigen::Vector3d t0 = Eigen::Vector3d(-0.1503, 0.002, 0.01);
  double yaw_offset = 0.5 * kDeg;
  Eigen::Vector3d axis = Eigen::Vector3d(0.01, 1.0, -0.005).normalized();
};

/*! Render the rig views: robot at `positions` (vision-frame origins, heading 0), the yaw readings at each. */
std::vector<RigView> renderRig(const CameraModel &camera, const BoardLayout &board, const RigTruth &truth,
                               const Eigen::Isometry3d &wMb, const std::vector<Eigen::Vector3d> &positions,
                               const std::vector<double> &readings)
{
  PatternDetector detector(board.pattern);
  detector.setCamera(camera);
  std::vector<RigView> views;
  long frame = 0;
  for (const Eigen::Vector3d &p : positions)
    for (double r : readings) {
      Eigen::Isometry3d wMv = Eigen::Isometry3d::Identity();
      wMv.translation() = p;
      Eigen::Isometry3d vMc = Eigen::Isometry3d::Identity();
      vMc.linear() = Eigen::AngleAxisd(r + truth.yaw_offset, truth.axis).toRotationMatrix();
      vMc.translation() = vMc.linear() * truth.t0;
      const Eigen::Isometry3d cMb = (wMv * vMc).inverse() * wMb;
      REQUIRE(boardInside(camera, board, cMb, 3));
      const cv::Mat img = renderAt(camera, board, cMb, 500 + static_cast<std::uint64_t>(frame));
      const FrameDetection d = detector.detect(img, frame);
      REQUIRE(d.found);
      RigView v;
      v.sample.frame = frame++;
      v.sample.x = p.x();
      v.sample.y = p.y();
      v.sample.z = p.z();
      v.sample.yaw = r;
      v.features = d.features;
      views.push_back(v);
    }
  return views;
}

/*! Board pose: centred in front of the robot at `distance`, turned by `yaw` about the vertical. */
Eigen::Isometry3d boardAhead(const BoardLayout &board, double distance, double yaw, double x = -0.12)
{
  const Eigen::Vector3d centre(0.5 * (board.pattern.cols - 1) * board.pattern.square,
                               0.5 * (board.pattern.rows - 1) * board.pattern.square, 0);
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.linear() = rotY(yaw);
  M.translation() = Eigen::Vector3d(x, 0.0, distance) - M.linear() * centre;
  return M;
}

std::vector<double> yawReadings(double from_deg, double to_deg, int n)
{
  std::vector<double> r;
  for (int i = 0; i < n; ++i)
    r.push_back((from_deg + (to_deg - from_deg) * i / (n - 1)) * kDeg);
  return r;
}

/* The rig calibration scenes: the wide camera, a 6x5 board of 30 mm squares, the true rig. */
struct RigScene {
  const CameraModel camera = wideCamera();
  const BoardLayout board = chessboard(6, 5, 0.03);
  const RigTruth truth{};
  /* The views of a static robot, the board 0.75 m ahead turned by `board_angle`, at `count` yaw
     readings from `from_deg` to `to_deg`. */
  std::vector<RigView> staticViews(double board_angle, double from_deg, double to_deg, int count) const
  {
    return renderRig(camera, board, truth, boardAhead(board, 0.75, board_angle), {Eigen::Vector3d::Zero()},
                     yawReadings(from_deg, to_deg, count));
  }
};

/* What calibrate-rig finds on every scene: the observable offset (x, z), the yaw axis, a small RMS. */
void checkRigGeometry(const RigCalibration &rig, const RigTruth &truth)
{
  CHECK(std::abs(rig.camera_offset.x() - truth.t0.x()) < kRigOffsetTol);
  CHECK(std::abs(rig.camera_offset.z() - truth.t0.z()) < kRigOffsetTol);
  CHECK(std::acos(std::min(1.0, rig.yaw_axis.dot(truth.axis))) < kRigAxisTol);
  CHECK(rig.rms_px < kRigRmsTolPx);
}

} // namespace

TEST_CASE_METHOD(RigScene, "calibrate-rig: offset, axis and yaw zero of a board standing square", "[calibration][rig][slow]")
{
  const std::vector<RigView> views = staticViews(0.0, -25, 25, 9);
  RigCalibrationOptions o;
  o.board_square = true;
  o.initial_offset = Eigen::Vector3d(0, truth.t0.y(), 0); // the unobservable component, as a user would give it
  const RigCalibration rig = calibrateRig(camera, board, views, o);
  INFO("t0 " << rig.camera_offset.transpose() << " +- " << rig.camera_offset_sigma.transpose() << "; yaw offset "
             << rig.yaw_offset / kDeg << " +- " << rig.yaw_offset_sigma / kDeg << " deg; axis "
             << rig.yaw_axis.transpose() << " +- " << rig.yaw_axis_sigma.transpose() << "; rms " << rig.rms_px
             << " px, " << rig.iterations << " iterations");
  CHECK(rig.yaw_zero == YawZeroSource::BoardSquare);
  checkRigGeometry(rig, truth);
  CHECK(rig.camera_offset.y() == truth.t0.y());
  CHECK(std::abs(rig.yaw_offset - truth.yaw_offset) < kRigYawZeroTol);
  // The uncertainties are honest: the errors are within 4 sigma, and the sigmas are small.
  CHECK(std::abs(rig.camera_offset.x() - truth.t0.x()) < 4 * rig.camera_offset_sigma.x() + 1e-5);
  CHECK(std::abs(rig.yaw_offset - truth.yaw_offset) < 4 * rig.yaw_offset_sigma + 1e-5);
  CHECK(rig.camera_offset_sigma.x() > 0);
  CHECK(rig.camera_offset_sigma.x() < 0.001);
  CHECK(rig.camera_offset_sigma.y() == 0);

  // The rig file: what readRigFile() reads, plus the sigmas.
  const std::string dir = tempDir("rig");
  {
    std::ofstream out(dir + "/rig.yaml");
    out << rigCalibrationYaml(rig);
  }
  const RigFile f = readRigFile(dir + "/rig.yaml");
  CHECK((f.camera_offset - rig.camera_offset).norm() < 1e-12);
  CHECK(f.yaw_offset == Approx(rig.yaw_offset).epsilon(1e-12));
  REQUIRE(f.yaw_axis.has_value());
  CHECK((*f.yaw_axis - rig.yaw_axis).norm() < 1e-12);
  std::filesystem::remove_all(dir);
}

TEST_CASE_METHOD(RigScene, "calibrate-rig: static robot, board at an angle: offset found, yaw zero kept", "[calibration][rig]")
{
  const std::vector<RigView> views = staticViews(12 * kDeg, -25, 25, 7);
  const RigCalibration rig = calibrateRig(camera, board, views); // closed-form start, y kept at 0
  INFO("t0 " << rig.camera_offset.transpose() << "; axis " << rig.yaw_axis.transpose());
  CHECK(rig.yaw_zero == YawZeroSource::Fixed);
  CHECK(rig.yaw_offset == 0.0);
  CHECK(rig.yaw_offset_sigma == 0.0);
  checkRigGeometry(rig, truth);
  CHECK(rig.camera_offset.y() == 0.0);
}

TEST_CASE_METHOD(RigScene, "calibrate-rig: the robot's translation gives the yaw zero", "[calibration][rig][slow]")
{
  const std::vector<RigView> views =
      renderRig(camera, board, truth, boardAhead(board, 0.85, -10 * kDeg),
                {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.0, 0, 0.12), Eigen::Vector3d(0.03, 0, 0.24)},
                yawReadings(-20, 20, 5));
  const RigCalibration rig = calibrateRig(camera, board, views);
  INFO("t0 " << rig.camera_offset.transpose() << "; yaw offset " << rig.yaw_offset / kDeg << " +- "
             << rig.yaw_offset_sigma / kDeg << " deg");
  CHECK(rig.yaw_zero == YawZeroSource::RobotMotion);
  checkRigGeometry(rig, truth);
  CHECK(std::abs(rig.yaw_offset - truth.yaw_offset) < kRigYawZeroTol);
}

namespace {

constexpr double kTimeOffsetTol = 0.002; // s: the target for a 30 ms latency

/* A pan sweeping on a static robot, seen at 30 Hz on the camera's clock, the yaw read at 200 Hz on the
   motion clock with a latency: the image stamped t was taken at motion time t + latency. The readings
   carry white noise of 2 % of a 200 Hz step at the sweep's top speed. */
struct PanRecording {
  MotionLog motion;
  std::vector<double> image_times;
  std::vector<std::vector<FeatureObservation>> features;
};

PanRecording panRecording(const RigScene &scene, const std::function<double(double)> &true_yaw, double duration,
                          double latency, std::uint64_t seed)
{
  PanRecording rec;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double noise = 0.02 * 0.4 * 2 * M_PI * 22 * kDeg / 200.0;
  rec.motion.timestamped = true;
  rec.motion.yaw_column = true;
  for (int i = 0; i * 0.005 <= duration + 0.4; ++i) {
    const double t = -0.2 + i * 0.005;
    MotionSample s;
    s.frame = i;
    s.yaw = true_yaw(t) - scene.truth.yaw_offset + noise * unit(rng);
    rec.motion.samples.push_back(s);
    rec.motion.times.push_back(t);
  }
  PatternDetector detector(scene.board.pattern);
  detector.setCamera(scene.camera);
  const Eigen::Isometry3d wMb = boardAhead(scene.board, 0.75, 12 * kDeg);
  for (int k = 0; k / 30.0 <= duration; ++k) {
    const double t = k / 30.0;
    Eigen::Isometry3d vMc = Eigen::Isometry3d::Identity();
    vMc.linear() = Eigen::AngleAxisd(true_yaw(t + latency), scene.truth.axis).toRotationMatrix();
    vMc.translation() = vMc.linear() * scene.truth.t0;
    const Eigen::Isometry3d cMb = vMc.inverse() * wMb;
    const FrameDetection d = detector.detect(renderAt(scene.camera, scene.board, cMb, 900 + static_cast<std::uint64_t>(k)), k);
    REQUIRE(d.found);
    rec.image_times.push_back(t);
    rec.features.push_back(d.features);
  }
  return rec;
}

} // namespace

TEST_CASE_METHOD(RigScene, "calibrate-rig with the time offset: a 30 ms latency within 2 ms, a flat profile refused",
                 "[calibration][rig][slow]")
{
  const double latency = 0.030;
  TimeOffsetSearch search; // -100 .. 100 ms
  SECTION("a pan sweeping back and forth at up to 55 deg/s")
  {
    const PanRecording rec =
        panRecording(*this, [](double t) { return 22 * kDeg * std::sin(2 * M_PI * 0.4 * t); }, 2.5, latency, 7);
    const TimedRigCalibration cal =
        calibrateRigWithTimeOffset(camera, board, rec.motion, rec.image_times, rec.features, RigCalibrationOptions(), search);
    INFO("offset " << cal.time_offset.offset * 1e3 << " +- " << cal.time_offset.sigma * 1e3 << " ms, "
                   << cal.time_offset.evaluations << " fits, " << cal.images_used << " images, rms " << cal.rig.rms_px);
    CHECK(std::abs(cal.time_offset.offset - latency) < kTimeOffsetTol);
    CHECK(std::abs(cal.time_offset.offset - latency) < 4 * cal.time_offset.sigma + 1e-4);
    CHECK(cal.time_offset.sigma > 0);
    CHECK(cal.time_offset.sigma < kTimeOffsetTol);
    CHECK(cal.images_used >= 70);
    // The rig, at the board angle of this scene (not the calibration scenes' tolerances: the pan sweeps here).
    constexpr double kSweepOffsetTol = 0.5e-3;
    CHECK(std::abs(cal.rig.camera_offset.x() - truth.t0.x()) < kSweepOffsetTol);
    CHECK(std::abs(cal.rig.camera_offset.z() - truth.t0.z()) < kSweepOffsetTol);
    CHECK(cal.rig.rms_px < kRigRmsTolPx);
    // Without the offset the same recording fits worse.
    TimeAlignmentOptions none;
    ImageList images;
    images.times = rec.image_times;
    images.paths.assign(rec.image_times.size(), std::string());
    const TimeAlignment a = alignMotionToImages(rec.motion, images, none, "motion", "images");
    std::vector<RigView> views;
    for (std::size_t k = 0; k < a.log.samples.size(); ++k)
      views.push_back({a.log.samples[k], rec.features[static_cast<std::size_t>(a.log.samples[k].frame)]});
    RigCalibrationOptions loose;
    loose.max_rms_px = 1e9;
    CHECK(calibrateRig(camera, board, views, loose).rms_px > 3 * cal.rig.rms_px);
  }
  SECTION("a constant yaw rate cannot tell the offset from the yaw zero")
  {
    const PanRecording rec = panRecording(*this, [](double t) { return -20 * kDeg + 16 * kDeg * t; }, 2.5, latency, 8);
    CHECK_THROWS_WITH(
        calibrateRigWithTimeOffset(camera, board, rec.motion, rec.image_times, rec.features, RigCalibrationOptions(), search),
        Catch::Contains("the motion must change speed"));
  }
  SECTION("the search range must hold the offset")
  {
    TimeOffsetSearch narrow;
    narrow.min = -0.05;
    narrow.max = 0.01;
    const auto parabola = [](double x) {
      ProfileCost c;
      c.sum_squares = 100 + 1e6 * (x - 0.03) * (x - 0.03);
      c.residuals = 1000;
      c.parameters = 10;
      return c;
    };
    CHECK_THROWS_WITH(estimateTimeOffset(parabola, narrow), Catch::Contains("end of the search range"));
    const TimeOffsetEstimate e = estimateTimeOffset(parabola, search);
    CHECK(std::abs(e.offset - 0.03) < 2 * search.tolerance);
    // S'' = 2e6, residual variance 100 / 989: sigma = sqrt(2 * 0.1011 / 2e6).
    CHECK(e.sigma == Approx(std::sqrt(2.0 * (100.0 / 989.0) / 2e6)).epsilon(1e-3));
  }
}

TEST_CASE_METHOD(RigScene, "calibrate-rig rejects too small a yaw spread and too few views", "[calibration][rig]")
{
  const std::vector<RigView> views = staticViews(0.0, -5, 5, 4);
  CHECK_THROWS_WITH(calibrateRig(camera, board, views), Catch::Contains("yaw readings span only 10.0 deg"));
  const std::vector<RigView> two(views.begin(), views.begin() + 2);
  CHECK_THROWS_WITH(calibrateRig(camera, board, two), Catch::Contains("too few views"));
}

TEST_CASE_METHOD(RigScene, "calibrate-rig refuses a failed fit: wrong yaw sign, degrees, shuffled readings", "[calibration][rig]")
{
  const std::vector<RigView> views = staticViews(0.0, -30, 30, 5);
  REQUIRE_NOTHROW(calibrateRig(camera, board, views));
  std::vector<RigView> flipped = views, degrees = views, shuffled = views;
  for (std::size_t i = 0; i < views.size(); ++i) {
    flipped[i].sample.yaw = -views[i].sample.yaw;
    degrees[i].sample.yaw = views[i].sample.yaw / kDeg;
    shuffled[i].sample.yaw = views[(i + 2) % views.size()].sample.yaw;
  }
  for (const auto *bad : {&flipped, &degrees, &shuffled})
    CHECK_THROWS_WITH(calibrateRig(camera, board, *bad), Catch::Contains("calibrate-rig: the fit failed"));
}

// Not run by CTest: writes the rendered calibration images and a rig sequence for trying the
// command line, into $YAWDEPTH_CALIB_DUMP (default /tmp/yawdepth_calib_dump):
//   build/tests/test_calibration "[.dump]"
TEST_CASE("write rendered calibration images for the command line", "[.dump]")
{
  const char *env = std::getenv("YAWDEPTH_CALIB_DUMP");
  const std::string dir = env ? env : "/tmp/yawdepth_calib_dump";
  std::filesystem::create_directories(dir + "/camera");
  std::filesystem::create_directories(dir + "/rig");
  const CameraSet &set = cameraSet();
  for (std::size_t i = 0; i < set.images.size(); ++i)
    REQUIRE(cv::imwrite(dir + "/camera/" + set.names[i], set.images[i]));
  // Rig: the wide camera, static robot, board square, yaw readings -25 .. 25 deg.
  const CameraModel camera = wideCamera();
  saveCameraYaml(dir + "/rig/wide_camera.yaml", camera);
  const BoardLayout board = chessboard(6, 5, 0.03);
  const RigTruth truth{};
  const Eigen::Isometry3d wMb = boardAhead(board, 0.75, 0.0);
  std::ofstream csv(dir + "/rig/motion.csv");
  csv << "frame,x,y,z,heading,yaw,image\n";
  const std::vector<double> readings = yawReadings(-25, 25, 9);
  for (std::size_t i = 0; i < readings.size(); ++i) {
    Eigen::Isometry3d vMc = Eigen::Isometry3d::Identity();
    vMc.linear() = Eigen::AngleAxisd(readings[i] + truth.yaw_offset, truth.axis).toRotationMatrix();
    vMc.translation() = vMc.linear() * truth.t0;
    const cv::Mat img = renderAt(camera, board, vMc.inverse() * wMb, 900 + i);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.png", i);
    REQUIRE(cv::imwrite(dir + "/rig/" + name, img));
    char row[160];
    std::snprintf(row, sizeof row, "%zu,0,0,0,0,%.17g,%s\n", i, readings[i], name);
    csv << row;
  }
}

// ---------------------------------------------------------------------------------------------
// Hand-eye calibration.

namespace {

constexpr double kHandEyePx = 0.3; // corner noise of the synthetic views (px)

/* Synthetic hand-eye views: the hand at poses around the board, corners projected with noise. */
std::vector<HandEyeView> handEyeViews(const CameraModel &camera, const BoardLayout &board, HandEyeSetup setup,
                                      const Eigen::Isometry3d &X, const Eigen::Isometry3d &Y, int n,
                                      std::uint64_t seed, bool single_axis = false, double distance_spread = 0.0,
                                      const BoardLayout *printed = nullptr)
{
  // `printed`: the board as it really is (the corners projected from it), when not `board`.
  const BoardLayout &real = printed != nullptr ? *printed : board;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, kHandEyePx);
  std::vector<HandEyeView> views;
  for (int i = 0; i < n; ++i) {
    // The camera looks at the board centre from 0.5 m, from directions within 30 degrees.
    const Eigen::Vector3d o_centre(0.1, 0.06, 0.0);
    const Eigen::Vector3d dir =
        (Eigen::Vector3d(0, 0, -1) + (single_axis ? Eigen::Vector3d(0.5 * U(rng), 0, 0)
                                                  : Eigen::Vector3d(0.5 * U(rng), 0.5 * U(rng), 0)))
            .normalized();
    // The distance: 0.5 m, or from 0.5 - spread to 0.5 + spread in equal steps over the views.
    const double distance = 0.5 + (n > 1 ? distance_spread * (-1.0 + 2.0 * i / (n - 1)) : 0.0);
    const Eigen::Vector3d c = o_centre + distance * dir;
    const Eigen::Vector3d z = (o_centre - c).normalized();
    Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Isometry3d oMc = Eigen::Isometry3d::Identity();
    oMc.linear() << x, y, z;
    oMc.linear() = oMc.linear() * Eigen::AngleAxisd(single_axis ? 0.0 : 0.4 * U(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    oMc.translation() = c;
    const Eigen::Isometry3d cMo = oMc.inverse();
    // cMo = X^-1 A Y: A = X cMo Y^-1 is eMr (eye-in-hand) or rMe (eye-to-hand).
    const Eigen::Isometry3d A = X * cMo * Y.inverse();
    const Eigen::Isometry3d rMe = setup == HandEyeSetup::EyeInHand ? A.inverse() : A;
    // The kinematics report the hand pose with errors: 1 mm and 0.1 deg per axis (HandEyeOptions).
    std::normal_distribution<double> kin(0.0, 1.0);
    Eigen::Isometry3d err = Eigen::Isometry3d::Identity();
    err.linear() = expSO3<double>(Eigen::Vector3d(kin(rng), kin(rng), kin(rng)) * (0.1 * M_PI / 180));
    err.translation() = 1e-3 * Eigen::Vector3d(kin(rng), kin(rng), kin(rng));
    const Eigen::Isometry3d rMe_measured = rMe * err;
    HandEyeView v;
    v.rMe = toVisp(rMe_measured.linear(), rMe_measured.translation());
    v.name = "view " + std::to_string(i);
    for (const auto &f : real.features()) {
      const Eigen::Vector3d P = cMo * f.second;
      const Eigen::Vector2d uv = camera.project(P.head<2>() / P.z());
      v.features.push_back({f.first, uv.x() + g(rng), uv.y() + g(rng)});
    }
    views.push_back(v);
  }
  return views;
}

Eigen::Isometry3d isoOf(const vpHomogeneousMatrix &M) { return toIsometry(M); }

} // namespace

TEST_CASE("hand-eye: eye-in-hand and eye-to-hand recover the camera pose within its honest sigma", "[calibration][handeye][slow]")
{
  const CameraModel camera =
      CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480);
  const BoardLayout board = chessboard(9, 6, 0.0236);
  for (HandEyeSetup setup : {HandEyeSetup::EyeInHand, HandEyeSetup::EyeToHand}) {
    // X: eMc like the franka's (eye-in-hand), or a camera 1.2 m from the base (eye-to-hand).
    const Eigen::Isometry3d X = isoOf(setup == HandEyeSetup::EyeInHand
                                          ? vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818)
                                          : vpHomogeneousMatrix(1.2, 0.1, 0.5, 1.9, 0.1, -0.4));
    const Eigen::Isometry3d Y = isoOf(setup == HandEyeSetup::EyeInHand
                                          ? vpHomogeneousMatrix(0.536, 0.124, 0.0916, 2.226, -2.214, 0.0207)
                                          : vpHomogeneousMatrix(0.02, -0.01, 0.12, 0.1, 3.0, 0.2));
    double z2 = 0; // normalised squared errors of the camera pose's translation over the seeds
    int count = 0;
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      const std::vector<HandEyeView> views = handEyeViews(camera, board, setup, X, Y, 10, seed);
      HandEyeOptions opt;
      opt.setup = setup;
      const HandEyeCalibration cal = calibrateHandEye(camera, board, views, opt);
      CHECK(cal.views == 10);
      CHECK(cal.points == 540);
      CHECK(cal.rms_px < 1.2 * kHandEyePx); // corner noise; the hand poses take up a little of it
      CHECK(cal.rms_px <= cal.initial_rms_px + 1e-9);
      const Eigen::Isometry3d E = isoOf(cal.camera_pose).inverse() * X;
      const double dt = (isoOf(cal.camera_pose).translation() - X.translation()).norm();
      const double dr = Eigen::AngleAxisd(E.linear()).angle();
      // Noise-scaled: within 4 of the stated sigmas (norms over the three axes).
      CHECK(dt < 4 * cal.camera_pose_sigma.head<3>().norm());
      CHECK(dr < 4 * cal.camera_pose_sigma.tail<3>().norm());
      for (int k = 0; k < 3; ++k) {
        const double e = isoOf(cal.camera_pose).translation()(k) - X.translation()(k);
        REQUIRE(cal.camera_pose_sigma(k) > 0);
        z2 += (e / cal.camera_pose_sigma(k)) * (e / cal.camera_pose_sigma(k));
        ++count;
      }
      // The board pose too.
      CHECK((isoOf(cal.target_pose).translation() - Y.translation()).norm() < 6e-3);
      // The rig file: camera_pose reads back as X (the vision frame is the hand / the base).
      const std::string yaml = handEyeRigYaml(cal);
      CHECK(yaml.find("camera_pose: [") != std::string::npos);
      CHECK(yaml.find("camera_pose_sigma: [") != std::string::npos);
    }
    // Honest sigma: the RMS of error / sigma over 15 coordinates is near 1 (loose: 15 samples).
    const double ratio = std::sqrt(z2 / count);
    INFO("setup " << static_cast<int>(setup) << ": RMS(error / sigma) " << ratio);
    CHECK(ratio > 0.4);
    CHECK(ratio < 2.0);
  }
}

TEST_CASE("hand-eye: refuses too few views, single-axis rotations and poses that do not fit", "[calibration][handeye]")
{
  const CameraModel camera = CameraModel::brown(600, 600, 320, 240, {0, 0, 0, 0}, 640, 480);
  const BoardLayout board = chessboard(9, 6, 0.0236);
  const Eigen::Isometry3d X = isoOf(vpHomogeneousMatrix(0.05, -0.03, -0.04, 0.0, 0.0, 1.57));
  const Eigen::Isometry3d Y = isoOf(vpHomogeneousMatrix(0.5, 0.1, 0.1, 2.2, -2.2, 0.0));
  const auto views = handEyeViews(camera, board, HandEyeSetup::EyeInHand, X, Y, 8, 3);
  const std::vector<HandEyeView> two(views.begin(), views.begin() + 2);
  CHECK_THROWS_WITH(calibrateHandEye(camera, board, two), Catch::Contains("too few views"));
  const auto flat = handEyeViews(camera, board, HandEyeSetup::EyeInHand, X, Y, 8, 3, true);
  CHECK_THROWS_WITH(calibrateHandEye(camera, board, flat), Catch::Contains("single axis"));
  // The robot poses of another run: shuffled between the images.
  std::vector<HandEyeView> shuffled = views;
  for (std::size_t i = 0; i < shuffled.size(); ++i)
    shuffled[i].rMe = views[(i + 3) % views.size()].rMe;
  CHECK_THROWS_WITH(calibrateHandEye(camera, board, shuffled), Catch::Contains("failed"));
  CHECK_THROWS_AS(handEyeSetupFromString("eye-on-hand"), Error);
}

TEST_CASE("hand-eye on the real franka photos: ViSP's published eMc within millimetres", "[calibration][handeye][real]")
{
  // 8 real photos from a Panda arm and its forward kinematics (tests/data/franka-eye-in-hand);
  // the camera calibrated by yawdepth on the same photos (k1 k2 p1 p2, as calibrate-camera chooses).
  const std::string dir = std::string(YAWDEPTH_TEST_DATA_DIR) + "/franka-eye-in-hand/";
  const BoardLayout board = chessboard(9, 6, 0.0236);
  const CameraModel camera =
      CameraModel::brown(601.67, 602.05, 324.41, 239.61, {0.04600, 0.11010, -0.003922, 0.000321}, 640, 480);
  const MotionLog motion = readMotionCsv(dir + "motion.csv");
  REQUIRE(motion.samples.size() == 8);
  std::vector<HandEyeView> views;
  PatternDetector det(board.pattern);
  det.setCamera(camera);
  for (std::size_t i = 0; i < motion.samples.size(); ++i) {
    const FrameDetection d = det.detect(readGrayImage(motion.images[i]), motion.samples[i].frame);
    REQUIRE(d.found);
    views.push_back({wMv(motion.samples[i]), d.features, motion.images[i]});
  }
  const HandEyeCalibration cal = calibrateHandEye(camera, board, views);
  const vpHomogeneousMatrix visp(0.0577148, -0.0339261, -0.0422745, 0.00178253, 0.00917657, 1.58178);
  const Eigen::Isometry3d E = isoOf(cal.camera_pose).inverse() * isoOf(visp);
  const double dt = (isoOf(cal.camera_pose).translation() - isoOf(visp).translation()).norm();
  const double dr = Eigen::AngleAxisd(E.linear()).angle() * 180 / M_PI;
  const Eigen::Isometry3d E0 = isoOf(cal.initial_camera_pose).inverse() * isoOf(visp);
  std::printf("franka hand-eye: eMc %.2f mm and %.3f deg from ViSP's published eMc (start: %.2f mm, %.3f deg); RMS %.3f px "
              "(start %.3f)\n",
              1e3 * dt, dr, 1e3 * (isoOf(cal.initial_camera_pose).translation() - isoOf(visp).translation()).norm(),
              Eigen::AngleAxisd(E0.linear()).angle() * 180 / M_PI, cal.rms_px, cal.initial_rms_px);
  std::printf("  largest hand-pose correction %.2f mm, %.3f deg\n", cal.pose_correction_mm, cal.pose_correction_deg);
  const Eigen::Vector3d sig_t = 1e3 * cal.camera_pose_sigma.head<3>(), sig_r = cal.camera_pose_sigma.tail<3>() * 180 / M_PI;
  std::printf("  stated 1-sigma of eMc: %.2f to %.2f mm, %.3f to %.3f deg\n", sig_t.minCoeff(), sig_t.maxCoeff(),
              sig_r.minCoeff(), sig_r.maxCoeff());
  // docs/arms.md ("Hand-eye calibration") quotes these: eMc within 2.4 mm and 0.41 deg of ViSP's (start 2.0 mm,
  // 0.40 deg), RMS 0.19 px (4.4 px at the start), stated 1-sigma 0.5 to 0.8 mm and 0.05 to 0.09 deg,
  // largest hand-pose correction 5.7 mm and 0.46 deg. Measured: 2.43 mm, 0.405 deg (start 2.02 mm,
  // 0.397 deg), RMS 0.187 px (start 4.435 px), sigmas 0.46 to 0.84 mm and 0.048 to 0.092 deg,
  // correction 5.73 mm and 0.464 deg. The bounds sit just around them.
  constexpr double kEmcTolM = 3e-3, kEmcTolDeg = 0.5, kRmsTolPx = 0.25;
  CHECK(cal.views == 8);
  CHECK(dt < kEmcTolM);
  CHECK(dr < kEmcTolDeg);
  CHECK((isoOf(cal.initial_camera_pose).translation() - isoOf(visp).translation()).norm() < kEmcTolM);
  CHECK(Eigen::AngleAxisd(E0.linear()).angle() * 180 / M_PI < kEmcTolDeg);
  CHECK(cal.rms_px < kRmsTolPx);
  CHECK(cal.initial_rms_px > 3.5);
  CHECK(cal.initial_rms_px < 5.5);
  CHECK(sig_t.minCoeff() > 0.35);
  CHECK(sig_t.maxCoeff() < 1.0);
  CHECK(sig_r.minCoeff() > 0.035);
  CHECK(sig_r.maxCoeff() < 0.11);
  CHECK(cal.pose_correction_mm < 7.0);
  CHECK(cal.pose_correction_deg < 0.6);
  // ViSP's published board pose rMo within a few millimetres too.
  const vpHomogeneousMatrix rMo(0.5364858483, 0.123945742, 0.09155742609, 2.22636085, -2.213916548, 0.02071766945);
  CHECK((isoOf(cal.target_pose).translation() - isoOf(rMo).translation()).norm() < 5e-3);
  // The board scale check on these photos (docs/arms.md, "The board's size"): the hand's motion says the
  // board is 1.137 +- 0.030 times the 23.6 mm printed on the data's sheet, a mismatch it warns about:
  // not resolved (the print unmeasured, or the arm's errors growing with the distance). Pinned here
  // so that a change of it is seen.
  std::printf("  board scale %.4f +- %.4f (%s), distances spread by %.1f mm\n", cal.board_scale.scale,
              cal.board_scale.sigma, toString(cal.board_scale.status), 1e3 * cal.board_scale.distance_spread);
  CHECK(cal.board_scale.scale > 1.10);
  CHECK(cal.board_scale.scale < 1.17);
  CHECK(cal.board_scale.sigma > 0.02);
  CHECK(cal.board_scale.sigma < 0.04);
}

namespace {

// The board scale check (board_scale.h): 25 mm typed for a 23.6 mm print (issue 38: s = 0.944) is
// warned, the right size is not. Measured on the scenes below (10 views from 0.4 to 0.6 m, 0.3 px,
// kinematics 1 mm and 0.1 deg): see the test's INFO.
constexpr double kScaleTol = 0.01; // |s - s_true| allowed: the check's own min_relative
constexpr double kDistanceSpread = 0.15; // the views' distances: 0.35 to 0.65 m (a spread of 96 mm)

} // namespace

TEST_CASE("hand-eye: a wrong square size is warned, the right one is not", "[calibration][handeye][scale]")
{
  const CameraModel camera =
      CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480);
  const BoardLayout printed = chessboard(9, 6, 0.0236), typed = chessboard(9, 6, 0.025);
  const Eigen::Isometry3d X = isoOf(vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818));
  const Eigen::Isometry3d Y = isoOf(vpHomogeneousMatrix(0.536, 0.124, 0.0916, 2.226, -2.214, 0.0207));
  for (std::uint64_t seed = 11; seed <= 14; ++seed) {
    const std::vector<HandEyeView> views =
        handEyeViews(camera, printed, HandEyeSetup::EyeInHand, X, Y, 10, seed, false, kDistanceSpread);
    const HandEyeCalibration right = calibrateHandEye(camera, printed, views);
    const HandEyeCalibration wrong = calibrateHandEye(camera, typed, views);
    INFO("seed " << seed << ": right size s = " << right.board_scale.scale << " +- " << right.board_scale.sigma
                 << ", wrong size s = " << wrong.board_scale.scale << " +- " << wrong.board_scale.sigma << " ("
                 << wrong.board_scale.message << "); RMS " << right.rms_px << " / " << wrong.rms_px << " px");
    CHECK(right.board_scale.status == BoardScaleStatus::Consistent);
    CHECK(right.board_scale.message.empty());
    CHECK(std::abs(right.board_scale.scale - 1.0) < kScaleTol);
    CHECK(wrong.board_scale.status == BoardScaleStatus::Mismatch);
    CHECK(std::abs(wrong.board_scale.scale - 0.0236 / 0.025) < kScaleTol);
    CHECK(wrong.board_scale.message.find("the board looks 0.9") != std::string::npos);
    CHECK(wrong.board_scale.message.find("check the square size") != std::string::npos);
    // The result stays the fit with the size given: the scale is reported, not applied.
    CHECK(wrong.camera_pose_sigma(2) > 0);
    CHECK(handEyeRigYaml(wrong).find("(mismatch)") != std::string::npos);
  }
  // Views from 0.25 to 0.75 m: the hand poses cannot absorb the wrong size, and the fit's refusal says why.
  const std::vector<HandEyeView> far_near = handEyeViews(camera, printed, HandEyeSetup::EyeInHand, X, Y, 10, 11, false, 0.22);
  CHECK_NOTHROW(calibrateHandEye(camera, printed, far_near));
  CHECK_THROWS_WITH(calibrateHandEye(camera, typed, far_near), Catch::Contains("check the square size"));
  // A gross mismatch (the size of the board for its square) is refused.
  BoardScaleOptions o;
  CHECK_THROWS_WITH(checkBoardScale(0.5, 0.01, typed, o), Catch::Contains("refused"));
  CHECK(checkBoardScale(1.004, 0.0005, typed, o).status == BoardScaleStatus::Consistent); // under 1 %: a printer's
  CHECK(checkBoardScale(0.99, 0.01, typed, o).status == BoardScaleStatus::Consistent);    // could see a 4 % error
  // 2.5 sigma is not a mismatch, but views whose 4 sigma exceed 5 % could not have told 25 mm from 23.6.
  const BoardScaleCheck unsure = checkBoardScale(0.95, 0.02, typed, o);
  CHECK(unsure.status == BoardScaleStatus::Unconfirmed);
  CHECK(unsure.message.find("cannot confirm the board's size") != std::string::npos);
  CHECK(unsure.message.find("off by less than 8 %") != std::string::npos);
  CHECK(checkBoardScale(0.95, 0.005, typed, o).status == BoardScaleStatus::Mismatch);
  o.min_relative = 0;
  CHECK_THROWS_AS(checkBoardScale(1.0, 0.01, typed, o), Error);
}

TEST_CASE_METHOD(RigScene, "calibrate-rig: a wrong square size is warned when the robot moved, not seen when static",
                 "[calibration][rig][scale][slow]")
{
  const std::vector<Eigen::Vector3d> positions = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.0, 0, 0.12),
                                                  Eigen::Vector3d(0.03, 0, 0.24)};
  const std::vector<RigView> moving =
      renderRig(camera, board, truth, boardAhead(board, 0.85, -10 * kDeg), positions, yawReadings(-20, 20, 5));
  BoardLayout typed = board; // 30 mm printed, 32 mm typed
  typed.pattern.square = 0.032;
  const RigCalibration right = calibrateRig(camera, board, moving);
  const RigCalibration wrong = calibrateRig(camera, typed, moving);
  INFO("right: s = " << right.board_scale.scale << " +- " << right.board_scale.sigma << "; wrong: s = "
                     << wrong.board_scale.scale << " +- " << wrong.board_scale.sigma << " (" << wrong.board_scale.message
                     << "); RMS " << right.rms_px << " / " << wrong.rms_px);
  CHECK(right.board_scale.status == BoardScaleStatus::Consistent);
  CHECK(std::abs(right.board_scale.scale - 1.0) < kScaleTol);
  CHECK(wrong.board_scale.status == BoardScaleStatus::Mismatch);
  CHECK(std::abs(wrong.board_scale.scale - 0.030 / 0.032) < kScaleTol);
  // A static robot cannot tell: the offset grows with the board, the fit is as good.
  const std::vector<RigView> still = staticViews(12 * kDeg, -25, 25, 7);
  const RigCalibration s_right = calibrateRig(camera, board, still), s_wrong = calibrateRig(camera, typed, still);
  CHECK(s_wrong.board_scale.status == BoardScaleStatus::NotEstimated);
  CHECK(std::abs(s_wrong.camera_offset.x() / s_right.camera_offset.x() - 0.032 / 0.030) < 1e-3);
  CHECK(s_wrong.rms_px < s_right.rms_px + 0.01);
}

namespace {

/* The board in the camera (cMo) for a path sample q = (dir x, dir y, distance, roll): the camera on
   the ray through the board's centre along (dir x, dir y, -1), looking at the centre, rolled by q(3). */
Eigen::Isometry3d cMoOnPath(const BoardLayout &board, const Eigen::Vector4d &q)
{
  const Eigen::Vector3d o_centre(0.5 * (board.pattern.cols - 1) * board.pattern.square,
                                 0.5 * (board.pattern.rows - 1) * board.pattern.square, 0.0);
  const Eigen::Vector3d dir = Eigen::Vector3d(q(0), q(1), -1.0).normalized();
  const Eigen::Vector3d c = o_centre + q(2) * dir;
  const Eigen::Vector3d z = (o_centre - c).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d oMc = Eigen::Isometry3d::Identity();
  oMc.linear() << x, y, z;
  oMc.linear() = oMc.linear() * Eigen::AngleAxisd(q(3), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  oMc.translation() = c;
  return oMc.inverse();
}

/* A camera on an arm moving continuously in front of a fixed board: the camera's direction from
   the board's centre and its distance and roll follow `path(t)` (dir x, dir y, distance, roll);
   the hand's poses logged at 100 Hz on the motion clock with white noise (0.3 mm, 0.03 deg per
   axis), the images at 25 Hz on the camera's clock (at `image_times`), each taken at motion time
   t + latency, its corners projected with 0.3 px noise. */
struct ArmRecording {
  MotionLog motion;
  std::vector<double> image_times;
  std::vector<std::vector<FeatureObservation>> features;
  std::vector<std::string> names;
};

ArmRecording armRecording(const CameraModel &camera, const BoardLayout &board, const Eigen::Isometry3d &X,
                          const Eigen::Isometry3d &Y, const std::function<Eigen::Vector4d(double)> &path,
                          const std::vector<double> &image_times, double duration, double latency, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const auto cMoAt = [&](double t) { return cMoOnPath(board, path(t)); };
  // Eye-in-hand: cMo = X^-1 eMr Y, so rMe = (X cMo Y^-1)^-1.
  const auto rMeAt = [&](double t) { return Eigen::Isometry3d((X * cMoAt(t) * Y.inverse()).inverse()); };
  ArmRecording rec;
  rec.motion.timestamped = true;
  for (int k = 0; k * 0.01 <= duration + 0.4; ++k) {
    const double t = -0.2 + k * 0.01;
    Eigen::Isometry3d err = Eigen::Isometry3d::Identity();
    err.linear() = expSO3<double>(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * (0.03 * kDeg));
    err.translation() = 0.3e-3 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    const Eigen::Isometry3d M = rMeAt(t) * err;
    rec.motion.samples.push_back(MotionSample::fromPose(k, toVisp(M.linear(), M.translation())));
    rec.motion.times.push_back(t);
  }
  std::normal_distribution<double> px(0.0, kHandEyePx);
  for (double t : image_times) {
    const Eigen::Isometry3d cMo = cMoAt(t + latency);
    std::vector<FeatureObservation> f;
    for (const auto &p : board.features()) {
      const Eigen::Vector3d P = cMo * p.second;
      const Eigen::Vector2d uv = camera.project(P.head<2>() / P.z());
      f.push_back({p.first, uv.x() + px(rng), uv.y() + px(rng)});
    }
    rec.image_times.push_back(t);
    rec.features.push_back(f);
    rec.names.push_back("image at " + std::to_string(t) + " s");
  }
  return rec;
}

} // namespace

TEST_CASE("hand-eye with the time offset: a 30 ms latency within 2 ms, a near-static arm refused",
          "[calibration][handeye][slow]")
{
  const CameraModel camera =
      CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480);
  const BoardLayout board = chessboard(9, 6, 0.0236);
  const Eigen::Isometry3d X = isoOf(vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818));
  const Eigen::Isometry3d Y = isoOf(vpHomogeneousMatrix(0.536, 0.124, 0.0916, 2.226, -2.214, 0.0207));
  const double latency = 0.030;
  const TimeOffsetSearch search; // -100 .. 100 ms
  SECTION("an arm moving continuously, changing speed")
  {
    // Up to about 0.35 m/s and 40 deg/s: an arm's brisk calibration motion.
    const auto path = [](double t) {
      return Eigen::Vector4d(0.45 * std::sin(2 * M_PI * 0.35 * t), 0.4 * std::sin(2 * M_PI * 0.5 * t + 1.0),
                             0.5 + 0.08 * std::sin(2 * M_PI * 0.3 * t), 0.35 * std::sin(2 * M_PI * 0.4 * t + 0.5));
    };
    const double duration = 2.0;
    std::vector<double> times;
    for (int k = 0; k / 25.0 <= duration; ++k)
      times.push_back(k / 25.0);
    const ArmRecording rec = armRecording(camera, board, X, Y, path, times, duration, latency, 21);
    const TimedHandEyeCalibration cal = calibrateHandEyeWithTimeOffset(camera, board, rec.motion, rec.image_times,
                                                                       rec.features, rec.names, HandEyeOptions(), search);
    const double dt = (isoOf(cal.hand_eye.camera_pose).translation() - X.translation()).norm();
    INFO("offset " << cal.time_offset.offset * 1e3 << " +- " << cal.time_offset.sigma * 1e3 << " ms, "
                   << cal.time_offset.evaluations << " fits, " << cal.images_used << " images; eMc "
                   << 1e3 * dt << " mm off, RMS " << cal.hand_eye.rms_px << " px");
    CHECK(std::abs(cal.time_offset.offset - latency) < kTimeOffsetTol);
    CHECK(std::abs(cal.time_offset.offset - latency) < 4 * cal.time_offset.sigma + 1e-4);
    CHECK(cal.time_offset.sigma > 0);
    CHECK(cal.time_offset.sigma < kTimeOffsetTol);
    CHECK(cal.images_used == static_cast<int>(times.size()));
    CHECK(dt < 4 * cal.hand_eye.camera_pose_sigma.head<3>().norm());
    CHECK(cal.hand_eye.rms_px < 1.2 * kHandEyePx);
    // The right size: never a mismatch (these views, all at one distance, may not confirm it).
    CHECK(cal.hand_eye.board_scale.status != BoardScaleStatus::Mismatch);
    CHECK(cal.hand_eye.board_scale.status != BoardScaleStatus::NotEstimated);
  }
  SECTION("an arm that stops for each image cannot tell the offset")
  {
    // Eight stations held 0.6 s each, joined by 0.3 s moves; the images in the middle 0.2 s of each
    // hold: at any offset in the range every image's pose is a still arm's.
    const std::vector<Eigen::Vector4d> stations = {{0.3, 0.1, 0.5, 0.0},   {-0.3, 0.2, 0.55, 0.3},
                                                   {0.1, -0.35, 0.45, -0.2}, {-0.2, -0.2, 0.5, 0.1},
                                                   {0.35, 0.3, 0.6, -0.3}, {0.0, 0.4, 0.48, 0.25},
                                                   {-0.4, 0.0, 0.52, -0.1}, {0.2, -0.1, 0.58, 0.35}};
    const double hold = 0.6, move = 0.3, period = hold + move;
    const auto path = [&](double t) {
      const double u = std::max(0.0, t) / period;
      const std::size_t i = std::min(stations.size() - 1, static_cast<std::size_t>(u));
      const double into = (u - static_cast<double>(i)) * period;
      if (into <= hold || i + 1 >= stations.size())
        return stations[i];
      const double w = 0.5 - 0.5 * std::cos(M_PI * (into - hold) / move);
      return Eigen::Vector4d((1 - w) * stations[i] + w * stations[i + 1]);
    };
    std::vector<double> times;
    for (std::size_t i = 0; i < stations.size(); ++i)
      for (int k = 0; k < 5; ++k)
        times.push_back(static_cast<double>(i) * period + 0.2 + 0.05 * k);
    const ArmRecording rec =
        armRecording(camera, board, X, Y, path, times, period * static_cast<double>(stations.size()), latency, 22);
    CHECK_THROWS_WITH(calibrateHandEyeWithTimeOffset(camera, board, rec.motion, rec.image_times, rec.features, rec.names,
                                                     HandEyeOptions(), search),
                      Catch::Contains("the motion must change speed"));
  }
}

// Not run by CTest: a timestamped arm recording for trying `calibrate-rig --hand-eye eye-in-hand
// --estimate-time-offset` (the test above's continuous motion, rendered): $YAWDEPTH_CALIB_DUMP/arm
// (default /tmp/yawdepth_calib_dump/arm) gets camera.yaml, poses.tum (the hand at 100 Hz) and
// images/ (25 Hz, named by their camera-clock times; a 30 ms latency):
//   build/tests/test_calibration "[.dump-arm]"
TEST_CASE("write a rendered timestamped arm recording for the command line", "[.dump-arm]")
{
  const char *env = std::getenv("YAWDEPTH_CALIB_DUMP");
  const std::string dir = std::string(env ? env : "/tmp/yawdepth_calib_dump") + "/arm";
  std::filesystem::create_directories(dir + "/images");
  const CameraModel camera =
      CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480);
  saveCameraYaml(dir + "/camera.yaml", camera);
  const BoardLayout board = chessboard(9, 6, 0.0236);
  const Eigen::Isometry3d X = isoOf(vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818));
  const Eigen::Isometry3d Y = isoOf(vpHomogeneousMatrix(0.536, 0.124, 0.0916, 2.226, -2.214, 0.0207));
  const auto path = [](double t) {
    return Eigen::Vector4d(0.45 * std::sin(2 * M_PI * 0.35 * t), 0.4 * std::sin(2 * M_PI * 0.5 * t + 1.0),
                           0.5 + 0.08 * std::sin(2 * M_PI * 0.3 * t), 0.35 * std::sin(2 * M_PI * 0.4 * t + 0.5));
  };
  std::vector<double> times;
  for (int k = 0; k / 25.0 <= 2.0; ++k)
    times.push_back(k / 25.0);
  const double latency = 0.030, t0 = 1000.0;
  const ArmRecording rec = armRecording(camera, board, X, Y, path, times, 2.0, latency, 21);
  std::ofstream tum(dir + "/poses.tum");
  for (std::size_t k = 0; k < rec.motion.samples.size(); ++k) {
    const Eigen::Isometry3d M = isoOf(wMv(rec.motion.samples[k]));
    const Eigen::Quaterniond q(M.linear());
    char line[256];
    std::snprintf(line, sizeof line, "%.6f %.9f %.9f %.9f %.12f %.12f %.12f %.12f\n", t0 + rec.motion.times[k],
                  M.translation().x(), M.translation().y(), M.translation().z(), q.x(), q.y(), q.z(), q.w());
    tum << line;
  }
  // The images: the board rendered at the true pose of each image (motion time t + latency); the
  // renderer's pose is the board in the camera, cMo = X^-1 eMr(t + latency) Y from the same path.
  for (double t : times) {
    const Eigen::Isometry3d cMo = cMoOnPath(board, path(t + latency));
    char name[64];
    std::snprintf(name, sizeof name, "/images/%.6f.png", t0 + t);
    REQUIRE(cv::imwrite(dir + name, renderAt(camera, board, cMo, 3000 + static_cast<std::uint64_t>(1000 * t))));
  }
  CHECK(std::filesystem::exists(dir + "/poses.tum"));
}
