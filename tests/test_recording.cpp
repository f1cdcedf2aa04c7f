// Tests of the recordings a user brings (yawdepth/io/recording.h): TUM, EuRoC, timestamped yawdepth
// CSV and ViSP pose files; timestamped images; the time alignment.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>
#include <yawdepth/error.h>
#include <yawdepth/io/recording.h>

#include "file_support.h"

using namespace yawdepth;
using namespace yawdepth::test;
namespace fs = std::filesystem;

namespace {

constexpr double kExact = 1e-12;        // what a reader must reproduce of a printed 17-digit number
constexpr double kPrinted = 1e-9;       // numbers printed with %.12g here
const std::string kFranka = std::string(YAWDEPTH_TEST_DATA_DIR) + "/franka-eye-in-hand";

/* A smooth 6-DoF trajectory of the body in a ROS-like world (x forward, z up): the truth. */
struct Trajectory {
  Eigen::Vector3d position(double t) const
  {
    return Eigen::Vector3d(0.4 * t + 0.05 * std::sin(2.0 * t), 0.3 * std::sin(0.7 * t), 0.02 * std::cos(1.3 * t));
  }
  Eigen::Matrix3d rotation(double t) const
  {
    return (Eigen::AngleAxisd(0.5 * std::sin(0.9 * t), Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(0.1 * std::sin(1.7 * t), Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(0.05 * std::cos(2.1 * t), Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
  }
};

std::string num(double v)
{
  char b[64];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

/* The TUM text of the trajectory sampled at `rate` Hz from t0 over `duration` s. */
std::string tumText(const Trajectory &tr, double t0, double rate, double duration)
{
  std::string s = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  for (int i = 0; i <= static_cast<int>(std::round(duration * rate)); ++i) {
    const double t = t0 + i / rate;
    const Eigen::Vector3d p = tr.position(t - t0);
    const Eigen::Quaterniond q(tr.rotation(t - t0));
    s += num(t) + " " + num(p.x()) + " " + num(p.y()) + " " + num(p.z()) + " " + num(q.x()) + " " + num(q.y()) + " " +
         num(q.z()) + " " + num(q.w()) + "\n";
  }
  return s;
}

double rotationError(const Eigen::Matrix3d &A, const Eigen::Matrix3d &B)
{
  return Eigen::AngleAxisd(A.transpose() * B).angle();
}

/* The message of `f`'s yawdepth::Error, checked to be one line. */
template <class F> std::string oneLineError(F f)
{
  const std::string m = errorOf(f);
  CHECK(m.find('\n') == std::string::npos);
  return m;
}

void requireContains(const std::string &text, const std::string &words)
{
  INFO("message: " << text);
  CHECK(text.find(words) != std::string::npos);
}

} // namespace

TEST_CASE("interpolateMotion: ends, slerp midpoint, shorter way round")
{
  MotionSample a = MotionSample::fromPose(0, vpHomogeneousMatrix(0, 0, 0, 0, 0, 0));
  MotionSample b = MotionSample::fromPose(1, vpHomogeneousMatrix(1, 2, 3, 0, 0, 1.0));
  const MotionSample m = interpolateMotion(a, b, 0.5);
  CHECK(m.position().isApprox(Eigen::Vector3d(0.5, 1, 1.5), kExact));
  CHECK(m.theta_u.isApprox(Eigen::Vector3d(0, 0, 0.5), kExact));
  CHECK(interpolateMotion(a, b, 1.0).rotation().isApprox(b.rotation(), kExact));
  CHECK(interpolateMotion(a, b, 0.0).rotation().isApprox(a.rotation(), kExact));
  // Planar: a heading and a yaw across +-pi go the short way.
  MotionSample p, q;
  p.heading = M_PI - 0.1;
  q.heading = -M_PI + 0.1;
  p.yaw = -M_PI + 0.05;
  q.yaw = M_PI - 0.05;
  const MotionSample r = interpolateMotion(p, q, 0.5);
  CHECK(std::abs(wrapAngle(r.heading - M_PI)) < kExact);
  CHECK(std::abs(wrapAngle(r.yaw - M_PI)) < kExact);
  CHECK_THROWS_AS(interpolateMotion(a, p, 0.5), Error);
}

TEST_CASE("TUM trajectory: read, detected, quaternions to theta-u")
{
  TempDir dir;
  const Trajectory tr;
  const std::string path = dir.write("groundtruth.txt", tumText(tr, 1305031102.0, 100.0, 2.0));
  CHECK(detectMotionFormat(path) == MotionFormat::Tum);
  const MotionLog log = readMotionFile({path});
  REQUIRE(log.timestamped);
  REQUIRE(log.samples.size() == 201);
  REQUIRE(log.times.size() == 201);
  CHECK(std::abs(log.times[100] - (1305031102.0 + 1.0)) < 1e-6);
  for (std::size_t i : {std::size_t(0), std::size_t(57), std::size_t(200)}) {
    const double t = log.times[i] - 1305031102.0;
    CHECK(log.samples[i].six_dof);
    CHECK((log.samples[i].position() - tr.position(t)).norm() < 1e-9);
    CHECK(rotationError(log.samples[i].rotation(), tr.rotation(t)) < 1e-9);
  }
}

TEST_CASE("EuRoC CSV: units in the header, nanoseconds, extra columns")
{
  TempDir dir;
  const Trajectory tr;
  std::string s = "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
                  "v_RS_R_x [m s^-1]\n";
  const long t0 = 1403636579763555584L;
  for (int i = 0; i < 50; ++i) {
    const long ns = t0 + i * 5000000L; // 200 Hz
    const double t = i * 0.005;
    const Eigen::Vector3d p = tr.position(t);
    const Eigen::Quaterniond q(tr.rotation(t));
    s += std::to_string(ns) + "," + num(p.x()) + "," + num(p.y()) + "," + num(p.z()) + "," + num(q.w()) + "," +
         num(q.x()) + "," + num(q.y()) + "," + num(q.z()) + ",0.1\n";
  }
  const std::string path = dir.write("data.csv", s);
  CHECK(detectMotionFormat(path) == MotionFormat::Euroc);
  const MotionLog log = readMotionFile({path});
  REQUIRE(log.samples.size() == 50);
  CHECK(std::abs((log.times[10] - log.times[0]) - 0.05) < 1e-6);
  CHECK(std::abs(log.times[0] - 1403636579.763555584) < 1e-6);
  CHECK((log.samples[10].position() - tr.position(0.05)).norm() < 1e-9);
  CHECK(rotationError(log.samples[10].rotation(), tr.rotation(0.05)) < 1e-9);
}

TEST_CASE("yawdepth CSV with t: planar, theta-u and quaternion forms; frame-based unchanged")
{
  TempDir dir;
  const std::string planar = dir.write("p.csv", "t,x,y,z,heading,yaw\n0.0,0,0,0,0,0.1\n0.01,0.002,0,0,0.001,0.1\n");
  CHECK(detectMotionFormat(planar) == MotionFormat::Yawdepth);
  const MotionLog p = readMotionFile({planar});
  CHECK(p.timestamped);
  CHECK_FALSE(p.samples[1].six_dof);
  CHECK(p.samples[1].heading == 0.001);

  const std::string quat = dir.write("q.csv", "t,tx,ty,tz,qx,qy,qz,qw\n0,1,2,3,0,0,0,1\n0.5,1,2,3,0,0,0.70710678,0.70710678\n");
  const MotionLog q = readMotionFile({quat});
  CHECK(q.samples[1].six_dof);
  CHECK(q.samples[1].theta_u.isApprox(Eigen::Vector3d(0, 0, M_PI / 2), 1e-8));

  const std::string framed = dir.write("f.csv", "frame,t,tx,ty,tz,tux,tuy,tuz\n0,5,0,0,0,0,0,0\n1,6,0,0,0.01,0,0,0\n");
  const MotionLog f = readMotionFile({framed});
  CHECK_FALSE(f.timestamped);
  CHECK(f.times.empty()); // `t` of a frame-based log is informational
  CHECK(f.samples[1].frame == 1);
}

TEST_CASE("Motion files: bad input is one line naming the file and line")
{
  TempDir dir;
  // A timestamp that goes back.
  const std::string back = dir.write("back.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n");
  requireContains(oneLineError([&] { readMotionFile({back}); }), back + ":3: time 1.5 s goes back");
  const std::string repeated = dir.write("rep.csv", "t,x,y,z,heading\n1,0,0,0,0\n1,0,0,0,0\n");
  requireContains(oneLineError([&] { readMotionFile({repeated}, MotionFormat::Auto, 0.0); }), ":3: time 1 s is repeated");
  // A quaternion of norm 0, and one that is not unit.
  const std::string zero = dir.write("zero.txt", "1 0 0 0 0 0 0 0\n");
  requireContains(oneLineError([&] { readMotionFile({zero}, MotionFormat::Tum); }), zero + ":1: the quaternion");
  requireContains(oneLineError([&] { readMotionFile({zero}, MotionFormat::Tum); }), "norm 0");
  const std::string big = dir.write("big.csv", "t,tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,0,1.01\n");
  requireContains(oneLineError([&] { readMotionFile({big}); }), big + ":2: the quaternion");
  // Slightly off unit (printed digits) is normalised.
  const std::string ok = dir.write("ok.csv", "t,tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,0,1.0004\n");
  CHECK(readMotionFile({ok}).samples[0].theta_u.norm() < kExact);
  // TUM with a missing field, and text in a number.
  const std::string seven = dir.write("seven.txt", "# c\n1 0 0 0 0 0 1\n");
  requireContains(oneLineError([&] { readMotionFile({seven}, MotionFormat::Tum); }), seven + ":2: expected 8 fields");
  const std::string text = dir.write("text.txt", "1 0 0 zero 0 0 0 1\n");
  requireContains(oneLineError([&] { readMotionFile({text}, MotionFormat::Tum); }), "tz: 'zero' is not a number");
  // Both a theta-u and a quaternion; an image column in a timestamped log; neither frame nor t.
  const std::string both = dir.write("both.csv", "t,tx,ty,tz,tux,tuy,tuz,qx,qy,qz,qw\n0,0,0,0,0,0,0,0,0,0,1\n");
  requireContains(oneLineError([&] { readMotionFile({both}); }), "give one");
  const std::string img = dir.write("img.csv", "t,tx,ty,tz,tux,tuy,tuz,image\n0,0,0,0,0,0,0,a.png\n");
  requireContains(oneLineError([&] { readMotionFile({img}); }), "--images");
  const std::string none = dir.write("none.csv", "x,y,z,heading,yaw\n0,0,0,0,0\n");
  requireContains(oneLineError([&] { readMotionFile({none}); }), "missing column 'frame'");
  // EuRoC without a quaternion.
  const std::string noq = dir.write("noq.csv", "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m]\n1,0,0,0\n");
  requireContains(oneLineError([&] { readMotionFile({noq}); }), "missing quaternion columns");
}

TEST_CASE("Timestamped images: folders named in s and ns, rgb.txt, EuRoC data.csv")
{
  TempDir dir;
  fs::create_directories(dir.path / "rgb");
  for (const char *n : {"1305031102.211214.png", "1305031102.175304.png", "1305031102.243211.png"})
    dir.write(std::string("rgb/") + n, "x");
  dir.write("rgb/notes.txt", "not an image");
  ImageList a = readImageList(dir.file("rgb"));
  REQUIRE(a.paths.size() == 3);
  CHECK(fs::path(a.paths[0]).filename() == "1305031102.175304.png");
  CHECK(std::abs(a.times[0] - 1305031102.175304) < 1e-6);
  CHECK(a.times[1] > a.times[0]);

  fs::create_directories(dir.path / "cam0" / "data");
  dir.write("cam0/data/1403636579763555584.png", "x");
  dir.write("cam0/data/1403636579813555456.png", "x");
  const ImageList b = readImageList(dir.file("cam0/data"));
  REQUIRE(b.paths.size() == 2);
  CHECK(std::abs((b.times[1] - b.times[0]) - 0.049999872) < 1e-6);
  const std::string list = dir.write("cam0/data.csv", "#timestamp [ns],filename\n1403636579763555584,1403636579763555584.png\n"
                                                      "1403636579813555456,1403636579813555456.png\n");
  const ImageList c = readImageList(list);
  REQUIRE(c.paths.size() == 2);
  CHECK(fs::path(c.paths[1]).filename() == "1403636579813555456.png");
  CHECK(c.times == b.times);

  const std::string rgb = dir.write("rgb.txt", "# color images\n# timestamp filename\n1305031102.175304 rgb/1305031102.175304.png\n"
                                               "1305031102.211214 rgb/1305031102.211214.png\n");
  const ImageList d = readImageList(rgb);
  REQUIRE(d.paths.size() == 2);
  CHECK(fs::exists(d.paths[1]));

  // Bad input: a name that is not a timestamp; a list going back; a missing image.
  dir.write("rgb/frame_0001.png", "x");
  requireContains(oneLineError([&] { readImageList(dir.file("rgb")); }), "frame_0001.png: the image name is not a timestamp");
  CHECK(readImageList(dir.file("rgb"), false).paths.size() == 4); // untimed: natural name order
  const std::string backwards = dir.write("back.txt", "2 rgb/1305031102.211214.png\n1 rgb/1305031102.175304.png\n");
  requireContains(oneLineError([&] { readImageList(backwards); }), backwards + ":2: time 1 s goes back");
  const std::string missing = dir.write("missing.txt", "2 rgb/nope.png\n");
  requireContains(oneLineError([&] { readImageList(missing); }), missing + ":1: rgb/nope.png: no such image file");
}

TEST_CASE("Time alignment: poses at 200 Hz, images at 30 Hz with a latency, interpolated on SE(3)")
{
  TempDir dir;
  const Trajectory tr;
  const double t0 = 1700000000.0, offset = 0.031;
  const std::string path = dir.write("traj.txt", tumText(tr, t0, 200.0, 3.0));
  const MotionLog log = readMotionFile({path});
  ImageList images;
  for (int i = 0; i < 100; ++i) { // camera clock: from 0.21 s before the log starts to 0.09 s after it ends
    images.times.push_back(t0 - 0.21 - offset + i / 30.0);
    images.paths.push_back("img" + std::to_string(i) + ".png");
  }
  TimeAlignmentOptions o;
  o.time_offset = offset;
  const TimeAlignment a = alignMotionToImages(log, images, o, path, "images");
  CHECK(a.images == 100);
  CHECK(a.before == 7); // motion-clock times -0.21 + i / 30: i = 0..6 before 0
  CHECK(a.after == 3);  // i = 97..99 after 3 s
  CHECK(a.matched == 90);
  CHECK(a.in_gap == 0);
  constexpr double kRateHz = 0.02; // times near 1.7e9 s resolve 0.24 us: 5e-5 of a 5 ms step
  CHECK(std::abs(a.motion_rate_hz - 200.0) < kRateHz);
  CHECK(std::abs(a.image_rate_hz - 30.0) < kRateHz);
  REQUIRE(a.log.samples.size() == a.matched);
  REQUIRE(a.log.images.size() == a.matched);
  // Linear interpolation between samples 5 ms apart: second-order error, well below 0.1 mm and 0.1 mrad.
  constexpr double kInterpPosition = 1e-5, kInterpRotation = 1e-4;
  double worst_p = 0, worst_r = 0;
  for (std::size_t k = 0; k < a.log.samples.size(); ++k) {
    const MotionSample &s = a.log.samples[k];
    const double t = images.times[static_cast<std::size_t>(s.frame)] + offset - t0;
    CHECK(a.log.images[k] == images.paths[static_cast<std::size_t>(s.frame)]);
    CHECK(std::abs(a.log.times[k] - (t + t0)) < 1e-6);
    worst_p = std::max(worst_p, (s.position() - tr.position(t)).norm());
    worst_r = std::max(worst_r, rotationError(s.rotation(), tr.rotation(t)));
  }
  CHECK(worst_p < kInterpPosition);
  CHECK(worst_r < kInterpRotation);
  CHECK(a.log.samples.front().frame == 7); // frames are the images' places in the list
  CHECK_FALSE(a.summary().empty());

  SECTION("a gap in the log skips the images in it")
  {
    MotionLog gappy = log;
    // Drop the samples between 1.0 s and 1.5 s.
    MotionLog g;
    g.timestamped = true;
    for (std::size_t i = 0; i < gappy.samples.size(); ++i)
      if (gappy.times[i] - t0 <= 1.0 || gappy.times[i] - t0 >= 1.5) {
        g.samples.push_back(gappy.samples[i]);
        g.times.push_back(gappy.times[i]);
      }
    const TimeAlignment b = alignMotionToImages(g, images, o, path, "images");
    CHECK(b.in_gap == 15); // 0.5 s at 30 Hz
    CHECK(b.matched + b.in_gap == a.matched);
  }
  SECTION("spans that do not overlap: both spans, and seconds against nanoseconds")
  {
    ImageList ns = images;
    for (double &t : ns.times)
      t *= 1e9;
    const std::string m = oneLineError([&] { alignMotionToImages(log, ns, o, path, "imgs"); });
    requireContains(m, "imgs: the images span [");
    requireContains(m, "and the poses of " + path + " span [");
    requireContains(m, "nanoseconds against seconds");
  }
}

TEST_CASE("ViSP pose files: the franka recording's files, paired with its images in name order")
{
  std::vector<std::string> poses, images;
  for (int i = 1; i <= 8; ++i) {
    poses.push_back(kFranka + "/franka_pose_rPe_" + std::to_string(i) + ".yaml");
    images.push_back(kFranka + "/franka_image-" + std::to_string(i) + ".png");
  }
  const vpPoseVector p1 = readVispPoseFile(poses[0]);
  CHECK(std::abs(p1[0] - 0.335091) < kPrinted);
  CHECK(std::abs(p1[3] - -3.01226) < kPrinted);
  CHECK(detectMotionFormat(poses[0]) == MotionFormat::Visp);

  TempDir dir;
  fs::create_directories(dir.path / "img");
  for (int i = 1; i <= 8; ++i)
    fs::copy_file(images[static_cast<std::size_t>(i - 1)], dir.path / "img" / ("franka_image-" + std::to_string(i) + ".png"));
  MotionInput in;
  in.motion = {poses[7], poses[0], poses[1], poses[2], poses[3], poses[4], poses[5], poses[6]}; // shell order is not kept
  in.images = dir.file("img");
  const LoadedMotion m = loadMotion(in, std::nullopt, std::nullopt);
  REQUIRE(m.log.samples.size() == 8);
  REQUIRE(m.log.images.size() == 8);
  CHECK(fs::path(m.log.images[7]).filename() == "franka_image-8.png");
  CHECK(m.log.samples[0].position().isApprox(Eigen::Vector3d(p1[0], p1[1], p1[2]), kExact));
  // The same poses as the motion log the repository once converted from them by hand.
  const MotionLog by_hand = readMotionCsv(kFranka + "/motion.csv");
  REQUIRE(by_hand.samples.size() == 8);
  for (std::size_t i = 0; i < 8; ++i) {
    CHECK((m.log.samples[i].position() - by_hand.samples[i].position()).norm() < kPrinted);
    CHECK(rotationError(m.log.samples[i].rotation(), by_hand.samples[i].rotation()) < kPrinted);
  }
  in.motion.pop_back();
  requireContains(oneLineError([&] { loadMotion(in, std::nullopt, std::nullopt); }), "8 images for 7 ViSP pose files");
  const std::string bad = dir.write("bad.yaml", "rows: 3\ncols: 1\ndata:\n  - [1]\n  - [2]\n  - [3]\n");
  requireContains(oneLineError([&] { readVispPoseFile(bad); }), "6x1");
}

TEST_CASE("loadMotion: a timestamped log needs --images; a frame-based one refuses them; import round trip")
{
  TempDir dir;
  const Trajectory tr;
  const std::string traj = dir.write("traj.txt", tumText(tr, 100.0, 100.0, 1.0));
  fs::create_directories(dir.path / "rgb");
  for (int i = 0; i < 20; ++i)
  {
    char name[64];
    std::snprintf(name, sizeof name, "rgb/%.6f.png", 100.01 + i * 0.05);
    dir.write(name, "x");
  }
  MotionInput in;
  in.motion = {traj};
  requireContains(oneLineError([&] { loadMotion(in, std::nullopt, std::nullopt); }), "needs --images");
  in.images = dir.file("rgb");
  const LoadedMotion m = loadMotion(in, std::nullopt, 0.02);
  REQUIRE(m.alignment);
  CHECK(m.time_offset == 0.02); // the rig file's, without --time-offset
  CHECK(m.alignment->matched == 20);
  in.time_offset = -0.5;
  CHECK(loadMotion(in, std::nullopt, 0.02).alignment->before == 10); // --time-offset wins over the rig's

  // The aligned log written and read back as the frame-based form, with its t column.
  const std::string out = dir.file("motion.csv");
  writeMotionCsv(out, m.log);
  const MotionLog back = readMotionCsv(out);
  REQUIRE(back.samples.size() == m.log.samples.size());
  CHECK_FALSE(back.timestamped);
  for (std::size_t i = 0; i < back.samples.size(); ++i) {
    CHECK(back.samples[i].frame == m.log.samples[i].frame);
    CHECK((back.samples[i].position() - m.log.samples[i].position()).norm() < kExact);
    CHECK(fs::equivalent(back.images[i], m.log.images[i]));
  }
  MotionInput framed;
  framed.motion = {out};
  framed.images = dir.file("rgb");
  requireContains(oneLineError([&] { loadMotion(framed, std::nullopt, std::nullopt); }), "is frame-based");
}
