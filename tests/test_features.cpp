// `features` and `render`: pattern text form, board geometry, the renderer, chessboard ids and
// corner accuracy against the renderer's exact truth, AprilTag ids and corner order, image reading
// and detection failure reasons.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <unistd.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/features/video_frames.h>
#include <yawdepth/render/renderer.h>

#include "corner_metrics.h"
#include "file_support.h"
#include "render_scenes.h"

using namespace yawdepth;
using namespace yawdepth::bench;

namespace {

constexpr double kDeg = M_PI / 180.0;

} // namespace

// ------------------------------------------------------------------------------------------------
TEST_CASE("pattern text form", "[features]") {
  const PatternSpec c = PatternSpec::parse("chessboard:5x4:0.02");
  CHECK(c.kind == PatternSpec::Kind::Chessboard);
  CHECK(c.cols == 5);
  CHECK(c.rows == 4);
  CHECK(c.square == 0.02);
  CHECK(c.chessboardCorners() == 20);
  CHECK(c.toString() == "chessboard:5x4:0.02");
  CHECK(PatternSpec::parse(c.toString()).square == c.square);
  const PatternSpec odd = PatternSpec::parse("chessboard:9X6:0.0254");
  CHECK(PatternSpec::parse(odd.toString()).square == 0.0254);

  const PatternSpec a = PatternSpec::parse("apriltag:36h11:0.05");
  CHECK(a.kind == PatternSpec::Kind::AprilTag);
  CHECK(a.family == "36h11");
  CHECK(a.tag_size == 0.05);
  CHECK(a.chessboardCorners() == 0);
  CHECK(a.toString() == "apriltag:36h11:0.05");
  CHECK(PatternSpec::parse("apriltag:tag25h9:0.1").family == "25h9");
  CHECK(PatternSpec::parse("apriltag:Circle21h7:0.1").family == "circle21h7");

  for (const char *bad : {"", "chessboard", "chessboard:5x4", "chessboard:5x4:0.02:1", "chessboard:5:0.02",
                          "chessboard:5x:0.02", "chessboard:x4:0.02", "chessboard:-5x4:0.02", "chessboard:2x4:0.02",
                          "chessboard:5x4:0", "chessboard:5x4:-0.02", "chessboard:5x4:abc", "chessboard:5x4:nan",
                          "chessboard:5x4:0.02mm", "chessboard:5.5x4:0.02", "apriltag:36h11", "apriltag:99h99:0.05",
                          "apriltag:36h11:0", "apriltag:36h11:inf", "circles:5x4:0.02"})
    CHECK_THROWS_AS(PatternSpec::parse(bad), yawdepth::Error);
}

TEST_CASE("board layout: ids, reflectance, extent", "[features]") {
  BoardLayout b;
  b.pattern = PatternSpec::parse("chessboard:5x4:0.02");
  const auto f = b.features();
  REQUIRE(f.size() == 20);
  CHECK(f[7].first == 7);
  CHECK(f[7].second.isApprox(Eigen::Vector3d(2 * 0.02, 1 * 0.02, 0)));
  CHECK(b.reflectance(-0.01, -0.01) == 0); // the outer square beyond corner 0: black
  CHECK(b.reflectance(0.01, -0.01) == 1);
  CHECK(b.reflectance(0.01, 0.01) == 0);
  CHECK(b.reflectance(0.09, 0.07) == 1);   // square (4, 3) beyond the last corner: white (5 + 4 odd)
  CHECK(b.reflectance(-0.03, 0.0) == 1);   // margin
  CHECK(b.reflectance(-0.05, 0.0) == -1);  // outside
  CHECK(b.extent().isApprox(Eigen::Vector4d(-0.04, -0.04, 0.12, 0.10)));

  BoardLayout t;
  t.pattern = PatternSpec::parse("apriltag:36h11:0.08");
  t.tags_x = 2;
  t.tags_y = 1;
  t.gap = 0.02;
  t.first_tag_id = 4;
  const auto tf = t.features();
  REQUIRE(tf.size() == 10);
  CHECK(tf[0].first == aprilTagFeatureId(4));
  CHECK(tf[0].second.isApprox(Eigen::Vector3d(0.04, 0.04, 0)));
  CHECK(tf[1].first == aprilTagFeatureId(4, 0));
  CHECK(tf[1].second.isApprox(Eigen::Vector3d(0, 0.08, 0))); // bottom-left
  CHECK(tf[9].first == aprilTagFeatureId(5, 3));
  CHECK(tf[9].second.isApprox(Eigen::Vector3d(0.10, 0, 0))); // top-left of tag 5
  CHECK(t.reflectance(0.005, 0.005) == 0);   // black border
  CHECK(t.reflectance(-0.005, 0.04) == 1);   // white ring of the bitmap / margin
  CHECK(t.extent().isApprox(Eigen::Vector4d(-0.02, -0.02, 0.20, 0.10)));
  const AprilTagFamilyInfo info = aprilTagFamilyInfo("36h11");
  CHECK(info.ncodes == 587);
  CHECK(info.total_width == 10);
  CHECK(info.width_at_border == 8);
  t.first_tag_id = 586;
  CHECK_THROWS_AS(t.features(), yawdepth::Error);
}

TEST_CASE("renderer: exact coverage, background and determinism", "[render]") {
  const CameraModel cam = CameraModel::brown(800, 800, 320, 240, {}, 640, 480);
  const YawRig rig;
  MotionSample s;
  BoardLayout b;
  b.pattern = PatternSpec::parse("chessboard:5x4:0.02");
  // Fronto-parallel at 0.8 m: 20 px squares; corner 0 at pixel (300.25, 220.5).
  Eigen::Isometry3d wMb = Eigen::Isometry3d::Identity();
  wMb.translation() = Eigen::Vector3d(-19.75 * 0.001, -19.5 * 0.001, 0.8);
  RenderOptions ro;
  const cv::Mat img = renderBoard(cam, rig, s, b, wMb, ro);
  REQUIRE(img.type() == CV_8UC1);
  REQUIRE(img.cols == 640);
  REQUIRE(img.rows == 480);
  CHECK(img.at<unsigned char>(210, 290) == 25);  // inside the black outer square
  CHECK(img.at<unsigned char>(210, 310) == 230); // white
  CHECK(img.at<unsigned char>(5, 5) == 110);     // background
  // Pixel 300 spans u in [299.5, 300.5]: 3/4 left of the edge at 300.25 (black above row 220.5).
  CHECK(img.at<unsigned char>(210, 300) == static_cast<int>(std::lround(0.75 * 25 + 0.25 * 230)));
  // Board behind the camera: all background.
  Eigen::Isometry3d behind = wMb;
  behind.translation().z() = -0.8;
  const cv::Mat bg = renderBoard(cam, rig, s, b, behind, ro);
  CHECK(cv::countNonZero(bg != 110) == 0);
  // Same seed, same image; blur and noise change it.
  ro.blur_sigma_px = 0.7;
  ro.noise_sigma = 2;
  const cv::Mat n1 = renderBoard(cam, rig, s, b, wMb, ro), n2 = renderBoard(cam, rig, s, b, wMb, ro);
  CHECK(cv::countNonZero(n1 != n2) == 0);
  ro.seed = 2;
  CHECK(cv::countNonZero(renderBoard(cam, rig, s, b, wMb, ro) != n1) > 0);
  RenderOptions badopt;
  badopt.supersampling = 0;
  CHECK_THROWS_AS(renderBoard(cam, rig, s, b, wMb, badopt), yawdepth::Error);
  CHECK_THROWS_AS(renderBoard(CameraModel::brown(800, 800, 320, 240, {}), rig, s, b, wMb), yawdepth::Error);
}

TEST_CASE("renderer: the textured wall around the board, fixed to its plane", "[render]") {
  constexpr int kMinWallContrast = 30; // gray levels: the texture's standard deviation at least this
  constexpr int kShiftPx = 10;         // a 10 mm sideways step at 0.8 m and f = 800 px
  const CameraModel cam = CameraModel::brown(800, 800, 320, 240, {}, 640, 480);
  const YawRig rig;
  MotionSample s;
  BoardLayout b;
  b.pattern = PatternSpec::parse("chessboard:5x4:0.02");
  Eigen::Isometry3d wMb = Eigen::Isometry3d::Identity();
  wMb.translation() = Eigen::Vector3d(-19.75 * 0.001, -19.5 * 0.001, 0.8);
  RenderOptions plain, walled;
  walled.wall_texel = 0.02;
  walled.wall_seed = 5;
  const cv::Mat a = renderBoard(cam, rig, s, b, wMb, plain), w = renderBoard(cam, rig, s, b, wMb, walled);
  // The board is unchanged (away from its outline, where the wall is mixed in).
  cv::Mat board_mask;
  cv::erode(a != 110, board_mask, cv::Mat::ones(5, 5, CV_8U));
  REQUIRE(cv::countNonZero(board_mask) > 10000);
  CHECK(cv::countNonZero((a != w) & board_mask) == 0);
  // Beyond it, a texture with contrast.
  cv::Mat mean, sd;
  cv::meanStdDev(w, mean, sd, a == 110);
  CHECK(sd.at<double>(0) > kMinWallContrast);
  // Fixed to the wall: a sideways step shifts the image by exactly kShiftPx; another seed, another wall.
  MotionSample moved = s;
  moved.x = kShiftPx * 0.8 / 800;
  const cv::Mat w2 = renderBoard(cam, rig, moved, b, wMb, walled);
  cv::Mat diff;
  cv::absdiff(w2(cv::Rect(0, 0, 640 - kShiftPx, 480)), w(cv::Rect(kShiftPx, 0, 640 - kShiftPx, 480)), diff);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst);
  CHECK(worst <= 1);
  walled.wall_seed = 6;
  CHECK(cv::countNonZero(renderBoard(cam, rig, s, b, wMb, walled) != w) > 100000);
  RenderOptions bad;
  bad.wall_texel = -1;
  CHECK_THROWS_AS(checkRenderOptions(cam, bad), yawdepth::Error);
}

