// The ROS 1 bag reader, its decoders and importBag() on bags written by real rosbag
// (tests/data/bags/writers/make_ros1_bags.py), checked against the values they were written with
// (tests/data/bags/ros1_truth.json) and the formulas of the writer.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>
#include <yaml-cpp/yaml.h>
#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/import.h>
#include <yawdepth/bag/messages.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

#include "file_support.h"

using namespace yawdepth;
using namespace yawdepth::test;
namespace fs = std::filesystem;

namespace {

const std::string kDir = std::string(YAWDEPTH_TEST_DATA_DIR) + "/bags";
const std::string kRobot = kDir + "/robot.bag";
const std::string kEncodings = kDir + "/encodings.bag";
const std::string kCameraCases = kDir + "/camera_cases.bag";
constexpr double T0 = 1700000000.0;

const YAML::Node &truth()
{
  static const YAML::Node t = YAML::LoadFile(kDir + "/ros1_truth.json");
  return t;
}

bool contains(const std::string &s, const std::string &part) { return s.find(part) != std::string::npos; }

Eigen::Quaterniond rpy(double r, double p, double y)
{
  return Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(p, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(r, Eigen::Vector3d::UnitX());
}

// The writer's motion: base_link in odom, odom in world (tau = t - T0).
Eigen::Isometry3d odomPose(double tau)
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.translation() = Eigen::Vector3d(0.5 * tau, 0.1 * std::sin(2 * tau), 0);
  M.linear() = rpy(0.02 * std::sin(5 * tau), 0, 0.3 * tau + 0.1 * std::sin(3 * tau)).toRotationMatrix();
  return M;
}
Eigen::Isometry3d worldOdom(double tau)
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.translation() = Eigen::Vector3d(1.0 + 0.02 * tau, 2.0, 0.1);
  M.linear() = rpy(0, 0, 0.1).toRotationMatrix();
  return M;
}
double panJoint(double tau) { return 0.2 * std::sin(M_PI * tau); }

Eigen::Isometry3d transformOf(const YAML::Node &t, const char *tr = "translation", const char *rot = "rotation")
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.translation() = Eigen::Vector3d(t[tr][0].as<double>(), t[tr][1].as<double>(), t[tr][2].as<double>());
  M.linear() = Eigen::Quaterniond(t[rot][3].as<double>(), t[rot][0].as<double>(), t[rot][1].as<double>(),
                                  t[rot][2].as<double>())
                   .toRotationMatrix();
  return M;
}

// bMc of the static chain base_link -> pan_link -> camera_link -> camera_optical_frame.
Eigen::Isometry3d staticChain()
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  for (const YAML::Node &t : truth()["static"])
    M = M * transformOf(t);
  return M;
}

Eigen::Isometry3d isoOf(const vpHomogeneousMatrix &H)
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      M.linear()(r, c) = H[r][c];
    M.translation()(r) = H[r][3];
  }
  return M;
}

double rotationError(const Eigen::Matrix3d &A, const Eigen::Matrix3d &B)
{
  return Eigen::AngleAxisd(A.transpose() * B).angle();
}

std::vector<std::uint8_t> bytesOf(const BagMessage &m) { return std::vector<std::uint8_t>(m.data, m.data + m.size); }

// Every message of `topic`, copied.
std::vector<std::pair<std::int64_t, std::vector<std::uint8_t>>> messages(BagReader &bag, const std::string &topic)
{
  std::vector<std::pair<std::int64_t, std::vector<std::uint8_t>>> out;
  BagReadOptions ro;
  ro.topics = {topic};
  bag.read(ro, [&](const BagMessage &m) {
    out.emplace_back(m.log_time, bytesOf(m));
    return true;
  });
  return out;
}

BagMessage messageOf(const BagTopic *topic, const std::pair<std::int64_t, std::vector<std::uint8_t>> &m)
{
  BagMessage b;
  b.topic = topic;
  b.log_time = m.first;
  b.data = m.second.data();
  b.size = m.second.size();
  return b;
}

std::int64_t ns(const YAML::Node &n) { return n.as<std::int64_t>(); }

// An imported image's stamp (s), from its name.
double stampOf(const std::string &image) { return double(std::stoll(fs::path(image).stem().string())) * 1e-9; }

// The t column of a motion.csv (readMotionCsv() keeps frames and ignores it).
std::vector<double> timesOf(const std::string &csv)
{
  std::ifstream f(csv);
  std::string line;
  std::getline(f, line);
  REQUIRE(line.rfind("frame,t,tx,ty,tz,tux,tuy,tuz,yaw,image", 0) == 0);
  std::vector<double> t;
  while (std::getline(f, line))
    t.push_back(std::stod(line.substr(line.find(',') + 1)));
  return t;
}

BagImportOptions robotOptions(const std::string &out)
{
  BagImportOptions o;
  o.bag = kRobot;
  o.out_dir = out;
  o.image_topic = "/camera/image_raw";
  o.odom_topic = "/odom";
  return o;
}

std::string copyPrefix(const TempDir &dir, const std::string &name, const std::string &from, std::size_t n)
{
  std::string s = slurp(from);
  return dir.write(name, s.substr(0, std::min(n, s.size())));
}

// The pixel pattern of the writer's small images.
int patternValue(int x, int y, int c, int k) { return (x * 13 + y * 7 + 40 * c + 9 * k) % 256; }

} // namespace

