// yawdepth::report: the board metrics of measured points — block lengths and their quantiles, the
// plane, and a chessboard's pose in the world — on boards placed with a known pose and scale.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <yawdepth/report/board_report.h>
#include <yawdepth/report/cloud_report.h>
#include "file_support.h"

using namespace yawdepth;

namespace {

constexpr double kRoundOff = 1e-9; // m, rad: exact maths on metre-sized numbers

// A 9x6 chessboard of `square` at wMo, scaled by `scale`, each corner moved by N(0, sigma) per axis,
// as estimates at frame 0 of a robot standing at the world's origin (so w_P = c_P).
std::vector<std::pair<long, PointEstimate>> placedBoard(const PatternSpec &p, const Eigen::Isometry3d &wMo, double scale,
                                                        double sigma, std::uint64_t seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<std::pair<long, PointEstimate>> rows;
  for (long id = 0; id < p.cols * p.rows; ++id) {
    PointEstimate e;
    e.status = Status::Ok;
    e.frame = 0;
    const Eigen::Vector3d o(static_cast<double>(id % p.cols) * p.square, static_cast<double>(id / p.cols) * p.square, 0);
    e.c_P = wMo * (scale * o) + sigma * Eigen::Vector3d(g(rng), g(rng), g(rng));
    rows.emplace_back(id, e);
  }
  return rows;
}

} // namespace

TEST_CASE("board report: a chessboard's pose in the world, its scale, block-length quantiles", "[report]")
{
  const PatternSpec p = PatternSpec::parse("chessboard:9x6:0.0236");
  const YawRig rig(Eigen::Vector3d::Zero());
  std::vector<MotionSample> motion(1); // frame 0 at the world's origin: wMc = identity
  Eigen::Isometry3d wMo = Eigen::Isometry3d::Identity();
  wMo.linear() = Eigen::AngleAxisd(2.0, Eigen::Vector3d(0.7, -0.7, 0.1).normalized()).toRotationMatrix();
  wMo.translation() = Eigen::Vector3d(0.5365, 0.1239, 0.4156);

  // Exact points: the pose and scale back to round-off, every block nominal.
  const BoardMetrics exact = boardMetrics(p, rig, motion, placedBoard(p, wMo, 1.0, 0.0, 1));
  REQUIRE(exact.has_board_pose);
  CHECK((exact.w_t_o - wMo.translation()).norm() < kRoundOff);
  CHECK(Eigen::AngleAxisd(exact.w_R_o.transpose() * wMo.linear()).angle() < kRoundOff);
  CHECK(exact.board_scale == Approx(1.0).margin(kRoundOff));
  CHECK(exact.board_fit_rms < kRoundOff);
  CHECK(exact.quantile(0.5) == Approx(0.0236).margin(kRoundOff));
  CHECK(exact.fractionWithin(1e-6) == 1.0);
  CHECK(exact.max_plane_distance < kRoundOff);
  CHECK(formatBoardMetrics(exact).find("board pose in the world:") != std::string::npos);

  // A board 0.6 % large: the similarity fit's scale says so, the rigid fit keeps the centroid.
  const BoardMetrics large = boardMetrics(p, rig, motion, placedBoard(p, wMo, 1.006, 0.0, 1));
  CHECK(large.board_scale == Approx(1.006).epsilon(1e-9));
  CHECK(large.quantile(0.05) == Approx(1.006 * 0.0236).epsilon(1e-9));
  CHECK(large.fractionWithin(1e-4) == 0.0);
  CHECK(large.fractionWithin(2e-4) == 1.0);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const BoardPoint &q : large.points)
    centroid += q.w_P;
  centroid /= static_cast<double>(large.points.size());
  const Eigen::Vector3d nominal_centre(4 * 0.0236, 2.5 * 0.0236, 0);
  CHECK((large.w_R_o * nominal_centre + large.w_t_o - centroid).norm() < kRoundOff);

  // Noisy corners (0.2 mm): the pose within a few noise sigmas, the quantiles ordered.
  constexpr double kSigma = 2e-4;
  const BoardMetrics noisy = boardMetrics(p, rig, motion, placedBoard(p, wMo, 1.0, kSigma, 7));
  CHECK((noisy.w_t_o - wMo.translation()).norm() < 4 * kSigma);
  CHECK(noisy.board_fit_rms == Approx(kSigma * std::sqrt(3.0)).epsilon(0.25));
  CHECK(noisy.quantile(0.05) < noisy.quantile(0.5));
  CHECK(noisy.quantile(0.5) < noisy.quantile(0.95));
  CHECK(noisy.quantile(0.0) == Approx(BoardMetrics::stats(noisy.horizontal).x() < BoardMetrics::stats(noisy.vertical).x()
                                          ? BoardMetrics::stats(noisy.horizontal).x()
                                          : BoardMetrics::stats(noisy.vertical).x()));

  // An AprilTag board has no chessboard pose.
  const PatternSpec tags = PatternSpec::parse("apriltag:36h11:0.05");
  std::vector<std::pair<long, PointEstimate>> tag_rows;
  for (long id : {1, 2, 3, 4}) {
    PointEstimate e;
    e.status = Status::Ok;
    e.c_P = Eigen::Vector3d((id == 2 || id == 3) ? 0.05 : 0.0, id >= 3 ? 0.05 : 0.0, 1.0);
    tag_rows.emplace_back(id, e);
  }
  const BoardMetrics tm = boardMetrics(tags, rig, motion, tag_rows);
  CHECK_FALSE(tm.has_board_pose);
  CHECK(tm.quantile(0.5) == Approx(0.05).margin(kRoundOff));
}