namespace {

/*! Detect the board in `img` as frame `frame`, requiring it found with `expected` features (a failure
    names `context` and the detector's reason). */
FrameDetection detectAll(PatternDetector &det, const cv::Mat &img, long frame, std::size_t expected,
                         const std::string &context = "") {
  const FrameDetection d = det.detect(img, frame);
  INFO(context << d.reason);
  REQUIRE(d.found);
  REQUIRE(d.features.size() == expected);
  return d;
}

/*! Detect and compare every id with the truth; returns the largest error (px). */
double maxIdError(PatternDetector &det, const cv::Mat &img, const std::map<long, Eigen::Vector2d> &truth,
                  std::size_t expected) {
  const FrameDetection d = detectAll(det, img, 0, expected);
  double worst = 0;
  for (const auto &f : d.features)
    worst = std::max(worst, (Eigen::Vector2d(f.u, f.v) - truth.at(f.id)).norm());
  return worst;
}

/*! Place the board of `sc` at `depth` near the optical axis, tilted about two axes by up to
    +-max_tilt_deg / 2, rolled by roll(), offset sideways; `draw` gives the uniform numbers in [0, 1).
    False when a corner is behind the camera or closer than `margin` px to the image border. */
template <class Roll, class Draw>
bool placeBoard(AccuracyScene &sc, const YawRig &rig, double depth, double max_tilt_deg, const Roll &roll, double margin,
                const Draw &draw) {
  sc.wMb = boardPose(rig, sc.sample, sc.board, depth, (draw() - 0.5) * max_tilt_deg * kDeg,
                     (draw() - 0.5) * max_tilt_deg * kDeg, roll(), (draw() - 0.5) * 0.2 * depth,
                     (draw() - 0.5) * 0.15 * depth);
  return truthPixels(sc.cam, rig, sc.sample, sc.board, sc.wMb, sc.truth) && allInside(sc.truth, sc.cam, margin);
}

} // namespace

TEST_CASE("chessboard ids follow the board's own grid under rotation", "[features][slow]") {
  const CameraModel cam = paperCamera();
  const YawRig rig = paperRig();
  MotionSample s;
  RenderOptions ro;
  ro.blur_sigma_px = 0.7;
  ro.noise_sigma = 2;
  ro.supersampling = 2; // ids, not corner accuracy: a coarser anti-aliasing renders 10x faster
  SECTION("odd boards: the square colours fix the orientation in every frame") {
    for (const char *pat : {"chessboard:5x4:0.02", "chessboard:7x4:0.015"}) {
      BoardLayout b;
      b.pattern = PatternSpec::parse(pat);
      for (double roll : {0.0, 0.4, M_PI, M_PI + 0.3, -M_PI / 2}) {
        PatternDetector det(b.pattern); // fresh: no history
        const Eigen::Isometry3d wMb = boardPose(rig, s, b, 0.6, 0.2, -0.25, roll, 0.0, 0.0);
        std::map<long, Eigen::Vector2d> truth;
        REQUIRE(truthPixels(cam, rig, s, b, wMb, truth));
        CHECK(maxIdError(det, renderBoard(cam, rig, s, b, wMb, ro), truth, truth.size()) < 0.2);
      }
    }
  }
  SECTION("symmetric boards: consistent with the previous frame while the board turns by 180 degrees") {
    for (const char *pat : {"chessboard:6x4:0.02", "chessboard:5x5:0.02", "chessboard:4x4:0.02"}) {
      BoardLayout b;
      b.pattern = PatternSpec::parse(pat);
      PatternDetector det(b.pattern);
      for (int k = 0; k <= 6; ++k) { // 0 .. 180 degrees in 30 degree steps
        const double roll = 0.05 + k * M_PI / 6;
        const Eigen::Isometry3d wMb = boardPose(rig, s, b, 0.6, 0.15, 0.1, roll, 0.0, 0.0);
        std::map<long, Eigen::Vector2d> truth;
        REQUIRE(truthPixels(cam, rig, s, b, wMb, truth));
        INFO(pat << " roll " << roll);
        CHECK(maxIdError(det, renderBoard(cam, rig, s, b, wMb, ro), truth, truth.size()) < 0.2);
      }
    }
  }
}

TEST_CASE("chessboard corner accuracy on rendered images", "[features][slow]") {
  // Seeded random poses (tilt up to 40 degrees, any roll, two cameras incl. strong distortion),
  // blur 0.7 px, noise 2 gray levels; boards whose orientation the colours fix.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const auto draw = [&] { return U(rng); };
  const YawRig rig = paperRig();
  ErrorStats stats;
  int scenes = 0, attempts = 0;
  while (scenes < 16 && attempts < 400) {
    ++attempts;
    AccuracyScene sc;
    const bool wide = scenes % 2 == 1;
    sc.cam = wide ? wideCamera() : paperCamera();
    sc.board.pattern = PatternSpec::parse(scenes % 4 < 2 ? "chessboard:5x4:0.02" : "chessboard:7x6:0.015");
    sc.sample.yaw = (U(rng) - 0.5) * 90 * kDeg;
    const double depth = wide ? 0.25 + 0.3 * U(rng) : 0.5 + 0.4 * U(rng);
    if (!placeBoard(sc, rig, depth, 80, [&] { return U(rng) * 2 * M_PI; }, 25, draw))
      continue;
    RenderOptions ro;
    ro.blur_sigma_px = 0.7;
    ro.noise_sigma = 2;
    ro.seed = 500 + scenes;
    const cv::Mat img = renderBoard(sc.cam, rig, sc.sample, sc.board, sc.wMb, ro);
    PatternDetector det(sc.board.pattern);
    const FrameDetection d = detectAll(det, img, scenes, sc.truth.size(), "scene " + std::to_string(scenes) + ": ");
    for (const auto &f : d.features)
      stats.add(Eigen::Vector2d(f.u, f.v) - sc.truth.at(f.id));
    ++scenes;
  }
  REQUIRE(scenes == 16);
  std::printf("corner accuracy: %ld corners, rms %.4f px, bias (%+.4f, %+.4f) px, max %.4f px\n", stats.n,
              stats.rms(), stats.biasX(), stats.biasY(), stats.max);
  // docs/accuracy.md (the paper's experiment) quotes 0.018 px RMS for these renders (blur 0.7, noise 2; the
  // same figure bench_corner_refinement prints on its 24 scenes). Measured here (Release, seeded):
  // 496 corners, RMS 0.0175 px, bias (-0.0010, -0.0003) px, max 0.072 px; the bounds sit just above.
  constexpr double kRmsTolPx = 0.025;
  constexpr double kBiasTolPx = 0.005;
  constexpr double kMaxTolPx = 0.1; // also: every id right (a wrong id is off by a whole square)
  CHECK(stats.rms() < kRmsTolPx);
  CHECK(std::abs(stats.biasX()) < kBiasTolPx);
  CHECK(std::abs(stats.biasY()) < kBiasTolPx);
  CHECK(stats.max < kMaxTolPx);
}

TEST_CASE("chessboard corners on photo-like renders of a board with narrow outer squares", "[features]") {
  // What real photographs have and ideal renders lack: outer squares cut to 45 % (the outer
  // corners' windows must stop before the board's edge), JPEG, gamma, vignetting, a light
  // gradient, Bayer demosaicing, shot noise and depth-dependent defocus. Strong barrel distortion.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const auto draw = [&] { return U(rng); };
  const YawRig rig = paperRig();
  ErrorStats ours, outer, peer;
  int scenes = 0, attempts = 0;
  while (scenes < 6 && attempts < 400) {
    ++attempts;
    AccuracyScene sc;
    sc.cam = wideCamera();
    sc.board.pattern = PatternSpec::parse("chessboard:9x6:0.025");
    sc.board.outer_square = 0.45 * 0.025;
    const double depth = 0.3 + 0.3 * U(rng);
    if (!placeBoard(sc, rig, depth, 70, [&] { return (U(rng) - 0.5) * 30 * kDeg; }, 30, draw))
      continue;
    RenderOptions ro = photoLikeRenderOptions(depth);
    ro.light_angle = U(rng) * 2 * M_PI;
    ro.seed = 900 + scenes;
    const cv::Mat img = renderBoard(sc.cam, rig, sc.sample, sc.board, sc.wMb, ro);
    PatternDetector det(sc.board.pattern);
    const FrameDetection d = detectAll(det, img, scenes, sc.truth.size(), "scene " + std::to_string(scenes) + ": ");
    for (const auto &f : d.features) {
      const Eigen::Vector2d e = Eigen::Vector2d(f.u, f.v) - sc.truth.at(f.id);
      ours.add(e);
      const long c = f.id % 9, r = f.id / 9;
      if (c == 0 || c == 8 || r == 0 || r == 5)
        outer.add(e);
    }
    // the peer: stock OpenCV, cornerSubPix 11x11
    const bench::Corners pc = bench::opencvSubPix(img, 9, 6, 5);
    REQUIRE(pc.size() == sc.truth.size());
    for (const auto &q : pc) {
      double best = 1e9;
      for (const auto &t : sc.truth)
        best = std::min(best, std::hypot(q.x - t.second.x(), q.y - t.second.y()));
      peer.add(Eigen::Vector2d(best, 0));
    }
    ++scenes;
  }
  REQUIRE(scenes == 6);
  std::printf("photo-like renders: %ld corners, rms %.4f px (outer corners %.4f), max %.4f; cornerSubPix 11x11 rms %.4f\n",
              ours.n, ours.rms(), outer.rms(), ours.max, peer.rms());
  CHECK(ours.rms() < 0.08);
  CHECK(outer.rms() < 0.1);
  CHECK(ours.max < 0.4);
  CHECK(ours.rms() < 0.9 * peer.rms());
}