TEST_CASE("ROS 1 reader: format, topics with types and counts, time order", "[bag]")
{
  const auto formats = readableBagFormats();
  REQUIRE(std::find(formats.begin(), formats.end(), BagFormat::Ros1) != formats.end());
  auto bag = openBag(kRobot);
  CHECK(bag->format() == BagFormat::Ros1);
  CHECK(bag->path() == kRobot);
  const std::map<std::string, std::pair<std::string, std::uint64_t>> expected = {
      {"/camera/camera_info", {"sensor_msgs/CameraInfo", 22}},
      {"/camera/image_raw", {"sensor_msgs/Image", 22}},
      {"/joint_states", {"sensor_msgs/JointState", 41}},
      {"/odom", {"nav_msgs/Odometry", 71}},
      {"/pose", {"geometry_msgs/PoseStamped", 50}},
      {"/pose_cov", {"geometry_msgs/PoseWithCovarianceStamped", 50}},
      {"/tf", {"tf2_msgs/TFMessage", 50}},
      {"/tf_static", {"tf2_msgs/TFMessage", 1}}};
  REQUIRE(bag->topics().size() == expected.size());
  for (const BagTopic &t : bag->topics()) {
    INFO(t.name);
    REQUIRE(expected.count(t.name) == 1);
    CHECK(t.type == expected.at(t.name).first);
    CHECK(t.messages == expected.at(t.name).second);
    CHECK(t.encoding == BagEncoding::Ros1);
  }
  CHECK(bag->topic("/odom") != nullptr);
  CHECK(bag->topic("/nope") == nullptr);
  CHECK(contains(bag->topicList(), "/camera/image_raw (sensor_msgs/Image, 22 messages)"));

  std::size_t n = 0;
  std::int64_t last = INT64_MIN;
  bool ordered = true;
  bag->read({}, [&](const BagMessage &m) {
    ordered = ordered && m.log_time >= last;
    last = m.log_time;
    ++n;
    return true;
  });
  CHECK(n == 307);
  CHECK(ordered);

  // A topic and a time window; stopping early.
  BagReadOptions ro;
  ro.topics = {"/camera/image_raw", "/nope"};
  ro.start = std::int64_t((T0 + 0.2) * 1e9);
  ro.end = std::int64_t((T0 + 0.5) * 1e9);
  std::vector<std::int64_t> times;
  bag->read(ro, [&](const BagMessage &m) {
    CHECK(m.topic->name == "/camera/image_raw");
    times.push_back(m.log_time);
    return true;
  });
  // logged 40 ms after the stamps T0 - 0.03 + 0.05 k: log times T0 + 0.01 + 0.05 k, k = 4..9
  REQUIRE(times.size() == 6);
  CHECK(times.front() == ns(truth()["images"][4]["log_ns"]));
  std::size_t seen = 0;
  bag->read({}, [&](const BagMessage &) { return ++seen < 3; });
  CHECK(seen == 3);
}