// ---------------------------------------------------------------------------------------------
// The cloud report (cloud_report.h)

namespace {

// A gray 640x480 image and three points in front of a camera at the world's origin (cMw identity):
// near (0.5 m) on the optical axis, far (2 m) to the right, and one behind the camera.
CloudReportInput threePoints()
{
  CloudReportInput in;
  in.camera = CameraModel::brown(500, 500, 320, 240, {0, 0, 0, 0}, 640, 480);
  in.image = cv::Mat(480, 640, CV_8UC1, cv::Scalar(128));
  in.points = {{1, Eigen::Vector3d(0, 0, 0.5), 0.01}, {2, Eigen::Vector3d(0.8, 0, 2.0), 0.05},
               {3, Eigen::Vector3d(0, 0, -1.0), 0.01}};
  in.title = "three points";
  in.summary = "ok: 3\n";
  return in;
}

} // namespace

TEST_CASE("cloud report: points over the image coloured by depth, seen from above, written together", "[report]")
{
  const CloudReportInput in = threePoints();
  const cv::Mat overlay = cloudOverlay(in);
  REQUIRE(overlay.type() == CV_8UC3);
  CHECK(overlay.cols == 640);
  CHECK(overlay.rows == 480 + 44);
  // The near point at the principal point, the far one at u = 320 + 500 x 0.8 / 2 = 520: the near end
  // of the scale is TURBO's dark blue-violet, the far end its dark red; the gray image elsewhere.
  const cv::Vec3b near = overlay.at<cv::Vec3b>(240, 320), far = overlay.at<cv::Vec3b>(240, 520);
  CHECK(near[0] > near[2]);                  // blue over red
  CHECK(near[0] + near[1] + near[2] < 200);  // dark
  CHECK(far[2] > far[0] + 60);               // red
  const cv::Vec3b plain = overlay.at<cv::Vec3b>(100, 100);
  CHECK(plain[0] == plain[2]); // untouched gray
  const cv::Mat top = cloudTopView(in);
  CHECK(top.cols == 900);
  CHECK(top.rows == 700);
  CHECK(cv::countNonZero(top.reshape(1) != 255) > 1000); // something drawn

  test::TempDir dir;
  const std::string out = dir.file("rep");
  writeCloudReport(out, in);
  for (const std::string &f : cloudReportFiles(out)) {
    INFO(f);
    CHECK(std::filesystem::file_size(f) > 0);
  }
  CHECK(cv::imread(cloudReportFiles(out)[1]).size() == overlay.size());
  CHECK(test::slurp(cloudReportFiles(out)[0]) == "three points\n\nok: 3\n");
}

TEST_CASE("cloud report: an image of another size than the camera's is refused, nothing written", "[report]")
{
  CloudReportInput in = threePoints();
  in.image = cv::Mat(240, 320, CV_8UC1, cv::Scalar(128));
  CHECK_THROWS_AS(cloudOverlay(in), Error);
  test::TempDir dir;
  const std::string out = dir.file("rep");
  CHECK_THROWS_AS(writeCloudReport(out, in), Error);
  for (const std::string &f : cloudReportFiles(out))
    CHECK_FALSE(std::filesystem::exists(f));
  in.image = cv::Mat();
  CHECK_THROWS_AS(cloudOverlay(in), Error);
}