TEST_CASE("chessboard corners on real photographs: at or below stock OpenCV", "[features]") {
  // The eye-in-hand photographs (tests/data/franka-eye-in-hand, 8 PNG, 9x6): every corner found,
  // and the homography RMS of the undistorted corners (a camera calibrated by OpenCV on the peer's
  // corners, favouring neither) at or below cornerSubPix 11x11's, image by image in the median.
  const std::string dir = std::string(YAWDEPTH_TEST_DATA_DIR) + "/franka-eye-in-hand/";
  const PatternSpec pattern = PatternSpec::parse("chessboard:9x6:0.0236");
  std::vector<bench::Corners> ours, peer;
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<cv::Point3f> board;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 9; ++c)
      board.emplace_back(static_cast<float>(c * 0.0236), static_cast<float>(r * 0.0236), 0.f);
  cv::Size size;
  for (int k = 1; k <= 8; ++k) {
    const cv::Mat img = readGrayImage(dir + "franka_image-" + std::to_string(k) + ".png");
    size = img.size();
    PatternDetector det(pattern);
    const FrameDetection d = det.detect(img, k);
    INFO("image " << k << ": " << d.reason);
    REQUIRE(d.found);
    REQUIRE(d.features.size() == 54);
    bench::Corners c(54);
    for (const auto &f : d.features)
      c[static_cast<std::size_t>(f.id)] = cv::Point2f(static_cast<float>(f.u), static_cast<float>(f.v));
    bench::Corners p = bench::opencvSubPix(img, 9, 6, 5);
    REQUIRE(p.size() == 54);
    REQUIRE(bench::matchOrder(c, p));
    ours.push_back(c);
    peer.push_back(p);
    obj.push_back(board);
  }
  cv::Mat K, D;
  std::vector<cv::Mat> rv, tv;
  cv::calibrateCamera(obj, peer, size, K, D, rv, tv);
  std::vector<double> h_ours, h_peer;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    h_ours.push_back(bench::planarFit(ours[i], 9, 6, K, D).h_rms);
    h_peer.push_back(bench::planarFit(peer[i], 9, 6, K, D).h_rms);
  }
  std::printf("franka photos: homography RMS median yawdepth %.4f px, cornerSubPix 11x11 %.4f px\n",
              bench::median(h_ours), bench::median(h_peer));
  CHECK(bench::median(h_ours) <= bench::median(h_peer));
  CHECK(bench::median(h_ours) < 0.2);
}

TEST_CASE("dot grid centres: darkness centroid and perspective pole against the truth", "[features]") {
  // Seeded 6x6 dot grids under a random homography (exact outlines, area-averaged, blur, noise):
  // refineDotGridCentres on cv::findCirclesGrid's centres is closer to the true images of the
  // circles' centres than OpenCV's own, and within 0.01 px RMS.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(-1, 1);
  double so = 0, sy = 0, worst = 0;
  int n = 0;
  for (int k = 0; k < 6; ++k) {
    const double s = 55 + 10 * U(rng);
    const cv::Matx33d H(s, 0.15 * s * U(rng), 170 + 20 * U(rng), 0.15 * s * U(rng), s, 90 + 20 * U(rng),
                        3e-3 * U(rng), 3e-3 * U(rng), 1);
    std::vector<cv::Point2f> truth;
    const cv::Mat g = bench::dotGridImage(H, 6, 6, 0.6, cv::Size(640, 480), 0.8, 2.0, 200 + static_cast<unsigned>(k), truth);
    bench::Corners c;
    REQUIRE(cv::findCirclesGrid(g, cv::Size(6, 6), c, cv::CALIB_CB_SYMMETRIC_GRID));
    std::vector<cv::Point2d> d(c.begin(), c.end());
    CHECK(refineDotGridCentres(g, d, 6, 6) == 36);
    bench::Corners y;
    for (const auto &p : d)
      y.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    REQUIRE(bench::matchOrder(truth, c));
    REQUIRE(bench::matchOrder(truth, y));
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const cv::Point2f a = c[i] - truth[i], b = y[i] - truth[i];
      so += a.dot(a);
      sy += b.dot(b);
      worst = std::max(worst, static_cast<double>(cv::norm(b)));
      n += 2;
    }
  }
  const double ro = std::sqrt(so / n), ry = std::sqrt(sy / n);
  std::printf("dot grids: centre error RMS %.4f px (worst %.4f), cv::findCirclesGrid %.4f px\n", ry, worst, ro);
  CHECK(ry < 0.01);
  CHECK(ry < 0.8 * ro);
  CHECK(worst < 0.05);
  // bad input: a one-line error, never a crash
  std::vector<cv::Point2d> few(5);
  CHECK_THROWS_AS(refineDotGridCentres(cv::Mat(100, 100, CV_8UC1, cv::Scalar(0)), few, 6, 6), Error);
}

TEST_CASE("renderer: photo-like options", "[render]") {
  const CameraModel cam = wideCamera();
  const YawRig rig = paperRig();
  MotionSample sample;
  BoardLayout board;
  board.pattern = PatternSpec::parse("chessboard:7x5:0.03");
  const Eigen::Isometry3d wMb = boardPose(rig, sample, board, 0.45, 0.2, -0.3, 0.1, 0, 0);
  RenderOptions ideal;
  const cv::Mat a = renderBoard(cam, rig, sample, board, wMb, ideal);
  RenderOptions photo = photoLikeRenderOptions(0.45);
  const cv::Mat b = renderBoard(cam, rig, sample, board, wMb, photo);
  const cv::Mat b2 = renderBoard(cam, rig, sample, board, wMb, photo);
  CHECK(cv::norm(b, b2, cv::NORM_INF) == 0); // deterministic for a seed
  photo.seed = 2;
  CHECK(cv::norm(b, renderBoard(cam, rig, sample, board, wMb, photo), cv::NORM_INF) > 0);
  CHECK(cv::norm(a, b, cv::NORM_L1) / a.total() > 2); // it changed the picture
  // vignetting alone darkens the corners of the image and leaves the centre
  RenderOptions vig;
  vig.vignetting = 0.5;
  vig.background = 200;
  const cv::Mat v = renderBoard(cam, rig, sample, board, Eigen::Isometry3d(Eigen::Translation3d(10, 10, -1)), vig);
  CHECK(v.at<uchar>(240, 320) == 200);
  CHECK(std::abs(v.at<uchar>(0, 0) - 100) <= 1);
  // gamma: a mid-gray background goes up, black and white stay
  RenderOptions gam;
  gam.gamma = 2.2;
  gam.background = 64;
  const cv::Mat g = renderBoard(cam, rig, sample, board, Eigen::Isometry3d(Eigen::Translation3d(10, 10, -1)), gam);
  CHECK(std::abs(g.at<uchar>(10, 10) - std::lround(255 * std::pow(64 / 255.0, 1 / 2.2))) <= 1);
  // refused options, one line each
  for (auto bad : std::vector<std::function<void(RenderOptions &)>>{
           [](RenderOptions &o) { o.gamma = 0; }, [](RenderOptions &o) { o.jpeg_quality = 101; },
           [](RenderOptions &o) { o.vignetting = 1.5; }, [](RenderOptions &o) { o.light_gradient = -0.1; },
           [](RenderOptions &o) { o.defocus_px = 1; }, [](RenderOptions &o) { o.shot_noise = NAN; }}) {
    RenderOptions o;
    bad(o);
    CHECK_THROWS_AS(checkRenderOptions(cam, o), Error);
  }
}