TEST_CASE("ROS 1 decoders: every field as written", "[bag]")
{
  auto bag = openBag(kRobot);
  const YAML::Node &T = truth();
  SECTION("images and camera_info")
  {
    const auto images = messages(*bag, "/camera/image_raw");
    REQUIRE(images.size() == T["images"].size());
    for (std::size_t k = 0; k < images.size(); ++k) {
      const ImageMessage im = decodeImage(messageOf(bag->topic("/camera/image_raw"), images[k]));
      const YAML::Node &t = T["images"][k];
      CHECK(images[k].first == ns(t["log_ns"]));
      CHECK(im.header.stamp == ns(t["stamp_ns"]));
      CHECK(std::abs(im.header.stamp + 40000000 - images[k].first) < 1000); // the 40 ms latency
      CHECK(im.header.frame_id == "camera_optical_frame");
      CHECK(im.width == 16);
      CHECK(im.height == 12);
      CHECK(im.encoding == "mono8");
      CHECK_FALSE(im.is_bigendian);
      CHECK(im.step == 16);
      REQUIRE(im.data.size() == 16 * 12);
      for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 16; ++x)
          REQUIRE(int(im.data[y * 16 + x]) == patternValue(x, y, 0, int(k)));
    }
    const auto infos = messages(*bag, "/camera/camera_info");
    REQUIRE(infos.size() == 22);
    const CameraInfoMessage ci = decodeCameraInfo(messageOf(bag->topic("/camera/camera_info"), infos[0]));
    const YAML::Node &t = T["camera_info"];
    CHECK(ci.header.stamp == ns(t["stamp_ns"]));
    CHECK(ci.header.frame_id == t["frame_id"].as<std::string>());
    CHECK(ci.width == 16);
    CHECK(ci.height == 12);
    CHECK(ci.distortion_model == "plumb_bob");
    REQUIRE(ci.D.size() == 5);
    for (int i = 0; i < 5; ++i)
      CHECK(ci.D[i] == t["D"][i].as<double>());
    for (int i = 0; i < 9; ++i) {
      CHECK(ci.K[i] == t["K"][i].as<double>());
      CHECK(ci.R[i] == t["R"][i].as<double>());
    }
    for (int i = 0; i < 12; ++i)
      CHECK(ci.P[i] == t["P"][i].as<double>());
    CHECK(ci.binning_x == 0);
    CHECK(ci.roi_width == 0);
    CHECK_FALSE(ci.roi_do_rectify);
  }
  SECTION("odometry, poses, TF, joints")
  {
    const auto odom = messages(*bag, "/odom");
    REQUIRE(odom.size() == T["odom"].size());
    for (std::size_t i = 0; i < odom.size(); ++i) {
      const OdometryMessage o = decodeOdometry(messageOf(bag->topic("/odom"), odom[i]));
      const YAML::Node &t = T["odom"][i];
      CHECK(o.header.stamp == ns(t["stamp_ns"]));
      CHECK(o.header.frame_id == "odom");
      CHECK(o.child_frame_id == "base_link");
      for (int k = 0; k < 3; ++k)
        CHECK(o.pose.position[k] == t["position"][k].as<double>());
      for (int k = 0; k < 4; ++k)
        CHECK(o.pose.orientation[k] == t["orientation"][k].as<double>());
      for (int k = 0; k < 36; ++k)
        CHECK(o.covariance[k] == (k % 7 == 0 ? 0.001 * (k + 1) : 0.0));
    }
    const auto pose = messages(*bag, "/pose");
    const auto pose_cov = messages(*bag, "/pose_cov");
    REQUIRE(pose.size() == T["pose"].size());
    REQUIRE(pose_cov.size() == pose.size());
    for (std::size_t i = 0; i < pose.size(); ++i) {
      const YAML::Node &t = T["pose"][i];
      const PoseMessage p = decodePose(messageOf(bag->topic("/pose"), pose[i]));
      const PoseMessage pc = decodePose(messageOf(bag->topic("/pose_cov"), pose_cov[i]));
      for (const PoseMessage *x : {&p, &pc}) {
        CHECK(x->header.stamp == ns(t["stamp_ns"]));
        CHECK(x->header.frame_id == "world");
        for (int k = 0; k < 3; ++k)
          CHECK(x->pose.position[k] == t["position"][k].as<double>());
        for (int k = 0; k < 4; ++k)
          CHECK(x->pose.orientation[k] == t["orientation"][k].as<double>());
      }
      for (int k = 0; k < 36; ++k) {
        CHECK(p.covariance[k] == 0.0);
        CHECK(pc.covariance[k] == (k % 7 == 0 ? 0.01 : 0.0));
      }
    }
    const auto tf = messages(*bag, "/tf");
    REQUIRE(tf.size() == 50);
    for (std::size_t i = 0; i < tf.size(); ++i) {
      const TfMessage m = decodeTf(messageOf(bag->topic("/tf"), tf[i]));
      REQUIRE(m.transforms.size() == 2);
      const double tau = double(m.transforms[0].header.stamp) * 1e-9 - T0;
      CHECK(tau == Approx(i / 50.0).margin(1e-6));
      CHECK(m.transforms[0].header.frame_id == "world");
      CHECK(m.transforms[0].child_frame_id == "odom");
      CHECK(m.transforms[1].header.frame_id == "odom");
      CHECK(m.transforms[1].child_frame_id == "base_link");
      const Eigen::Isometry3d ob = odomPose(i / 50.0);
      for (int k = 0; k < 3; ++k)
        CHECK(m.transforms[1].translation[k] == Approx(ob.translation()(k)).margin(1e-12));
      const Eigen::Quaterniond q(ob.linear());
      const Eigen::Quaterniond got(m.transforms[1].rotation[3], m.transforms[1].rotation[0], m.transforms[1].rotation[1],
                                   m.transforms[1].rotation[2]);
      CHECK(got.angularDistance(q) < 1e-9);
    }
    const auto st = messages(*bag, "/tf_static");
    REQUIRE(st.size() == 1);
    const TfMessage s = decodeTf(messageOf(bag->topic("/tf_static"), st[0]));
    REQUIRE(s.transforms.size() == 3);
    for (std::size_t i = 0; i < 3; ++i) {
      const YAML::Node &t = T["static"][i];
      CHECK(s.transforms[i].header.frame_id == t["parent"].as<std::string>());
      CHECK(s.transforms[i].child_frame_id == t["child"].as<std::string>());
      for (int k = 0; k < 3; ++k)
        CHECK(s.transforms[i].translation[k] == t["translation"][k].as<double>());
      for (int k = 0; k < 4; ++k)
        CHECK(s.transforms[i].rotation[k] == t["rotation"][k].as<double>());
    }
    const auto js = messages(*bag, "/joint_states");
    REQUIRE(js.size() == T["joint_states"].size());
    for (std::size_t i = 0; i < js.size(); ++i) {
      const JointStateMessage j = decodeJointState(messageOf(bag->topic("/joint_states"), js[i]));
      const YAML::Node &t = T["joint_states"][i];
      CHECK(j.header.stamp == ns(t["stamp_ns"]));
      REQUIRE(j.name == std::vector<std::string>{"wheel", "pan_joint"});
      REQUIRE(j.position.size() == 2);
      REQUIRE(j.velocity.size() == 2);
      CHECK(j.effort.empty());
      for (int k = 0; k < 2; ++k) {
        CHECK(j.position[k] == t["position"][k].as<double>());
        CHECK(j.velocity[k] == t["velocity"][k].as<double>());
      }
    }
  }
  SECTION("every encoding of encodings.bag")
  {
    auto eb = openBag(kEncodings);
    for (const char *name : {"mono8", "rgb8", "bgr8", "mono16"}) {
      const std::string topic = std::string("/cam/") + name + "/image_raw";
      const auto ms = messages(*eb, topic);
      REQUIRE(ms.size() == 4);
      for (std::size_t k = 0; k < 4; ++k) {
        const ImageMessage im = decodeImage(messageOf(eb->topic(topic), ms[k]));
        const YAML::Node &t = truth()["encodings"][name][k];
        CHECK(im.header.stamp == ns(t["stamp_ns"]));
        CHECK(im.encoding == name);
        CHECK(im.step == t["step"].as<std::uint32_t>());
        for (int b = 0; b < 8; ++b)
          CHECK(int(im.data[b]) == t["first_bytes"][b].as<int>());
      }
    }
    for (const char *name : {"jpeg", "png"}) {
      const std::string topic = std::string("/cam/") + name + "/image_raw/compressed";
      const auto ms = messages(*eb, topic);
      REQUIRE(ms.size() == 4);
      for (std::size_t k = 0; k < 4; ++k) {
        const CompressedImageMessage cm = decodeCompressedImage(messageOf(eb->topic(topic), ms[k]));
        const YAML::Node &t = truth()["encodings"][name][k];
        CHECK(cm.header.stamp == ns(t["stamp_ns"]));
        CHECK(cm.format == name);
        CHECK(cm.data.size() == t["bytes"].as<std::size_t>());
        for (int b = 0; b < 8; ++b)
          CHECK(int(cm.data[b]) == t["first_bytes"][b].as<int>());
      }
    }
  }
}