TEST_CASE("AprilTag ids, corner order and centre against the truth", "[features]") {
  const CameraModel cam = CameraModel::brown(900, 900, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
  const YawRig rig;
  MotionSample s;
  for (const char *pat : {"apriltag:36h11:0.05", "apriltag:25h9:0.05"}) {
    BoardLayout b;
    b.pattern = PatternSpec::parse(pat);
    b.tags_x = 2;
    b.tags_y = 2;
    b.gap = 0.03;
    b.first_tag_id = 3;
    for (double roll : {0.3, 2.5}) {
      const Eigen::Isometry3d wMb = boardPose(rig, s, b, 0.45, 0.3, 0.1, roll, 0.0, 0.0);
      std::map<long, Eigen::Vector2d> truth;
      REQUIRE(truthPixels(cam, rig, s, b, wMb, truth));
      RenderOptions ro;
      ro.blur_sigma_px = 0.7;
      ro.noise_sigma = 2;
      const cv::Mat img = renderBoard(cam, rig, s, b, wMb, ro);
      PatternDetector det(b.pattern);
      det.setCamera(cam);
      const FrameDetection d = det.detect(img, 3);
      INFO(pat << " roll " << roll << ": " << d.reason);
      REQUIRE(d.found);
      CHECK(d.frame == 3);
      REQUIRE(d.features.size() == 20); // 4 tags x (centre + 4 corners)
      for (const auto &f : d.features) {
        REQUIRE(truth.count(f.id) == 1);
        CHECK((Eigen::Vector2d(f.u, f.v) - truth.at(f.id)).norm() < 0.3);
      }
    }
  }
  CHECK_THROWS_AS(PatternDetector(PatternSpec{PatternSpec::Kind::AprilTag, 0, 0, 0, "99h1", 0.05}), yawdepth::Error);
}

TEST_CASE("readGrayImage and detection failures", "[features]") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("yawdepth_features_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string missing = (dir / "missing.png").string();
  try {
    readGrayImage(missing);
    FAIL("no exception");
  } catch (const yawdepth::Error &e) {
    CHECK(std::string(e.what()).rfind(missing + ": cannot read image", 0) == 0);
  }
  cv::Mat img(60, 80, CV_8UC1);
  cv::randu(img, 0, 255);
  const std::string good = (dir / "good.png").string();
  REQUIRE(cv::imwrite(good, img));
  const cv::Mat back = readGrayImage(good);
  CHECK(cv::countNonZero(back != img) == 0);
  // A truncated PNG.
  std::ifstream in(good, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string truncated = (dir / "truncated.png").string();
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  CHECK_THROWS_AS(readGrayImage(truncated), yawdepth::Error);
  const std::string text = (dir / "text.png").string();
  std::ofstream(text) << "not an image\n";
  CHECK_THROWS_AS(readGrayImage(text), yawdepth::Error);
  fs::remove_all(dir);

  PatternDetector chess(PatternSpec::parse("chessboard:5x4:0.02"));
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(128));
  FrameDetection d = chess.detect(blank, 7);
  CHECK_FALSE(d.found);
  CHECK(d.frame == 7);
  CHECK(d.features.empty());
  CHECK(d.reason == "chessboard 5x4 not found");
  d = chess.detect(cv::Mat(), 8);
  CHECK_FALSE(d.found);
  CHECK(d.reason == "empty image");
  d = chess.detect(cv::Mat(10, 10, CV_32FC1, cv::Scalar(0.5)), 9);
  CHECK_FALSE(d.found);
  CHECK_FALSE(d.reason.empty());
  PatternDetector tags(PatternSpec::parse("apriltag:36h11:0.05"));
  d = tags.detect(blank, 1);
  CHECK_FALSE(d.found);
  CHECK(d.reason == "no AprilTag of family 36h11 found");
  cv::Mat colour;
  cv::cvtColor(blank, colour, cv::COLOR_GRAY2BGR);
  CHECK_FALSE(tags.detect(colour, 2).found);
}

TEST_CASE("toTracks groups by id and sorts by frame", "[features]") {
  std::vector<FrameDetection> frames(3);
  frames[0].frame = 5;
  frames[0].found = true;
  frames[0].features = {{1, 10, 20}, {0, 1, 2}};
  frames[1].frame = 2;
  frames[1].found = true;
  frames[1].features = {{1, 11, 21}};
  frames[2].frame = 3;
  frames[2].found = false;
  const std::vector<Track> tracks = PatternDetector::toTracks(frames);
  REQUIRE(tracks.size() == 2);
  CHECK(tracks[0].id == 0);
  REQUIRE(tracks[1].observations.size() == 2);
  CHECK(tracks[1].observations[0].frame == 2);
  CHECK(tracks[1].observations[0].u == 11);
  CHECK(tracks[1].observations[1].frame == 5);
}

namespace {

// A textured plane Z = depth in front of camera 1 (smoothed random noise, seeded), seen by a camera
// 2 at pose c2Mc1: image 2 is image 1 warped by the plane's homography K (R + t n^T / d) K^-1.
struct PlaneScene {
  CameraModel camera = CameraModel::brown(600, 600, 320, 240, {0, 0, 0, 0}, 640, 480);
  double depth = 2.0;
  cv::Mat texture(unsigned seed) const
  {
    cv::Mat noise(480, 640, CV_32F);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
    cv::Mat smooth;
    cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 2.0);
    cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
    cv::Mat out;
    smooth.convertTo(out, CV_8U);
    return out;
  }
  cv::Matx33d homography(const vpHomogeneousMatrix &c2Mc1) const
  {
    const cv::Matx33d K(600, 0, 320, 0, 600, 240, 0, 0, 1);
    cv::Matx33d A;
    for (unsigned i = 0; i < 3; ++i)
      for (unsigned j = 0; j < 3; ++j)
        A(i, j) = c2Mc1[i][j] + (j == 2 ? c2Mc1[i][3] / depth : 0.0);
    return K * A * K.inv();
  }
  cv::Mat warp(const cv::Mat &image, const vpHomogeneousMatrix &c2Mc1) const
  {
    cv::Mat out;
    cv::warpPerspective(image, out, cv::Mat(homography(c2Mc1)), image.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
    return out;
  }
  Eigen::Vector2d map(const vpHomogeneousMatrix &c2Mc1, double u, double v) const
  {
    const cv::Vec3d p = homography(c2Mc1) * cv::Vec3d(u, v, 1.0);
    return {p[0] / p[2], p[1] / p[2]};
  }
};

} // namespace

TEST_CASE("klt: tracks follow a textured plane, ids stable, the true motion's epipolar gate cuts nothing", "[features][klt]")
{
  constexpr double kTrackTolPx = 0.15; // KLT on a smooth texture with a cubic warp
  const PlaneScene scene;
  const cv::Mat im1 = scene.texture(7);
  // A sideways step with a little pan: parallax of 600 * 0.03 / 2 = 9 px plus 6 px of rotation.
  const vpHomogeneousMatrix c2Mc1(-0.03, 0.0, 0.01, 0.0, 0.01, 0.0);
  const cv::Mat im2 = scene.warp(im1, c2Mc1);
  KltOptions o;
  o.max_features = 150;
  KltTracker tracker(scene.camera, o);
  const std::vector<FeatureObservation> f1 = tracker.track(im1);
  REQUIRE(f1.size() >= 100);
  CHECK(tracker.lastStats().detected == static_cast<int>(f1.size()));
  // The ids are distinct, and the features at least min_distance apart.
  std::map<long, FeatureObservation> by_id;
  for (const FeatureObservation &f : f1)
    by_id[f.id] = f;
  CHECK(by_id.size() == f1.size());
  double closest = 1e9;
  for (std::size_t i = 0; i < f1.size(); ++i)
    for (std::size_t j = i + 1; j < f1.size(); ++j)
      closest = std::min(closest, std::hypot(f1[i].u - f1[j].u, f1[i].v - f1[j].v));
  CHECK(closest >= o.min_distance);
  KltMotion m;
  m.cMp = c2Mc1;
  m.sigma_rot = 0.001;
  m.sigma_trans = 0.001;
  const std::vector<FeatureObservation> f2 = tracker.track(im2, &m);
  const KltStats st = tracker.lastStats();
  CHECK(st.lost_epipolar == 0);
  CHECK(st.tracked >= static_cast<int>(0.9 * f1.size()));
  int checked = 0;
  double worst = 0;
  for (const FeatureObservation &f : f2) {
    const auto it = by_id.find(f.id);
    if (it == by_id.end())
      continue; // a new feature
    const Eigen::Vector2d truth = scene.map(c2Mc1, it->second.u, it->second.v);
    worst = std::max(worst, std::hypot(f.u - truth.x(), f.v - truth.y()));
    ++checked;
  }
  CHECK(checked == st.tracked);
  CHECK(worst < kTrackTolPx);
}

TEST_CASE("klt: the epipolar segment and the band cut tracks that the motion cannot explain", "[features][klt]")
{
  constexpr double kRoundOff = 1e-6; // px
  const PlaneScene scene;
  KltOptions o;
  o.min_depth = 0.5;
  KltTracker tracker(scene.camera, o);
  const vpHomogeneousMatrix cMp(-0.05, 0.0, 0.02, 0.0, 0.02, 0.0);
  // A point at depth 3 m seen in both cameras: on its epipolar segment.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-0.4, 0.4);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d P(uni(rng) * 3, uni(rng) * 3, 3.0 + uni(rng));
    const vpColVector Q = cMp * vpColVector({P.x(), P.y(), P.z(), 1.0});
    const Eigen::Vector2d a = scene.camera.project(Eigen::Vector2d(P.x() / P.z(), P.y() / P.z()));
    const Eigen::Vector2d b = scene.camera.project(Eigen::Vector2d(Q[0] / Q[2], Q[1] / Q[2]));
    CHECK(tracker.epipolarDistance(a, b, cMp) < kRoundOff);
    // Moved across the epipolar line (nearly along v: the baseline is mostly along x) by 3 px: 3 px away.
    CHECK(tracker.epipolarDistance(a, b + Eigen::Vector2d(0, 3), cMp) == Approx(3.0).margin(0.1));
    // Nearer than min_depth would have to be, along the line: off the segment's near end.
    const double near = 0.2;
    const Eigen::Vector3d Pn = P * (near / P.z());
    const vpColVector Qn = cMp * vpColVector({Pn.x(), Pn.y(), Pn.z(), 1.0});
    const Eigen::Vector2d bn = scene.camera.project(Eigen::Vector2d(Qn[0] / Qn[2], Qn[1] / Qn[2]));
    CHECK(tracker.epipolarDistance(a, bn, cMp) > 5.0);
  }
  // No translation: the segment is the rotation's prediction, a point.
  const vpHomogeneousMatrix rot(0, 0, 0, 0.0, 0.02, 0.0);
  const Eigen::Vector2d a(300, 200);
  Eigen::Vector2d m;
  REQUIRE(scene.camera.undistort(a, m));
  const vpColVector q = rot * vpColVector({m.x(), m.y(), 1.0, 1.0});
  const Eigen::Vector2d b = scene.camera.project(Eigen::Vector2d(q[0] / q[2], q[1] / q[2]));
  CHECK(tracker.epipolarDistance(a, b, rot) < kRoundOff);
  CHECK(tracker.epipolarDistance(a, b + Eigen::Vector2d(2, 0), rot) == Approx(2.0).margin(1e-6));
  // The band: k sqrt(2 sigma_px^2 + (f sigma_rot)^2 + (f sigma_t / Z_min)^2).
  KltMotion motion;
  motion.sigma_rot = 0.001;
  motion.sigma_trans = 0.0005;
  CHECK(tracker.bandHalfWidth(motion) ==
        Approx(o.gate_sigmas * std::sqrt(2 * 0.25 + 0.36 + 0.36)).epsilon(1e-12));

  // Tracking with a motion that says the camera went up, not sideways: the tracks are cut.
  const cv::Mat im1 = scene.texture(11);
  const vpHomogeneousMatrix truth(-0.04, 0.0, 0.0, 0.0, 0.0, 0.0);
  const cv::Mat im2 = scene.warp(im1, truth);
  KltTracker gated(scene.camera, KltOptions());
  const std::size_t n1 = gated.track(im1).size();
  KltMotion wrong;
  wrong.cMp = vpHomogeneousMatrix(0.0, -0.04, 0.0, 0.0, 0.0, 0.0);
  wrong.sigma_rot = 1e-4;
  wrong.sigma_trans = 1e-4;
  gated.track(im2, &wrong);
  CHECK(gated.lastStats().lost_epipolar >= static_cast<int>(0.9 * n1));
  CHECK(gated.lastStats().detected > 0); // new features where the old ones were cut
}

TEST_CASE("klt: bad input", "[features][klt]")
{
  const PlaneScene scene;
  KltTracker tracker(scene.camera);
  CHECK_THROWS_AS(tracker.track(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0))), Error);
  CHECK_THROWS_AS(tracker.track(cv::Mat(480, 640, CV_8UC3, cv::Scalar(0))), Error);
  CHECK_THROWS_AS(tracker.track(cv::Mat()), Error);
  CHECK_THROWS_AS(KltTracker(CameraModel::brown(600, 600, 320, 240, {0, 0, 0, 0})), Error); // no image size
  KltOptions bad;
  bad.window = 20;
  CHECK_THROWS_AS(KltTracker(scene.camera, bad), Error);
  bad = KltOptions();
  bad.min_depth = 0;
  CHECK_THROWS_AS(bad.validate(), Error);
  bad = KltOptions();
  bad.min_ncc = 1.0; // no patch correlates better than 1: every feature would be cut
  CHECK_THROWS_AS(bad.validate(), Error);
  bad.min_ncc = std::nan("");
  CHECK_THROWS_AS(bad.validate(), Error);
  bad = KltOptions();
  bad.jump_sigmas = -1;
  CHECK_THROWS_AS(bad.validate(), Error);
  bad.jump_sigmas = 0; // off
  CHECK_NOTHROW(bad.validate());
  // A blank image has no corners: no features, and no crash on the next frame either.
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(128));
  CHECK(tracker.track(blank).empty());
  CHECK(tracker.track(blank).empty());
}

TEST_CASE("klt guided: the epipolar segment against a hand computation", "[features][klt]")
{
  constexpr double kRoundOff = 1e-9; // px
  const PlaneScene scene; // f = 600 px, centre (320, 240), no distortion
  const KltTracker tracker(scene.camera);
  Eigen::Vector2d near_px, far_px;
  // Pixel (400, 300): bearing (80/600, 60/600, 1). The camera moved so that cMp's translation is
  // (-0.1, 0.05, 0.2), no rotation: at depth Z the point is (Z x - 0.1, Z y + 0.05, Z + 0.2).
  const vpHomogeneousMatrix cMp(-0.1, 0.05, 0.2, 0, 0, 0);
  REQUIRE(tracker.epipolarSegment(Eigen::Vector2d(400, 300), cMp, 1.0, 4.0, near_px, far_px));
  // Z = 1: (0.1333 - 0.1, 0.1 + 0.05, 1.2) -> u = 320 + 600 (1/30) / 1.2, v = 240 + 600 (0.15) / 1.2.
  CHECK(near_px.x() == Approx(320 + 600 * (1.0 / 30) / 1.2).margin(kRoundOff));
  CHECK(near_px.y() == Approx(240 + 600 * 0.15 / 1.2).margin(kRoundOff));
  // Z = 4: (0.5333 - 0.1, 0.4 + 0.05, 4.2).
  CHECK(far_px.x() == Approx(320 + 600 * (4 * 80.0 / 600 - 0.1) / 4.2).margin(kRoundOff));
  CHECK(far_px.y() == Approx(240 + 600 * 0.45 / 4.2).margin(kRoundOff));
  // Z = infinity: the bearing itself (no rotation), the pixel it started at.
  REQUIRE(tracker.epipolarSegment(Eigen::Vector2d(400, 300), cMp, 1.0, std::numeric_limits<double>::infinity(),
                                  near_px, far_px));
  CHECK((far_px - Eigen::Vector2d(400, 300)).norm() < kRoundOff);
  // A point between the two depths is on the segment, and the gate agrees.
  const Eigen::Vector2d mid(320 + 600 * (2 * 80.0 / 600 - 0.1) / 2.2, 240 + 600 * (0.2 + 0.05) / 2.2);
  REQUIRE(tracker.epipolarSegment(Eigen::Vector2d(400, 300), cMp, 1.0, 4.0, near_px, far_px));
  const Eigen::Vector2d ab = far_px - near_px, am = mid - near_px;
  CHECK(std::abs(ab.x() * am.y() - ab.y() * am.x()) / ab.norm() < kRoundOff);
  CHECK(am.dot(ab) > 0);
  CHECK(am.norm() < ab.norm());
  CHECK(tracker.epipolarDistance(Eigen::Vector2d(400, 300), mid, cMp) < 1e-6);
  // A pure rotation: the segment is one point, the rotated bearing.
  const vpHomogeneousMatrix rot(0, 0, 0, 0.0, 0.02, 0.0);
  REQUIRE(tracker.epipolarSegment(Eigen::Vector2d(400, 300), rot, 0.5, 10.0, near_px, far_px));
  const vpColVector q = rot * vpColVector({80.0 / 600, 0.1, 1.0, 1.0});
  const Eigen::Vector2d rotated(320 + 600 * q[0] / q[2], 240 + 600 * q[1] / q[2]);
  CHECK((near_px - rotated).norm() < kRoundOff);
  CHECK((far_px - rotated).norm() < kRoundOff);
  // Turned away (180 degrees about the vertical): no depth in front of the camera.
  CHECK_FALSE(tracker.epipolarSegment(Eigen::Vector2d(400, 300), vpHomogeneousMatrix(0, 0, 0, 0, M_PI, 0), 0.5,
                                      std::numeric_limits<double>::infinity(), near_px, far_px));
  // The options: max_depth above min_depth, a known mode.
  KltOptions bad;
  bad.max_depth = bad.min_depth;
  CHECK_THROWS_AS(bad.validate(), Error);
  CHECK_THROWS_AS(kltGuidedFromString("sometimes"), Error);
  CHECK(kltGuidedFromString(toString(KltGuided::On)) == KltGuided::On);
}

namespace {

/* The tracks of `f2` that continue a feature of `f1`, against the plane's truth: how many, their errors
   (px); `inside`: the features of f1 whose true position is at least `border` px inside the image. */
struct WideStep {
  int inside = 0, kept = 0;
  std::vector<double> errors;
  KltStats stats;
};

WideStep trackWideStep(const PlaneScene &scene, const cv::Mat &im1, const vpHomogeneousMatrix &c2Mc1, KltOptions o,
                       double hint_depth = 0, double hint_sigma = 0)
{
  KltTracker tracker(scene.camera, o);
  const std::vector<FeatureObservation> f1 = tracker.track(im1);
  if (hint_sigma > 0)
    for (const FeatureObservation &f : f1)
      tracker.setDepthHint(f.id, hint_depth, hint_sigma);
  KltMotion m;
  m.cMp = c2Mc1;
  m.sigma_rot = 1e-4;
  m.sigma_trans = 1e-4;
  const std::vector<FeatureObservation> f2 = tracker.track(scene.warp(im1, c2Mc1), &m);
  WideStep w;
  w.stats = tracker.lastStats();
  std::map<long, FeatureObservation> first;
  for (const FeatureObservation &f : f1) {
    first[f.id] = f;
    const Eigen::Vector2d t = scene.map(c2Mc1, f.u, f.v);
    w.inside += t.x() >= o.border_px && t.y() >= o.border_px && t.x() <= 639 - o.border_px && t.y() <= 479 - o.border_px;
  }
  for (const FeatureObservation &f : f2) {
    const auto it = first.find(f.id);
    if (it == first.end())
      continue;
    const Eigen::Vector2d t = scene.map(c2Mc1, it->second.u, it->second.v);
    w.errors.push_back(std::hypot(f.u - t.x(), f.v - t.y()));
    ++w.kept;
  }
  return w;
}

double medianOf(std::vector<double> v)
{
  if (v.empty())
    return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

} // namespace

TEST_CASE("klt guided: a wide sideways step plain LK loses is tracked along the epipolar segment, sub-pixel",
          "[features][klt]")
{
  constexpr double kPlainKeepsAtMost = 0.3;   // of the features whose truth is in the image
  constexpr double kGuidedKeepsAtLeast = 0.8; // the same
  constexpr double kMedianTolPx = 0.15;       // a clean cubic warp of a smooth texture
  constexpr double kWorstTolPx = 1.0;         // every track sub-pixel
  const PlaneScene scene;                     // a wall 2 m ahead, f = 600 px
  const cv::Mat im1 = scene.texture(21);
  for (const double step : {0.17, 0.5}) { // disparity 600 step / 2: 51 and 150 px
    CAPTURE(step);
    const vpHomogeneousMatrix c2Mc1(-step, 0.0, 0.0, 0.0, 0.0, 0.0);
    KltOptions o;
    o.max_features = 200;
    o.guided = KltGuided::Off;
    const WideStep plain = trackWideStep(scene, im1, c2Mc1, o);
    REQUIRE(plain.inside >= 100);
    CHECK(plain.kept <= kPlainKeepsAtMost * plain.inside);
    const auto gross = [&](const WideStep &w) {
      return std::count_if(w.errors.begin(), w.errors.end(), [&](double e) { return e >= kWorstTolPx; });
    };
    for (const KltGuided g : {KltGuided::Auto, KltGuided::On}) {
      CAPTURE(toString(g));
      o.guided = g;
      const WideStep guided = trackWideStep(scene, im1, c2Mc1, o);
      CHECK(guided.kept >= kGuidedKeepsAtLeast * guided.inside);
      CHECK(guided.stats.guided >= kGuidedKeepsAtLeast * guided.inside);
      CHECK(medianOf(guided.errors) < kMedianTolPx);
      // Every track sub-pixel: auto too, as plain LK lost most features (a wide step: every feature
      // searched, plain LK's locks onto a wrong corner within its reach corrected).
      CHECK(*std::max_element(guided.errors.begin(), guided.errors.end()) < kWorstTolPx);
      CHECK(gross(guided) <= gross(plain));
    }
    // A depth hint at the truth (2 m +- 3 x 5 cm) keeps them as well; one at 0.5 m +- 3 x 1 cm
    // searches where they are not, and keeps (almost) none.
    o.guided = KltGuided::On;
    const WideStep hinted = trackWideStep(scene, im1, c2Mc1, o, 2.0, 0.05);
    CHECK(hinted.kept >= kGuidedKeepsAtLeast * hinted.inside);
    CHECK(*std::max_element(hinted.errors.begin(), hinted.errors.end()) < kWorstTolPx);
    const WideStep wrong = trackWideStep(scene, im1, c2Mc1, o, 0.5, 0.01);
    CHECK(wrong.kept <= 0.05 * wrong.inside);
  }
}

TEST_CASE("klt: prepare() ahead of track() changes no track; another image's preparation is discarded",
          "[features][klt]")
{
  // A sequence along a wall: small sideways steps (plain LK), then a wide one (the guided search), a
  // turn, and a step back; tracked four ways: track() alone, prepare() then track() with the same
  // image, prepare() of another image (discarded) then track(), and the images as views into a
  // larger buffer.
  constexpr std::size_t kMinTracked = 50; // per image: the comparison is over real tracks
  const PlaneScene scene;
  const cv::Mat im0 = scene.texture(5);
  const std::vector<vpHomogeneousMatrix> ciMc0 = {
      vpHomogeneousMatrix(),
      vpHomogeneousMatrix(-0.02, 0.0, 0.0, 0.0, 0.0, 0.0),
      vpHomogeneousMatrix(-0.04, 0.0, 0.0, 0.0, 0.0, 0.0),
      vpHomogeneousMatrix(-0.22, 0.0, 0.0, 0.0, 0.0, 0.0), // 60 px: beyond plain LK's reach
      vpHomogeneousMatrix(-0.23, 0.0, 0.01, 0.0, 0.02, 0.0),
      vpHomogeneousMatrix(-0.21, 0.01, 0.0, 0.0, 0.02, 0.01)};
  std::vector<cv::Mat> images;
  for (const vpHomogeneousMatrix &M : ciMc0)
    images.push_back(scene.warp(im0, M));
  KltOptions o;
  o.max_features = 200;
  KltTracker alone(scene.camera, o), ahead(scene.camera, o), other(scene.camera, o), roi(scene.camera, o);
  // The images as views into larger buffers (a camera driver's padded frames), their margin other
  // pixels, the buffer overwritten after each step: the tracker keeps nothing of the caller's memory.
  cv::Mat buffer(480 + 80, 640 + 80, CV_8UC1);
  for (std::size_t i = 0; i < images.size(); ++i) {
    CAPTURE(i);
    KltMotion m;
    m.cMp = ciMc0[i] * (i > 0 ? ciMc0[i - 1] : ciMc0[i]).inverse();
    m.sigma_rot = 1e-4;
    m.sigma_trans = 1e-4;
    const KltMotion *motion = i > 0 ? &m : nullptr;
    const std::vector<FeatureObservation> a = alone.track(images[i], motion);
    ahead.prepare(images[i]);
    CHECK(ahead.prepared(images[i]));
    CHECK_FALSE(ahead.prepared(images[i].clone())); // another buffer, even with the same pixels
    ahead.prepare(images[i]);                       // again: kept, not redone
    const std::vector<FeatureObservation> b = ahead.track(images[i], motion);
    CHECK_FALSE(ahead.prepared(images[i]));
    other.prepare(images[(i + 1) % images.size()]);
    const std::vector<FeatureObservation> c = other.track(images[i].clone(), motion);
    cv::randu(buffer, 0, 256);
    const cv::Mat view = buffer(cv::Rect(40, 40, 640, 480));
    images[i].copyTo(view);
    roi.prepare(view);
    const std::vector<FeatureObservation> r = roi.track(view, motion);
    REQUIRE(a.size() >= kMinTracked);
    REQUIRE(b.size() == a.size());
    REQUIRE(c.size() == a.size());
    REQUIRE(r.size() == a.size());
    for (std::size_t k = 0; k < a.size(); ++k) { // bit for bit
      CHECK((b[k].id == a[k].id && b[k].u == a[k].u && b[k].v == a[k].v));
      CHECK((c[k].id == a[k].id && c[k].u == a[k].u && c[k].v == a[k].v));
      CHECK((r[k].id == a[k].id && r[k].u == a[k].u && r[k].v == a[k].v));
    }
    for (const KltTracker *t : {&ahead, &other, &roi}) {
      CHECK(t->lastStats().tracked == alone.lastStats().tracked);
      CHECK(t->lastStats().guided == alone.lastStats().guided);
      CHECK(t->lastStats().detected == alone.lastStats().detected);
      CHECK(t->lastStats().lost_fb == alone.lastStats().lost_fb);
      CHECK(t->lastStats().lost_epipolar == alone.lastStats().lost_epipolar);
    }
    if (i == 3)
      CHECK(alone.lastStats().guided >= static_cast<int>(kMinTracked)); // the wide step went through the search
  }
  CHECK_THROWS_WITH(ahead.prepare(cv::Mat(480, 640, CV_32FC1, cv::Scalar(0))), "klt: the image must be 8-bit gray");
  CHECK_THROWS_WITH(ahead.prepare(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0))),
                    Catch::Matchers::StartsWith("klt: the image is 320x240"));
}