TEST_CASE("ROS 1 decoders: a wrong type, a short message, a corrupt length: Error, never a read past the end",
          "[bag]")
{
  auto bag = openBag(kRobot);
  const auto pose = messages(*bag, "/pose");
  const BagMessage m = messageOf(bag->topic("/pose"), pose[0]);
  CHECK(errorOf([&] { decodeOdometry(m); }) == "/pose: is geometry_msgs/PoseStamped, not nav_msgs/Odometry");
  CHECK(contains(errorOf([&] { decodeImage(m); }), "not sensor_msgs/Image"));
  for (const std::string &topic : std::vector<std::string>{"/camera/image_raw", "/camera/camera_info", "/odom", "/pose", "/pose_cov", "/tf",
                                   "/tf_static", "/joint_states"}) {
    INFO(topic);
    const auto ms = messages(*bag, topic);
    const auto full = ms[0];
    const BagTopic *tp = bag->topic(topic);
    auto decode = [&](const BagMessage &x) {
      if (tp->type == "sensor_msgs/Image")
        decodeImage(x);
      else if (tp->type == "sensor_msgs/CameraInfo")
        decodeCameraInfo(x);
      else if (tp->type == "nav_msgs/Odometry")
        decodeOdometry(x);
      else if (tp->type == "tf2_msgs/TFMessage")
        decodeTf(x);
      else if (tp->type == "sensor_msgs/JointState")
        decodeJointState(x);
      else
        decodePose(x);
    };
    // Every shorter length: an Error naming the topic, never a read past the end (ASan checks that).
    for (std::size_t n = 0; n < full.second.size(); n += 1 + full.second.size() / 97) {
      std::vector<std::uint8_t> cut(full.second.begin(), full.second.begin() + std::ptrdiff_t(n));
      BagMessage x = messageOf(tp, {full.first, cut});
      x.data = cut.empty() ? nullptr : cut.data();
      const std::string e = errorOf([&] { decode(x); });
      CHECK(e.rfind(topic + ": message at t = ", 0) == 0);
    }
    // A length field (the frame_id's, after seq and stamp; a TFMessage's array count) made huge.
    std::vector<std::uint8_t> big = full.second;
    const std::size_t at = tp->type == "tf2_msgs/TFMessage" ? 0 : 12;
    big[at] = big[at + 1] = big[at + 2] = 0xff;
    big[at + 3] = 0x7f;
    CHECK(contains(errorOf([&] { decode(messageOf(tp, {full.first, big})); }), "length field beyond the message"));
  }
}

TEST_CASE("ROS 1 reader: truncated, unindexed and corrupt bags are an Error, never a crash", "[bag]")
{
  TempDir dir;
  const std::string whole = slurp(kRobot);
  for (std::size_t n : {std::size_t(0), std::size_t(5), std::size_t(13), std::size_t(20), std::size_t(4096),
                        std::size_t(4200), whole.size() / 2, whole.size() - 1000, whole.size() - 10,
                        whole.size() - 1}) {
    INFO("first " << n << " bytes");
    const std::string p = copyPrefix(dir, "cut" + std::to_string(n) + ".bag", kRobot, n);
    const std::string e = errorOf([&] {
      auto b = openBag(p);
      b->read({}, [](const BagMessage &) { return true; });
    });
    CHECK(e.rfind(p + ": ", 0) == 0);
    if (n >= 4200)
      CHECK(contains(e, "truncated or corrupt"));
    if (n >= 4200) // how far it got
      CHECK(contains(e, std::to_string(n)));
  }
  // index_pos = 0: a recording that did not finish.
  {
    std::string s = whole;
    const std::size_t at = s.find("index_pos=");
    REQUIRE(at != std::string::npos);
    std::memset(&s[at + 10], 0, 8);
    const std::string p = dir.write("unindexed.bag", s);
    CHECK(errorOf([&] { openBag(p); }) == p + ": unindexed bag (its recording did not finish: rosbag reindex it)");
  }
  // Two mutants that make rosbag_storage alone memcpy 2 GB past its chunk buffer (AddressSanitizer:
  // heap-buffer-overflow in Bag::readMessageDataIntoStream, rosbag/bag.h:414): refused by the check.
  for (int seed : {56, 82}) {
    std::mt19937 rng(seed);
    std::string s = whole;
    for (int k = 0; k < 1 + int(rng() % 4); ++k) { // (the count drawn again at each turn, as they were made)
      const char value = char(rng() % 3 == 0 ? 0xff : rng() % 256);
      s[rng() % s.size()] = value;
    }
    const std::string p = dir.write("overflow" + std::to_string(seed) + ".bag", s);
    CHECK_THAT(errorOf([&] { openBag(p); }), Catch::Contains(p + ": truncated or corrupt: a message runs past its chunk"));
  }
  // Random damage: each mutant opens and reads, or fails with an Error.
  std::mt19937 rng(7);
  std::size_t errors = 0, fine = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string s = whole;
    const int flips = 1 + int(rng() % 4);
    for (int f = 0; f < flips; ++f) {
      const std::size_t at = rng() % s.size();
      s[at] = char(rng() % 3 == 0 ? 0xff : rng() % 256);
    }
    const std::string p = dir.write("mutant.bag", s);
    try {
      auto b = openBag(p);
      b->read({}, [&](const BagMessage &m) {
        try {
          if (m.topic->type == "sensor_msgs/Image")
            decodeImage(m);
          else if (m.topic->type == "sensor_msgs/CameraInfo")
            decodeCameraInfo(m);
          else if (m.topic->type == "nav_msgs/Odometry")
            decodeOdometry(m);
          else if (m.topic->type == "tf2_msgs/TFMessage")
            decodeTf(m);
          else if (m.topic->type == "sensor_msgs/JointState")
            decodeJointState(m);
          else
            decodePose(m);
        } catch (const Error &) {
        }
        return true;
      });
      ++fine;
    } catch (const Error &e) {
      CHECK(std::string(e.what()).rfind(p + ": ", 0) == 0);
      ++errors;
    }
  }
  CHECK(errors + fine == 300);
  CHECK(errors > 0);
}