TEST_CASE("klt guided: a texture repeated along the epipolar line is refused, never mismatched", "[features][klt]")
{
  constexpr double kRefusedAtLeast = 0.8; // on: of the features whose truth is in view; auto: of plain LK's tracks
  constexpr double kMatchTolPx = 1.0;     // a kept track is the right one: within a pixel of the truth
  constexpr int kPeriod = 24;             // px: the texture repeats along x
  const PlaneScene scene;
  // One 24-px-wide column of smoothed noise, repeated across the image: every patch has copies 24 px
  // apart along the (horizontal) epipolar lines of a sideways step.
  cv::Mat noise(480, kPeriod, CV_32F), tile, row;
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(noise, tile, cv::Size(0, 0), 2.0);
  cv::normalize(tile, tile, 0, 255, cv::NORM_MINMAX);
  cv::repeat(tile, 1, 640 / kPeriod + 1, row);
  cv::Mat im1;
  row(cv::Rect(0, 0, 640, 480)).convertTo(im1, CV_8U);
  const vpHomogeneousMatrix c2Mc1(-0.2, 0.0, 0.0, 0.0, 0.0, 0.0); // 60 px of disparity
  KltOptions o;
  o.max_features = 200;
  o.guided = KltGuided::Off;
  const WideStep plain = trackWideStep(scene, im1, c2Mc1, o);
  REQUIRE(plain.inside >= 50);
  const auto wrong = [&](const WideStep &w) {
    return std::count_if(w.errors.begin(), w.errors.end(), [&](double e) { return e >= kMatchTolPx; });
  };
  // Plain LK locks onto copies within its reach (12 px away, where the truth is 60): wrong tracks.
  std::printf("repeated texture, guided off: %ld of %d kept tracks wrong\n", static_cast<long>(wrong(plain)),
              plain.kept);
  // on refuses every feature; auto too, as plain LK lost or overreached most features (a wide step:
  // every feature searched, its refusals final for the tracks plain LK passed).
  for (const KltGuided g : {KltGuided::Auto, KltGuided::On}) {
    CAPTURE(toString(g));
    o.guided = g;
    const WideStep w = trackWideStep(scene, im1, c2Mc1, o);
    CHECK(w.stats.lost_ambiguous >= kRefusedAtLeast * (g == KltGuided::On ? w.inside : plain.kept));
    CHECK(wrong(w) == 0);
  }
}

namespace {

// Six frames of the textured plane, the camera 5 mm further sideways each time.
std::vector<cv::Mat> planeFrames(const PlaneScene &scene)
{
  const cv::Mat first = scene.texture(5);
  std::vector<cv::Mat> frames;
  for (int k = 0; k < 6; ++k)
    frames.push_back(scene.warp(first, vpHomogeneousMatrix(-0.005 * k, 0.0, 0.0, 0.0, 0.0, 0.0)));
  return frames;
}

std::vector<MotionSample> sidewaysLog(std::size_t n)
{
  std::vector<MotionSample> log(n);
  for (std::size_t k = 0; k < n; ++k) {
    log[k].frame = static_cast<long>(k);
    log[k].x = 0.005 * static_cast<double>(k);
  }
  return log;
}

} // namespace

TEST_CASE("video: an image sequence and a movie read frame by frame, tracked as the files are", "[features][klt]")
{
  const PlaneScene scene;
  const std::vector<cv::Mat> frames = planeFrames(scene);
  test::TempDir dir;
  std::vector<std::string> files;
  char name[32];
  for (std::size_t k = 0; k < frames.size(); ++k) {
    std::snprintf(name, sizeof name, "f%04zu.png", k);
    files.push_back(dir.file(name));
    REQUIRE(cv::imwrite(files.back(), frames[k]));
  }
  // The numbered sequence: the same pixels, in order, then the end.
  VideoFrames seq(dir.file("f%04d.png"));
  for (const cv::Mat &f : frames) {
    const cv::Mat got = seq.next();
    REQUIRE(got.type() == CV_8UC1);
    CHECK(cv::norm(got, f, cv::NORM_INF) == 0);
  }
  CHECK(seq.framesRead() == frames.size());
  const std::string ended = test::errorOf([&] { seq.next(); });
  CHECK(ended.find("ended after 6 frames") != std::string::npos);
  // trackSequence from the sequence gives the tracks the files give.
  const std::vector<MotionSample> log = sidewaysLog(frames.size());
  VideoFrames again(dir.file("f%04d.png"));
  const SequenceTracks from_files = trackSequence(scene.camera, YawRig(), log, files, NoiseModel());
  const SequenceTracks from_video =
      trackSequence(scene.camera, YawRig(), log, [&](std::size_t) { return again.next(); }, NoiseModel());
  REQUIRE(from_files.tracks.size() >= 50);
  REQUIRE(from_video.tracks.size() == from_files.tracks.size());
  for (std::size_t i = 0; i < from_files.tracks.size(); ++i) {
    REQUIRE(from_video.tracks[i].observations.size() == from_files.tracks[i].observations.size());
    CHECK(from_video.tracks[i].observations.back().u == from_files.tracks[i].observations.back().u);
  }
  CHECK(cv::norm(from_video.last_image, frames.back(), cv::NORM_INF) == 0);
  // A movie (Motion JPEG in AVI, through OpenCV's writer): six frames, colour converted to gray.
  const std::string movie = dir.file("plane.avi");
  {
    cv::VideoWriter writer(movie, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, frames[0].size(), true);
    REQUIRE(writer.isOpened());
    for (const cv::Mat &f : frames) {
      cv::Mat bgr;
      cv::cvtColor(f, bgr, cv::COLOR_GRAY2BGR);
      writer.write(bgr);
    }
  }
  VideoFrames video(movie);
  for (const cv::Mat &f : frames) {
    const cv::Mat got = video.next();
    REQUIRE(got.type() == CV_8UC1);
    REQUIRE(got.size() == f.size());
    CHECK(cv::norm(got, f, cv::NORM_L1) / static_cast<double>(f.total()) < 3.0); // JPEG: a few gray levels
  }
  CHECK_THROWS_AS(video.next(), Error);
}

TEST_CASE("video: bad input is one line, never a crash", "[features][klt]")
{
  const PlaneScene scene;
  test::TempDir dir;
  CHECK_THROWS_AS(VideoFrames(""), Error);
  CHECK_THROWS_AS(VideoFrames(dir.file("missing.avi")), Error);
  CHECK_THROWS_AS(VideoFrames(dir.file("none%04d.png")), Error);
  const std::string junk = dir.write("junk.avi", "this is not a movie");
  CHECK_THROWS_AS(VideoFrames(junk), Error);
  // A frame of another size than the camera's names its frame.
  const std::vector<MotionSample> log = sidewaysLog(3);
  const std::string what = test::errorOf([&] {
    trackSequence(scene.camera, YawRig(), log,
                  [&](std::size_t i) { return cv::Mat(i == 1 ? 240 : 480, i == 1 ? 320 : 640, CV_8UC1, cv::Scalar(9)); },
                  NoiseModel());
  });
  CHECK(what.find("frame 1") != std::string::npos);
  CHECK(what.find("320x240") != std::string::npos);
}