TEST_CASE("importBag: odometry at the image times, the mount from /tf_static, the camera from camera_info", "[bag]")
{
  TempDir dir;
  const std::string out = dir.file("out");
  const auto t0 = std::chrono::steady_clock::now();
  const BagImportResult r = importBag(robotOptions(out));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  WARN("import of robot.bag (22 images): " << seconds << " s");
  CHECK(r.images_read == 22);
  CHECK(r.images_kept == 22);
  CHECK(r.skipped_before == 1); // T0 - 0.03, before the first odometry
  CHECK(r.skipped_after == 1);  // T0 + 1.02, after the last (T0 + 0.99)
  CHECK(r.skipped_gap == 6);    // T0 + 0.52 ... 0.77, in the gap (0.50, 0.80)
  CHECK(r.images_matched == 14);
  CHECK(r.poses == 71);
  CHECK(r.image_first == Approx(T0 - 0.03).margin(1e-6));
  CHECK(r.image_last == Approx(T0 + 1.02).margin(1e-6));
  CHECK(r.motion_first == Approx(T0).margin(1e-6));
  CHECK(r.motion_last == Approx(T0 + 0.99).margin(1e-6));
  CHECK(r.warnings.empty());
  CHECK(contains(r.summary(), "/odom (nav_msgs/Odometry): 71 messages"));
  CHECK(contains(r.summary(), "14 matched"));
  CHECK(r.images_dir == out + "/images");

  // Only the matched images, named by their stamps, their pixels as sent.
  std::size_t files = 0;
  for (const auto &e : fs::directory_iterator(out + "/images")) {
    (void)e;
    ++files;
  }
  CHECK(files == 14);
  const MotionLog log = readMotionCsv(r.motion_path);
  REQUIRE(log.samples.size() == 14);
  REQUIRE(log.images.size() == 14);
  const std::vector<double> times = timesOf(r.motion_path);
  REQUIRE(times.size() == 14);
  double worst_t = 0, worst_r = 0;
  for (std::size_t i = 0; i < 14; ++i) {
    const std::string stem = fs::path(log.images[i]).stem().string();
    const std::int64_t stamp = std::stoll(stem);
    CHECK(times[i] == Approx(double(stamp) * 1e-9).margin(1e-6));
    const double tau = double(stamp) * 1e-9 - T0;
    const int k = int(std::lround((tau + 0.03) / 0.05));
    const cv::Mat img = cv::imread(log.images[i], cv::IMREAD_UNCHANGED);
    REQUIRE(img.type() == CV_8UC1);
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 16; ++x)
        REQUIRE(int(img.at<std::uint8_t>(y, x)) == patternValue(x, y, 0, k));
    const Eigen::Isometry3d want = odomPose(tau);
    const Eigen::Isometry3d got = isoOf(wMv(log.samples[i]));
    worst_t = std::max(worst_t, (got.translation() - want.translation()).norm());
    worst_r = std::max(worst_r, rotationError(got.linear(), want.linear()));
  }
  WARN("odometry at 100 Hz, at the image times: " << worst_t << " m, " << worst_r << " rad from the truth");
  CHECK(worst_t < 2e-5);
  CHECK(worst_r < 2e-5);

  const RigFile rig = readRigFile(r.rig_path);
  REQUIRE(rig.camera_pose);
  const Eigen::Isometry3d bMc = isoOf(vpHomogeneousMatrix(*rig.camera_pose));
  const Eigen::Isometry3d chain = staticChain();
  CHECK((bMc.translation() - chain.translation()).norm() < 1e-12);
  CHECK(rotationError(bMc.linear(), chain.linear()) < 1e-9);
  // REP 103's optical frame: z along base_link's x (forward), x along -y, y along -z.
  CHECK((bMc.linear().col(2) - Eigen::Vector3d(std::cos(0.05), 0, -std::sin(0.05))).norm() < 1e-9);

  const CameraModel cam = loadCameraFile(r.camera_path);
  const YAML::Node &ci = truth()["camera_info"];
  CHECK(cam.width() == 16);
  CHECK(cam.height() == 12);
  CHECK(cam.parameters().get_px() == ci["K"][0].as<double>());
  CHECK(cam.parameters().get_py() == ci["K"][4].as<double>());
  CHECK(cam.parameters().get_u0() == ci["K"][2].as<double>());
  CHECK(cam.parameters().get_v0() == ci["K"][5].as<double>());
  CHECK(cam.distortion() == CameraModel::Distortion::Brown);
  const std::vector<double> D = cam.brownCoefficients();
  REQUIRE(D.size() >= 5);
  for (int i = 0; i < 5; ++i)
    CHECK(D[i] == ci["D"][i].as<double>());

  // Again into the same folder: replaced whole, no staging folder left.
  const BagImportResult again = importBag(robotOptions(out));
  CHECK(again.images_matched == 14);
  for (const auto &e : fs::directory_iterator(out))
    CHECK(e.path().filename().string().rfind(".import-bag", 0) != 0);
}