namespace {

// Two textured planes: a near one (Z = 1 m in the first camera) over u <= kEdgeU of the first image,
// in front of a far one (Z = 2 m); the camera steps 5 mm sideways per frame. Each image is the two
// textures warped by their homographies and composited by the near plane's mask (anti-aliased).
struct TwoPlanes {
  static constexpr double kEdgeU = 320;
  PlaneScene near_plane, far_plane;
  cv::Mat near_texture, far_texture;
  TwoPlanes()
  {
    near_plane.depth = 1.0;
    far_plane.depth = 2.0;
    near_texture = near_plane.texture(31);
    far_texture = far_plane.texture(37);
  }
  static vpHomogeneousMatrix pose(int k) { return vpHomogeneousMatrix(-0.005 * k, 0.0, 0.0, 0.0, 0.0, 0.0); }
  cv::Mat frame(int k) const
  {
    cv::Mat mask(480, 640, CV_32F, cv::Scalar(0));
    mask(cv::Rect(0, 0, static_cast<int>(kEdgeU) + 1, 480)).setTo(1.0);
    cv::Mat wn, wf, wm;
    cv::warpPerspective(near_texture, wn, cv::Mat(near_plane.homography(pose(k))), mask.size(), cv::INTER_CUBIC,
                        cv::BORDER_REFLECT);
    cv::warpPerspective(far_texture, wf, cv::Mat(far_plane.homography(pose(k))), mask.size(), cv::INTER_CUBIC,
                        cv::BORDER_REFLECT);
    cv::warpPerspective(mask, wm, cv::Mat(near_plane.homography(pose(k))), mask.size(), cv::INTER_LINEAR,
                        cv::BORDER_REPLICATE);
    cv::Mat fn, ff, out;
    wn.convertTo(fn, CV_32F);
    wf.convertTo(ff, CV_32F);
    cv::Mat composed = fn.mul(wm) + ff.mul(1.0 - wm);
    composed.convertTo(out, CV_8U);
    return out;
  }
  /* How far (px) a track is from moving as one point of either plane: for each plane, the largest
     distance of an observation from its first observation carried by that plane's motion; the
     smaller of the two. */
  double slide(const Track &t) const
  {
    double best = 1e9;
    for (const PlaneScene *p : {&near_plane, &far_plane}) {
      const Observation &o0 = t.observations.front();
      const vpHomogeneousMatrix c0 = pose(static_cast<int>(o0.frame)).inverse();
      double worst = 0;
      for (const Observation &o : t.observations) {
        const Eigen::Vector2d q = p->map(pose(static_cast<int>(o.frame)) * c0, o0.u, o0.v);
        worst = std::max(worst, std::hypot(o.u - q.x(), o.v - q.y()));
      }
      best = std::min(best, worst);
    }
    return best;
  }
};

} // namespace

TEST_CASE("klt: a corner on an occlusion edge (T-junction) is cut by its appearance, corners on a plane are kept",
          "[features][klt]")
{
  constexpr int kFrames = 16;
  // A track of one static point stays this close to its plane's motion: measured 0.72 px for a corner
  // 9 px from the edge whose 21 px LK window takes in a column of the other plane (the NCC hardly
  // sees it; the Lucas-Kanade alignment is pulled by it).
  constexpr double kOnePointPx = 1.0;
  constexpr double kSlidPx = 2.0;     // a T-junction slides 1.5 px per frame: this much is no tracker noise
  constexpr double kNearEdgePx = 3;   // a corner this close to the edge in its first frame is on the boundary
  constexpr double kOnPlanePx = 15;   // and this far from it, on one plane (the LK window's half is 10 px)
  const TwoPlanes scene;
  std::vector<cv::Mat> frames;
  for (int k = 0; k < kFrames; ++k)
    frames.push_back(scene.frame(k));
  const std::vector<MotionSample> log = sidewaysLog(kFrames);
  const auto run = [&](double min_ncc) {
    KltOptions o;
    o.min_ncc = min_ncc;
    return trackSequence(scene.near_plane.camera, YawRig(), log, [&](std::size_t i) { return frames[i]; },
                         NoiseModel(), o);
  };
  const auto edgeDistance = [&](const Track &t) { // in the first camera, px
    const Observation &o0 = t.observations.front();
    return std::abs(o0.u - TwoPlanes::kEdgeU - 0.005 * 600 / 1.0 * static_cast<double>(o0.frame));
  };
  // Without the appearance check the scene has tracks that are not one point: corners on the edge.
  const SequenceTracks unchecked = run(0.0);
  double worst_unchecked = 0;
  int on_edge_unchecked = 0;
  for (const Track &t : unchecked.tracks) {
    worst_unchecked = std::max(worst_unchecked, scene.slide(t));
    on_edge_unchecked += edgeDistance(t) < kNearEdgePx && t.observations.size() == kFrames ? 1 : 0;
  }
  CHECK(unchecked.totals.lost_appearance == 0);
  CHECK(worst_unchecked > kSlidPx);
  CHECK(on_edge_unchecked >= 1);
  // With it (the default): every track left is one point of one plane, the edge's corners are cut,
  // and the corners on either plane are kept through every frame.
  const SequenceTracks checked = run(KltOptions().min_ncc);
  CHECK(checked.totals.lost_appearance >= 1);
  int whole_on_plane = 0, whole_on_edge = 0;
  double worst = 0;
  for (const Track &t : checked.tracks) {
    worst = std::max(worst, scene.slide(t));
    const bool whole = t.observations.size() == kFrames;
    whole_on_plane += whole && edgeDistance(t) > kOnPlanePx ? 1 : 0;
    whole_on_edge += whole && edgeDistance(t) < kNearEdgePx ? 1 : 0;
  }
  CHECK(worst < kOnePointPx);
  CHECK(whole_on_edge == 0);
  int whole_on_plane_unchecked = 0;
  for (const Track &t : unchecked.tracks)
    whole_on_plane_unchecked += t.observations.size() == kFrames && edgeDistance(t) > kOnPlanePx ? 1 : 0;
  CHECK(whole_on_plane >= 100);
  CHECK(whole_on_plane >= whole_on_plane_unchecked - 5); // the check hardly touches corners on a plane
}

TEST_CASE("klt: a track that jumps along its epipolar line is split into two features", "[features][klt]")
{
  constexpr int kFrames = 8, kJumpFrame = 4;
  constexpr double kJumpPx = 6;      // along the parallax (as if nearer): inside the epipolar band
  constexpr double kStepTolPx = 3.5; // a step this far from the plane's motion is a jump
  const PlaneScene scene;
  const cv::Mat first = scene.texture(13);
  const cv::Rect region(220, 140, 200, 200);
  std::vector<cv::Mat> frames;
  for (int k = 0; k < kFrames; ++k) {
    cv::Mat f = scene.warp(first, vpHomogeneousMatrix(-0.005 * k, 0.0, 0.0, 0.0, 0.0, 0.0));
    if (k >= kJumpFrame) { // from here the region's content sits kJumpPx further left
      const cv::Mat shifted = f(region + cv::Point(static_cast<int>(kJumpPx), 0)).clone();
      shifted.copyTo(f(region));
    }
    frames.push_back(f);
  }
  const std::vector<MotionSample> log = sidewaysLog(kFrames);
  const auto run = [&](double jump_sigmas) {
    KltOptions o;
    o.jump_sigmas = jump_sigmas;
    return trackSequence(scene.camera, YawRig(), log, [&](std::size_t i) { return frames[i]; }, NoiseModel(), o);
  };
  // The largest step of any track away from the plane's motion.
  const auto worstStep = [&](const SequenceTracks &s) {
    double worst = 0;
    for (const Track &t : s.tracks)
      for (std::size_t j = 1; j < t.observations.size(); ++j) {
        const Observation &a = t.observations[j - 1], &b = t.observations[j];
        const vpHomogeneousMatrix bMa = vpHomogeneousMatrix(-0.005 * static_cast<double>(b.frame), 0, 0, 0, 0, 0) *
                                        vpHomogeneousMatrix(-0.005 * static_cast<double>(a.frame), 0, 0, 0, 0, 0).inverse();
        const Eigen::Vector2d q = scene.map(bMa, a.u, a.v);
        worst = std::max(worst, std::hypot(b.u - q.x(), b.v - q.y()));
      }
    return worst;
  };
  const SequenceTracks unsplit = run(0.0);
  CHECK(unsplit.totals.split_jump == 0);
  CHECK(worstStep(unsplit) > kJumpPx - 1); // the epipolar band lets the jumps through
  const SequenceTracks split = run(KltOptions().jump_sigmas);
  CHECK(split.totals.split_jump >= 10);
  CHECK(worstStep(split) < kStepTolPx);
  // The features that jumped go on under new ids: about as many tracks reach the last frame.
  const auto reachingEnd = [&](const SequenceTracks &s) {
    int n = 0;
    for (const Track &t : s.tracks)
      n += t.observations.back().frame == kFrames - 1 ? 1 : 0;
    return n;
  };
  CHECK(reachingEnd(split) >= reachingEnd(unsplit) - 5);
}

namespace {

/* A gray image with texture (a JPEG of it has entropy-coded data well past its first 1000 bytes). */
cv::Mat texturedImage(int width, int height)
{
  cv::Mat img(height, width, CV_8UC1);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(0, 255);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      img.at<unsigned char>(y, x) = static_cast<unsigned char>((x / 8 + y / 8) % 2 ? level(rng) / 4 : 200);
  return img;
}

std::string bytesOf(const std::vector<unsigned char> &b, std::size_t n) { return std::string(b.begin(), b.begin() + n); }

/* What the calls in `f` write to C's stderr (file descriptor 2), captured in a file. */
std::string stderrOf(const std::function<void()> &f)
{
  test::TempDir dir;
  const std::string log = dir.file("stderr.txt");
  std::fflush(stderr);
  const int saved = ::dup(STDERR_FILENO);
  std::FILE *capture = std::fopen(log.c_str(), "w");
  REQUIRE(capture != nullptr);
  ::dup2(::fileno(capture), STDERR_FILENO);
  try {
    f();
  } catch (...) {
    std::fflush(stderr);
    ::dup2(saved, STDERR_FILENO);
    ::close(saved);
    std::fclose(capture);
    throw;
  }
  std::fflush(stderr);
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  std::fclose(capture);
  return test::slurp(log);
}

/* What the calls in `f` print: on C's stderr (file descriptor 2, captured in a file), then on
   std::cout. */
std::string printedBy(const std::function<void()> &f)
{
  std::ostringstream out;
  std::streambuf *const cout = std::cout.rdbuf(out.rdbuf());
  const std::string err = stderrOf(f);
  std::cout.rdbuf(cout);
  return err + out.str();
}

} // namespace