TEST_CASE("importBag: --tf WORLD:BODY chained through /tf, --pose-topic, the pan joint as the yaw", "[bag]")
{
  TempDir dir;
  SECTION("--tf world:base_link")
  {
    BagImportOptions o = robotOptions(dir.file("tf"));
    o.odom_topic.clear();
    o.tf_world = "world";
    o.tf_body = "base_link";
    const BagImportResult r = importBag(o);
    CHECK(r.poses == 50);
    CHECK(r.skipped_before == 1);
    CHECK(r.skipped_after == 1);
    CHECK(r.skipped_gap == 0);
    CHECK(r.images_matched == 20);
    const MotionLog log = readMotionCsv(r.motion_path);
    REQUIRE(log.samples.size() == 20);
    double worst_t = 0, worst_r = 0;
    for (std::size_t i = 0; i < log.samples.size(); ++i) {
      const double tau = stampOf(log.images[i]) - T0;
      const Eigen::Isometry3d want = worldOdom(tau) * odomPose(tau);
      const Eigen::Isometry3d got = isoOf(wMv(log.samples[i]));
      worst_t = std::max(worst_t, (got.translation() - want.translation()).norm());
      worst_r = std::max(worst_r, rotationError(got.linear(), want.linear()));
    }
    WARN("/tf at 50 Hz, world -> odom -> base_link at the image times: " << worst_t << " m, " << worst_r
                                                                          << " rad from the truth");
    CHECK(worst_t < 1e-4);
    CHECK(worst_r < 1e-4);
  }
  SECTION("--pose-topic (PoseStamped and PoseWithCovarianceStamped) with the pan joint")
  {
    for (const char *topic : {"/pose", "/pose_cov"}) {
      BagImportOptions o = robotOptions(dir.file(std::string("pose") + (topic + 1)));
      o.odom_topic.clear();
      o.pose_topic = topic;
      o.joint_topic = "/joint_states";
      o.joint = "pan_joint";
      const BagImportResult r = importBag(o);
      CHECK(r.joint_readings == 41);
      CHECK(r.skipped_before == 1 + 2); // before the poses; T0 + 0.02, 0.07 before the joint's first (0.1)
      CHECK(r.skipped_after == 1 + 2);  // T0 + 0.92, 0.97 after the joint's last (0.9)
      CHECK(r.images_matched == 16);
      const MotionLog log = readMotionCsv(r.motion_path);
      REQUIRE(log.samples.size() == 16);
      CHECK(log.yaw_column);
      double worst_t = 0, worst_yaw = 0;
      for (std::size_t i = 0; i < log.samples.size(); ++i) {
        const double tau = stampOf(log.images[i]) - T0;
        const Eigen::Isometry3d want = worldOdom(tau) * odomPose(tau);
        worst_t = std::max(worst_t, (isoOf(wMv(log.samples[i])).translation() - want.translation()).norm());
        worst_yaw = std::max(worst_yaw, std::abs(log.samples[i].yaw - panJoint(tau)));
      }
      WARN(topic << " at 50 Hz: " << worst_t << " m; the pan joint at 50 Hz: " << worst_yaw << " rad from the truth");
      CHECK(worst_t < 1e-4);
      CHECK(worst_yaw < 2e-4);
      // The body is the root of the camera frame's /tf_static tree, base_link.
      const Eigen::Isometry3d bMc = isoOf(vpHomogeneousMatrix(*readRigFile(r.rig_path).camera_pose));
      CHECK((bMc.translation() - staticChain().translation()).norm() < 1e-12);
    }
  }
  SECTION("--camera-frame: the mount of another frame; the body itself")
  {
    BagImportOptions o = robotOptions(dir.file("cf"));
    o.camera_frame = "camera_link";
    Eigen::Isometry3d want = Eigen::Isometry3d::Identity();
    for (int i = 0; i < 2; ++i)
      want = want * transformOf(truth()["static"][i]);
    const Eigen::Isometry3d bMc = isoOf(vpHomogeneousMatrix(*readRigFile(importBag(o).rig_path).camera_pose));
    CHECK((bMc.translation() - want.translation()).norm() < 1e-12);
    CHECK(rotationError(bMc.linear(), want.linear()) < 1e-9);
    o.out_dir = dir.file("cf2");
    o.camera_frame = "base_link";
    const RigFile rig = readRigFile(importBag(o).rig_path);
    CHECK(isoOf(vpHomogeneousMatrix(*rig.camera_pose)).isApprox(Eigen::Isometry3d::Identity()));
  }
}

TEST_CASE("importBag: --every, --start, --duration, --time-offset", "[bag]")
{
  TempDir dir;
  BagImportOptions o = robotOptions(dir.file("w"));
  o.start = 0.2; // the bag's first message is /tf_static at T0
  o.duration = 0.5;
  BagImportResult r = importBag(o);
  // log times T0 + 0.01 + 0.05 k in [T0 + 0.2, T0 + 0.7]: k = 4..13
  CHECK(r.images_read == 10);
  CHECK(r.images_kept == 10);
  CHECK(r.image_first == Approx(T0 + 0.17).margin(1e-6));
  CHECK(r.image_last == Approx(T0 + 0.62).margin(1e-6));
  // /tf_static, recorded once at T0, is read over the whole bag: the mount is there.
  const Eigen::Isometry3d bMc = isoOf(vpHomogeneousMatrix(*readRigFile(r.rig_path).camera_pose));
  CHECK((bMc.translation() - staticChain().translation()).norm() < 1e-12);
  o.out_dir = dir.file("e");
  o.every = 3;
  r = importBag(o);
  CHECK(r.images_read == 10);
  CHECK(r.images_kept == 4); // k = 4, 7, 10, 13
  CHECK(r.image_last == Approx(T0 + 0.62).margin(1e-6));

  // An offset: the images' poses are those 0.1 s later on the motion clock.
  BagImportOptions off = robotOptions(dir.file("off"));
  off.time_offset = 0.1;
  r = importBag(off);
  const MotionLog log = readMotionCsv(r.motion_path);
  const std::vector<double> times = timesOf(r.motion_path);
  REQUIRE(times.size() == log.samples.size());
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const double stamp = stampOf(log.images[i]);
    CHECK(times[i] == Approx(stamp + 0.1).margin(1e-6));
    CHECK((isoOf(wMv(log.samples[i])).translation() - odomPose(stamp + 0.1 - T0).translation()).norm() < 2e-5);
  }
}

TEST_CASE("importBag: every encoding written as it came", "[bag]")
{
  TempDir dir;
  for (const char *name : {"mono8", "rgb8", "bgr8", "mono16", "jpeg", "png"}) {
    INFO(name);
    const bool comp = std::string(name) == "jpeg" || std::string(name) == "png";
    BagImportOptions o;
    o.bag = kEncodings;
    o.out_dir = dir.file(name);
    o.image_topic = std::string("/cam/") + name + (comp ? "/image_raw/compressed" : "/image_raw");
    o.odom_topic = "/odom";
    o.camera_info_topic = "/cam/camera_info";
    const BagImportResult r = importBag(o);
    REQUIRE(r.images_matched == 4);
    const MotionLog log = readMotionCsv(r.motion_path);
    for (std::size_t k = 0; k < 4; ++k) {
      const std::string &p = log.images[k];
      CHECK(fs::path(p).extension() == (std::string(name) == "jpeg" ? ".jpg" : ".png"));
      if (comp) {
        CHECK(fs::file_size(p) == truth()["encodings"][name][k]["bytes"].as<std::size_t>());
        continue;
      }
      const cv::Mat img = cv::imread(p, cv::IMREAD_UNCHANGED);
      REQUIRE(img.rows == 12);
      REQUIRE(img.cols == 16);
      for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 16; ++x) {
          if (std::string(name) == "mono8")
            REQUIRE(int(img.at<std::uint8_t>(y, x)) == patternValue(x, y, 0, int(k)));
          else if (std::string(name) == "mono16")
            REQUIRE(int(img.at<std::uint16_t>(y, x)) == ((patternValue(x, y, 0, int(k)) * 257 + 3) & 0xffff));
          else {
            // written as the channels 0, 1, 2 of the message; OpenCV's file is BGR
            const cv::Vec3b v = img.at<cv::Vec3b>(y, x);
            const bool rgb = std::string(name) == "rgb8";
            for (int c = 0; c < 3; ++c)
              REQUIRE(int(v[rgb ? 2 - c : c]) == patternValue(x, y, c, int(k)));
          }
        }
    }
  }
}

TEST_CASE("importBag: bad input, a one-line reason naming the bag, topic or frame, and nothing written", "[bag]")
{
  TempDir dir;
  const std::string out = dir.file("out");
  auto fails = [&](BagImportOptions o, const std::vector<std::string> &words) {
    o.out_dir = out;
    const std::string e = errorOf([&] { importBag(o); });
    for (const std::string &w : words)
      CHECK_THAT(e, Catch::Contains(w));
    CHECK(e.find('\n') == std::string::npos);
    CHECK_FALSE(fs::exists(out));
    return e;
  };
  BagImportOptions o = robotOptions(out);
  SECTION("options")
  {
    BagImportOptions x = o;
    x.odom_topic.clear();
    fails(x, {"one of --odom-topic, --pose-topic or --tf"});
    x = o;
    x.pose_topic = "/pose";
    fails(x, {"not --odom-topic and --pose-topic"});
    x = o;
    x.joint_topic = "/joint_states";
    fails(x, {"--joint-topic /joint_states needs --joint NAME"});
    x = o;
    x.every = 0;
    fails(x, {"--every 0"});
    x = o;
    x.max_pose_gap = 0;
    fails(x, {"max"});
  }
  SECTION("topics")
  {
    BagImportOptions x = o;
    x.image_topic = "/nope";
    fails(x, {kRobot + ": no topic /nope (--image-topic); the bag has: ", "/camera/image_raw (sensor_msgs/Image, 22 messages)",
              "/odom (nav_msgs/Odometry, 71 messages)"});
    x = o;
    x.odom_topic = "/pose";
    fails(x, {kRobot + ": /pose (--odom-topic) is geometry_msgs/PoseStamped, not nav_msgs/Odometry"});
    x = o;
    x.image_topic = "/odom";
    fails(x, {"/odom (--image-topic) is nav_msgs/Odometry, not sensor_msgs/Image or sensor_msgs/CompressedImage"});
    x = o;
    x.camera_info_topic = "/camera/info";
    fails(x, {"no topic /camera/info (--camera-info-topic)"});
    x = o;
    x.joint_topic = "/joint_states";
    x.joint = "tilt";
    fails(x, {"/joint_states has no joint tilt (joints: pan_joint, wheel)"});
    x = o;
    x.start = 5;
    fails(x, {"/camera/image_raw has no message in the window"});
  }
  SECTION("the default camera_info: the image topic's sibling (for .../compressed, the one before)")
  {
    BagImportOptions x = o;
    x.bag = kEncodings;
    x.image_topic = "/cam/jpeg/image_raw/compressed";
    fails(x, {kEncodings + ": no topic /cam/jpeg/camera_info (the image topic's camera_info; give --camera-info-topic)"});
    x.image_topic = "/cam/rgb8/image_raw";
    fails(x, {"no topic /cam/rgb8/camera_info"});
  }
  SECTION("frames")
  {
    BagImportOptions x = o;
    x.odom_topic.clear();
    x.tf_world = "world";
    x.tf_body = "nowhere";
    fails(x, {kRobot + ": --tf world:nowhere: no chain from world to nowhere in /tf and /tf_static (frames: ",
              "base_link, camera_link, camera_optical_frame, odom, pan_link, world"});
    x = o;
    x.camera_frame = "lidar";
    fails(x, {kRobot + ": /tf_static: no chain from base_link to the camera frame lidar (frames: ", "pan_link"});
  }
  SECTION("camera_info")
  {
    BagImportOptions x = o;
    x.bag = kCameraCases;
    x.image_topic = "/cam/image_raw";
    x.camera_info_topic = "/cam/big_info";
    fails(x, {"/cam/image_raw: the image at t = ", " s is 16 x 12 pixels, /cam/big_info says 20 x 15"});
    x.camera_info_topic = "/cam/fisheye_xyz_info";
    fails(x, {"/cam/fisheye_xyz_info: camera_info: distortion model 'fisheye_xyz'"});
    // Warned, not refused: a camera_info that changes; an equidistant camera.
    x.out_dir = dir.file("changes");
    x.camera_info_topic.clear();
    const BagImportResult r = importBag(x);
    REQUIRE(r.warnings.size() == 1);
    CHECK_THAT(r.warnings[0], Catch::StartsWith("/cam/camera_info: camera_info changes during the bag (first at t = "));
    x.out_dir = dir.file("equidistant");
    x.camera_info_topic = "/cam/equidistant_info";
    CHECK(loadCameraFile(importBag(x).camera_path).distortion() == CameraModel::Distortion::KannalaBrandt);
  }
  SECTION("a truncated bag")
  {
    BagImportOptions x = o;
    x.bag = copyPrefix(dir, "cut.bag", kRobot, fs::file_size(kRobot) / 2);
    fails(x, {x.bag + ": truncated or corrupt"});
  }
}