TEST_CASE("images: a truncated or damaged JPEG is refused like a truncated PNG", "[features][image]")
{
  test::TempDir dir;
  const cv::Mat img = texturedImage(320, 240);
  std::vector<unsigned char> jpeg;
  REQUIRE(cv::imencode(".jpg", img, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90}));
  REQUIRE(jpeg.size() > 5000);
  REQUIRE(jpeg[jpeg.size() - 2] == 0xFF);
  REQUIRE(jpeg[jpeg.size() - 1] == 0xD9);
  // Whole, and with a trailer after its end-of-image marker (as some cameras write): read.
  constexpr double kJpegMeanError = 10.0; // gray levels: the JPEG's loss at quality 90 on this texture
  const std::string whole = dir.write("whole.jpg", bytesOf(jpeg, jpeg.size()));
  const cv::Mat got = readGrayImage(whole);
  REQUIRE(got.size() == img.size());
  CHECK(cv::norm(got, img, cv::NORM_L1) / static_cast<double>(img.total()) < kJpegMeanError);
  CHECK(readGrayImage(dir.write("trailer.jpg", bytesOf(jpeg, jpeg.size()) + std::string(64, '\0'))).size() ==
        img.size());
  // Its first 1000 bytes (libjpeg decodes them to gray without an error), all but its last byte or
  // its end-of-image marker, its headers only: refused, naming the file.
  for (const std::size_t keep : {std::size_t(1000), jpeg.size() - 1, jpeg.size() - 2, std::size_t(300), std::size_t(4)}) {
    const std::string cut = dir.write("cut.jpg", bytesOf(jpeg, keep));
    const std::string what = test::errorOf([&] { readGrayImage(cut); });
    CHECK(what.rfind(cut + ": cannot read image (", 0) == 0);
    CHECK(what.find("truncated JPEG") != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
  }
  // A segment whose length is 0, image data before the frame header: damaged.
  std::vector<unsigned char> bad = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x00, 0xFF, 0xD9};
  CHECK(test::errorOf([&] { readGrayImage(dir.write("zero.jpg", bytesOf(bad, bad.size()))); }).find("damaged JPEG") !=
        std::string::npos);
  bad = {0xFF, 0xD8, 0xFF, 0xDA, 0x00, 0x02, 0x12, 0x34, 0xFF, 0xD9};
  CHECK(test::errorOf([&] { readGrayImage(dir.write("noframe.jpg", bytesOf(bad, bad.size()))); })
            .find("before its frame header") != std::string::npos);
  // A progressive JPEG (several scans, tables between them) is whole too.
  std::vector<unsigned char> progressive;
  REQUIRE(cv::imencode(".jpg", img, progressive, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  CHECK(readGrayImage(dir.write("progressive.jpg", bytesOf(progressive, progressive.size()))).size() == img.size());
  const std::string cut = dir.write("progressive_cut.jpg", bytesOf(progressive, progressive.size() / 2));
  CHECK(test::errorOf([&] { readGrayImage(cut); }).find("truncated JPEG") != std::string::npos);
  // The other formats' decoders refuse a truncated file themselves (formats.md promises it for all).
  for (const std::string ext : {".png", ".pgm", ".bmp", ".tif"}) {
    std::vector<unsigned char> encoded;
    REQUIRE(cv::imencode(ext, img, encoded));
    for (const std::size_t keep : {encoded.size() / 2, encoded.size() - 1}) {
      const std::string file = dir.write("cut" + ext, bytesOf(encoded, keep));
      CHECK(test::errorOf([&] { readGrayImage(file); }).rfind(file + ": cannot read image (", 0) == 0);
    }
  }
}

TEST_CASE("video: a numbered sequence starts at its lowest number and has no gap", "[features][klt]")
{
  test::TempDir dir;
  const cv::Mat img = texturedImage(64, 48);
  char name[32];
  for (const int k : {3, 4, 5, 7}) {
    std::snprintf(name, sizeof name, "f%04d.png", k);
    cv::Mat frame = img + cv::Scalar(k);
    REQUIRE(cv::imwrite(dir.file(name), frame));
  }
  REQUIRE(cv::imwrite(dir.file("f00012.png"), img)); // not a name %04d gives: not part of it
  const SequencePattern pattern(dir.file("f%04d.png"));
  CHECK(pattern.filesPresent() ==
        std::vector<std::string>{dir.file("f0003.png"), dir.file("f0004.png"), dir.file("f0005.png"), dir.file("f0007.png")});
  VideoFrames seq(dir.file("f%04d.png"));
  for (const int k : {3, 4, 5}) {
    const cv::Mat got = seq.next();
    REQUIRE(got.size() == img.size());
    CHECK(cv::norm(got, img + cv::Scalar(k), cv::NORM_INF) == 0);
  }
  // f0006.png is missing and f0007.png exists: an error naming the missing file, not f0007 as frame 4.
  const std::string gap = test::errorOf([&] { seq.next(); });
  CHECK(gap.rfind(dir.file("f0006.png") + ": missing from the numbered image sequence", 0) == 0);
  CHECK(gap.find("goes on at " + dir.file("f0007.png")) != std::string::npos);
  CHECK(seq.framesRead() == 3);
  // After the last file: the end.
  std::filesystem::remove(dir.file("f0007.png"));
  VideoFrames shorter(dir.file("f%04d.png"));
  for (int k = 0; k < 3; ++k)
    shorter.next();
  CHECK(test::errorOf([&] { shorter.next(); }).find("ended after 3 frames") != std::string::npos);
  // A damaged frame is refused, naming it.
  std::vector<unsigned char> jpeg;
  REQUIRE(cv::imencode(".jpg", img, jpeg));
  for (const int k : {0, 1})
    REQUIRE(cv::imwrite(dir.file("j" + std::to_string(k) + ".jpg"), img));
  dir.write("j2.jpg", std::string(jpeg.begin(), jpeg.begin() + static_cast<long>(jpeg.size() / 2)));
  VideoFrames jpegs(dir.file("j%d.jpg"));
  jpegs.next();
  jpegs.next();
  CHECK(test::errorOf([&] { jpegs.next(); }).rfind(dir.file("j2.jpg") + ": cannot read image (a truncated JPEG", 0) == 0);
}

TEST_CASE("video: patterns are checked, folders and bad movies are one line", "[features][klt]")
{
  test::TempDir dir;
  CHECK(SequencePattern::isPattern("frames/f%04d.png"));
  CHECK_FALSE(SequencePattern::isPattern("100%/movie.avi"));
  CHECK(SequencePattern("a/f%04d.png").file(7) == "a/f0007.png");
  CHECK(SequencePattern("a/f%04d.png").file(123456) == "a/f123456.png");
  CHECK(SequencePattern("f%d.png").file(12) == "f12.png");
  CHECK(SequencePattern("f%%_%09d.png").file(5) == "f%_000000005.png");
  // libstdc++'s std::regex once built from %999999999d ran out of NFA states: now a plain refusal.
  for (const auto &bad_says : std::vector<std::pair<std::string, std::string>>{
           {"x_%999999999d.png", "'%999999999d' is not %d or %0Nd with N from 1 to 9"},
           {"x_%010d.png", "'%010d' is not"},
           {"x_%4d.png", "'%4d' is not"},
           {"x_%s.png", "'%s' is not"},
           {"x_%", "'%' is not"},
           {"x_%04d_%d.png", "more than one %d or %0Nd"},
           {"x_%%.png", "holds no %d or %0Nd"}}) {
    const std::string &bad = bad_says.first; // (not a structured binding: C++17 lambdas cannot capture one)
    const std::string &says = bad_says.second;
    const std::string what = test::errorOf([&] { VideoFrames video(dir.file(bad)); });
    CHECK(what.rfind(dir.file(bad) + ": not a numbered image sequence: ", 0) == 0);
    CHECK(what.find(says) != std::string::npos);
  }
  CHECK(test::errorOf([&] { VideoFrames video(dir.file("none_%04d.png")); }).find("no file of this numbered image sequence exists") !=
        std::string::npos);
  // A folder: what it is and what is expected.
  const std::string folder = test::errorOf([&] { VideoFrames video(dir.path.string()); });
  CHECK(folder.find("is a folder, not a video file") != std::string::npos);
  CHECK(folder.find("frame_%04d.png") != std::string::npos);
  // A movie FFmpeg cannot read, and one whose frames are damaged: errors, and nothing on stderr
  // (FFmpeg's own complaints are silenced).
  const std::vector<unsigned char> riff = {'R', 'I', 'F', 'F', 0x10, 0, 0, 0, 'A', 'V', 'I', ' ', 'L', 'I', 'S', 'T'};
  const std::string junk = dir.write("junk.avi", bytesOf(riff, riff.size()) + "not a movie at all");
  std::string printed = printedBy([&] { CHECK_THROWS_AS(VideoFrames(junk), Error); });
  CHECK(printed.empty());
  const std::string movie = dir.file("plane.avi");
  const cv::Mat img = texturedImage(160, 120);
  {
    cv::VideoWriter writer(movie, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, img.size(), false);
    REQUIRE(writer.isOpened());
    for (int k = 0; k < 6; ++k)
      writer.write(img);
  }
  std::string bytes = test::slurp(movie);
  for (std::size_t i = bytes.size() / 3; i < bytes.size() * 2 / 3; i += 7) // damage the middle frames
    bytes[i] = static_cast<char>(bytes[i] ^ 0x5A);
  const std::string damaged = dir.write("damaged.avi", bytes);
  const std::string cut = dir.write("cut.avi", bytes.substr(0, bytes.size() / 2));
  for (const std::string &file : {damaged, cut}) {
    printed = printedBy([&] {
      try {
        VideoFrames video(file);
        for (int k = 0; k < 6; ++k)
          video.next();
      } catch (const Error &e) {
        CHECK(std::string(e.what()).find('\n') == std::string::npos);
      }
    });
    CHECK(printed.empty()); // (ViSP printed "Warning: Unable to decode image N" on std::cout)
  }
}