TEST_CASE("importBag: a pan joint about another axis than +Y (REP 103's z-up base_link)", "[bag]")
{
  // The same bag imported with the default axis and with --joint-axis 0,0,1 --joint-origin p: the
  // camera's pose that yawdepth's model rebuilds from the second (wMv vMc(yaw), the yaw about v's +Y)
  // is the first's body pose turned about the body's z axis through p by the joint's position.
  TempDir dir;
  BagImportOptions o = robotOptions(dir.file("y"));
  o.joint_topic = "/joint_states";
  o.joint = "pan_joint";
  const BagImportResult plain = importBag(o);
  // The writer's body turns about its z: the default axis gets the warning that names it.
  REQUIRE(plain.warnings.size() == 1);
  CHECK(contains(plain.warnings[0], "the body turns about"));
  CHECK(contains(plain.warnings[0], "--joint-axis 0,0,1"));
  o.out_dir = dir.file("z");
  o.joint_axis = {0, 0, 2}; // any length
  o.joint_origin = {0.1, -0.02, 0.3};
  const BagImportResult rep103 = importBag(o);
  CHECK(rep103.warnings.empty());
  const MotionLog a = readMotionCsv(plain.motion_path), b = readMotionCsv(rep103.motion_path);
  REQUIRE(a.samples.size() == b.samples.size());
  REQUIRE(a.samples.size() >= 10);
  const Eigen::Isometry3d bMc0 = isoOf(vpHomogeneousMatrix(*readRigFile(plain.rig_path).camera_pose));
  const YawRig rig = rigOf(readRigFile(rep103.rig_path));
  const Eigen::Vector3d p(0.1, -0.02, 0.3);
  double worst_t = 0, worst_r = 0;
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    const double yaw = b.samples[i].yaw;
    CHECK(yaw == a.samples[i].yaw);
    Eigen::Isometry3d pan = Eigen::Isometry3d::Identity();
    pan.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pan.translation() = p - pan.linear() * p;
    const Eigen::Isometry3d want = isoOf(wMv(a.samples[i])) * pan * bMc0;
    const Eigen::Isometry3d got = isoOf(wMv(b.samples[i]) * rig.vMc(yaw));
    worst_t = std::max(worst_t, (got.translation() - want.translation()).norm());
    worst_r = std::max(worst_r, rotationError(got.linear(), want.linear()));
  }
  CHECK(worst_t < 1e-9);
  CHECK(worst_r < 1e-9);
  // A zero axis is refused, naming the option.
  o.joint_axis = {0, 0, 0};
  CHECK_THROWS_WITH(importBag(o), Catch::Contains("--joint-axis"));
}

TEST_CASE("importBag: a camera whose mount moves in /tf (a pan joint from robot_state_publisher)", "[bag]")
{
  // tests/data/bags/writers/make_moving_mount_bag.py: REP 103's z-up base_link, the pan link on /tf.
  TempDir dir;
  BagImportOptions o;
  o.bag = kDir + "/moving_mount.bag";
  o.out_dir = dir.file("mm");
  o.image_topic = "/camera/image_raw";
  o.odom_topic = "/odom";
  o.joint_topic = "/joint_states";
  o.joint = "pan_joint";
  const BagImportResult r = importBag(o);
  REQUIRE(r.warnings.size() == 1);
  CHECK(contains(r.warnings[0], "moves in /tf, which holds the pan: /joint_states is not used"));
  CHECK(r.images_matched == 20);
  // The camera is the vision frame: camera_pose identity, each row the camera's pose in odom.
  CHECK(isoOf(vpHomogeneousMatrix(*readRigFile(r.rig_path).camera_pose)).isApprox(Eigen::Isometry3d::Identity()));
  const MotionLog log = readMotionCsv(r.motion_path);
  REQUIRE(log.samples.size() == 20);
  Eigen::Isometry3d pMc = Eigen::Isometry3d::Identity();
  pMc.translation() = Eigen::Vector3d(0.05, 0, 0.05);
  pMc.linear() = Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5).toRotationMatrix();
  double worst_t = 0, worst_r = 0;
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const double tau = stampOf(log.images[i]) - T0;
    Eigen::Isometry3d oMb = Eigen::Isometry3d::Identity(), bMp = Eigen::Isometry3d::Identity();
    oMb.translation() = Eigen::Vector3d(0.5 * tau, 0.1 * std::sin(tau), 0);
    oMb.linear() = Eigen::AngleAxisd(0.3 * tau, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    bMp.translation() = Eigen::Vector3d(0.1, 0, 0.4);
    bMp.linear() = Eigen::AngleAxisd(0.4 * std::sin(M_PI * tau), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Isometry3d want = oMb * bMp * pMc;
    const Eigen::Isometry3d got = isoOf(wMv(log.samples[i]));
    worst_t = std::max(worst_t, (got.translation() - want.translation()).norm());
    worst_r = std::max(worst_r, rotationError(got.linear(), want.linear()));
  }
  WARN("a moving mount: the camera at the image times " << worst_t << " m, " << worst_r << " rad from the truth");
  // The pan on /tf at 50 Hz, interpolated by tf2 (slerp): its curvature, 0.4 pi^2 rad/s^2 over 20 ms.
  CHECK(worst_t < 1e-3);
  CHECK(worst_r < 1e-3);
}
