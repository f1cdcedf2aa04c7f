// yawdepth::MeasuringNode (issue 37): the ROS node's logic without ROS, on benchmarks/online_drive.h's
// rendered drive: settings, start (camera_info, the odometry's frames, a fixed or moving mount), the
// motion with a pan joint's vision frame, diagnostics (the wrong-axis warning among them), and the
// servo depth requests.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>
#include <yawdepth/error.h>
#include <yawdepth/live/measuring_node.h>

#include "online_drive.h"

using namespace yawdepth;

namespace {

namespace drive = bench::drive;
constexpr double kLiveSeconds = 3.0;
constexpr unsigned kLiveSeed = 37;
constexpr double kWithin3SigmaFraction = 0.9; // honest sigmas: about 99.7 % of ok points

const drive::Drive &liveDrive()
{
  static const drive::Drive d = drive::renderDrive(kLiveSeconds, kLiveSeed);
  return d;
}

CameraInfoMessage liveCameraInfo()
{
  CameraInfoMessage c;
  c.width = drive::kWidth;
  c.height = drive::kHeight;
  c.distortion_model = "plumb_bob";
  c.D = {0, 0, 0, 0, 0};
  c.K = {drive::kFocal, 0, drive::kU0, 0, drive::kFocal, drive::kV0, 0, 0, 1};
  c.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  c.P = {drive::kFocal, 0, drive::kU0, 0, 0, drive::kFocal, drive::kV0, 0, 0, 0, 1, 0};
  return c;
}

/* The drive as a node sees it: the body is the drive's vision frame (the pan about its +Y through its
   origin: joint_axis (0, 1, 0), joint_origin 0), the mount bMc the rig at yaw 0, images stamped
   -kTimeOffset late (camera_latency = -0.02: the drive's camera clock runs behind). */
MeasuringNodeSettings liveSettings()
{
  MeasuringNodeSettings s;
  s.motion = "odom";
  s.joint = "pan";
  s.camera_latency = -drive::kTimeOffset;
  s.online.noise.sigma_px = 0.5;
  s.online.noise.motion_noise = MotionNoise::Absolute; // the render's poses are exact
  s.online.noise.sigma_odom = 1e-4;
  s.online.noise.sigma_rot = 1e-4;
  s.online.noise.sigma_yaw = 1e-4;
  s.online.klt.max_features = 200;
  return s;
}

MountLookup fixedMount(const std::string &, const std::string &)
{
  MountLookup m;
  m.fixed = liveDrive().rig.vMc(0.0);
  return m;
}

/* Every stream of the drive pushed in time order; the frames measured. */
std::vector<OnlineFrame> liveRun(MeasuringNode &node, std::vector<double> *image_times = nullptr)
{
  const drive::Drive &d = liveDrive();
  std::vector<OnlineFrame> frames;
  for (const drive::Event &e : drive::events(d)) {
    if (e.stream == drive::Event::Pose) {
      node.setOdometryFrames("odom", "base_link", "/odom");
      node.pushMotion(d.poses[e.index].first, wMv(d.poses[e.index].second));
    } else if (e.stream == drive::Event::Joint) {
      CHECK(node.pushJointState(d.joints[e.index].first, {"wheel", "pan"}, {0.5, d.joints[e.index].second}, "/joint_states"));
    } else {
      CHECK(node.start("camera_optical", fixedMount).empty());
      node.pushImage(d.image_times[e.index], d.images[e.index]);
      if (image_times)
        image_times->push_back(d.image_times[e.index]);
    }
    for (OnlineFrame &f : node.process())
      frames.push_back(std::move(f));
  }
  return frames;
}

} // namespace

TEST_CASE("MeasuringNode: settings name the bad parameter; the measurer's time offset is -camera_latency", "[live]")
{
  MeasuringNodeSettings s;
  s.camera_latency = 0.03;
  CHECK(s.onlineOptions().time_offset == -0.03);
  auto refused = [](MeasuringNodeSettings bad, const std::string &name) {
    INFO(name);
    try {
      MeasuringNode node(bad);
      FAIL("accepted");
    } catch (const Error &e) {
      CHECK(std::string(e.what()).rfind(name, 0) == 0);
    }
  };
  s = MeasuringNodeSettings();
  s.motion = "gps";
  refused(s, "motion");
  s = MeasuringNodeSettings();
  s.body_frame = s.world_frame;
  refused(s, "world_frame");
  s = MeasuringNodeSettings();
  s.joint_axis = Eigen::Vector3d::Zero();
  refused(s, "joint_axis");
  s = MeasuringNodeSettings();
  s.camera_latency = NAN;
  refused(s, "camera_latency");
  s = MeasuringNodeSettings();
  s.interval_sigmas = -1;
  refused(s, "interval_sigmas");
  s = MeasuringNodeSettings();
  s.diagnostics_period = 0;
  refused(s, "diagnostics_period");
  s = MeasuringNodeSettings();
  s.service_wait = -1;
  refused(s, "service_wait");
  s = MeasuringNodeSettings();
  s.online.window = 1;
  refused(s, "online options");
}

TEST_CASE("MeasuringNode: start waits for camera_info, the odometry's frames and the mount", "[live]")
{
  MeasuringNode node(liveSettings());
  const auto no_mount = [](const std::string &, const std::string &) {
    MountLookup m;
    m.why = "frame camera_optical does not exist";
    return m;
  };
  CHECK(node.start("camera_optical", no_mount) == "waiting for camera_info");
  CameraInfoMessage bad = liveCameraInfo();
  bad.K = {};
  CHECK_THROWS_WITH(node.setCameraInfo(bad, "/camera/camera_info"), Catch::Contains("/camera/camera_info"));
  CHECK(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
  CameraInfoMessage other = liveCameraInfo();
  other.K[0] = 610;
  CHECK_FALSE(node.setCameraInfo(other, "/camera/camera_info")); // kept the first: warn
  CHECK(node.start("camera_optical", no_mount).rfind("waiting for the odometry", 0) == 0);
  node.setOdometryFrames("odom", "base_link", "/odom");
  CHECK_THROWS_WITH(node.setOdometryFrames("map", "base_link", "/odom"), Catch::Contains("/odom"));
  CHECK(node.worldFrame() == "odom");
  CHECK(node.bodyFrame() == "base_link");
  const std::string waiting = node.start("camera_optical", no_mount);
  CHECK(waiting.find("base_link -> camera_optical") != std::string::npos);
  CHECK(waiting.find("does not exist") != std::string::npos);
  CHECK_FALSE(node.started());
  CHECK(node.diagnostics().warn);
  CHECK(node.depths({}).error.rfind("not measuring yet", 0) == 0);
  CHECK_THROWS_AS(node.start("", no_mount), Error); // no frame id and no camera_frame
  // A mount moving in the transforms: the camera's own pose is the motion, the joint not used.
  const auto moving = [](const std::string &, const std::string &) {
    MountLookup m;
    m.moving = true;
    return m;
  };
  CHECK(node.start("camera_optical", moving).empty());
  CHECK(node.started());
  CHECK(node.movingMount());
  CHECK(node.motionFrame() == "camera_optical");
  CHECK(node.pushJointState(0.1, {"pan"}, {0.2}, "/joint_states")); // found, not pushed
  CHECK_THROWS_WITH(node.pushJointState(0.1, {"pan"}, {}, "/joint_states"), Catch::Contains("/joint_states"));
  CHECK_FALSE(node.pushJointState(0.1, {"wheel"}, {0.2}, "/joint_states"));
}

TEST_CASE("MeasuringNode: the drive through a node: clouds on the wall, diagnostics, servo depths", "[live]")
{
  MeasuringNodeSettings settings = liveSettings();
  settings.online.max_image_age = 5.0; // the whole drive's motion kept: servo requests at any of its images
  MeasuringNode node(settings);
  REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
  std::vector<double> image_times;
  const std::vector<OnlineFrame> frames = liveRun(node, &image_times);
  const drive::Drive &d = liveDrive();
  REQUIRE(node.started());
  CHECK_FALSE(node.movingMount());
  CHECK(node.cameraFrame() == "camera_optical");
  CHECK(frames.size() + 1 >= d.images.size()); // all but, at most, the one before the first pose
  std::size_t ok = 0, within = 0;
  for (const OnlineFrame &f : frames) {
    // The pose used is the drive's (its yaw the joint's, from the joint state's "pan").
    const MotionSample e = drive::expectedPose(d, f.t + drive::kTimeOffset);
    CHECK(std::abs(f.pose.yaw - e.yaw) < 1e-12);
    for (const CloudPoint &c : node.cloud(f)) {
      ++ok;
      const double z = drive::wallDepth(d, f.pose, c.u, c.v);
      within += std::abs(c.c_P.z() - z) <= 3 * c.sigma_z ? 1 : 0;
    }
  }
  INFO("ok points " << ok << ", within 3 sigma " << within);
  REQUIRE(ok > 1000);
  CHECK(static_cast<double>(within) >= kWithin3SigmaFraction * static_cast<double>(ok));

  const NodeDiagnostics diag = node.diagnostics();
  auto value = [&diag](const std::string &key) {
    for (const auto &[k, v] : diag.values)
      if (k == key)
        return v;
    return std::string("(absent)");
  };
  // The first image came before the node's first pose (the node starts with it): dropped, warned.
  INFO(diag.message);
  CHECK(diag.warn == (value("dropped uncovered") != "0"));
  CHECK((diag.message == "measuring" || diag.message == "images dropped"));
  CHECK(std::stoul(value("dropped uncovered")) + frames.size() == d.images.size());
  CHECK(value("dropped stale") == "0");
  CHECK(value("images measured") == std::to_string(frames.size()));
  CHECK(value("latency median (ms)") != "(absent)");
  CHECK(value("bad messages") == "0");
  CHECK(value("points ok (last image)") == value("points published (last image)"));
  CHECK(node.diagnostics().values.size() < diag.values.size()); // a period without an image: no latency
  CHECK(node.diagnostics().message == "measuring"); // nothing dropped since
  node.noteBadMessage();
  const NodeDiagnostics bad = node.diagnostics();
  CHECK(bad.warn);
  CHECK(bad.message == "bad messages");

  // Servo requests: the last image's features (a client's own ids) at its stamp.
  ServoDepthRequest r;
  r.t = image_times.back();
  for (const OnlinePoint &p : frames.back().points) {
    r.ids.push_back(1000 + p.id);
    r.u.push_back(p.u);
    r.v.push_back(p.v);
  }
  const ServoDepthAnswer a = node.depths(r);
  REQUIRE(a.error.empty());
  REQUIRE(a.depths.size() == r.ids.size());
  CHECK(a.depths.front().id == r.ids.front());
  // One request is one control period: new ids, no depth yet (the prior, the provider's status).
  for (const FeatureDepth &f : a.depths) {
    CHECK_FALSE(f.converged);
    CHECK(f.depth == liveSettings().providerOptions().prior_depth);
  }
  // Requests at the last images' stamps: the same ids converge to the wall.
  std::size_t converged = 0, near_truth = 0;
  for (std::size_t k = frames.size() - 12; k < frames.size(); ++k) {
    ServoDepthRequest q;
    q.t = frames[k].t;
    std::vector<double> truth;
    for (const OnlinePoint &p : frames[k].points) {
      q.ids.push_back(1000 + p.id);
      q.u.push_back(p.u);
      q.v.push_back(p.v);
      truth.push_back(drive::wallDepth(d, frames[k].pose, p.u, p.v));
    }
    const ServoDepthAnswer b = node.depths(q);
    REQUIRE(b.error.empty());
    if (k + 1 < frames.size())
      continue;
    for (std::size_t i = 0; i < b.depths.size(); ++i) {
      if (!b.depths[i].converged)
        continue;
      ++converged;
      near_truth += std::abs(b.depths[i].depth - truth[i]) <= 3 * b.depths[i].sigma ? 1 : 0;
    }
  }
  INFO("converged " << converged << ", within 3 sigma " << near_truth);
  CHECK(converged > 50);
  CHECK(static_cast<double>(near_truth) >= kWithin3SigmaFraction * static_cast<double>(converged));
  r.u.pop_back();
  CHECK(node.depths(r).error == "ids, u and v must have the same length");
  ServoDepthRequest future;
  future.t = image_times.back() + 10.0; // no motion there yet: answered with the reason, after service_wait
  CHECK(node.depths(future).error.rfind("no motion around", 0) == 0);
  ServoDepthRequest past;
  past.t = image_times.front() - 1.0; // before the first pose: answered at once
  CHECK(node.depths(past).error.rfind("no motion at t", 0) == 0);
}

TEST_CASE("MeasuringNode: a pan axis the body does not turn about is warned about, the right one is not", "[live]")
{
  // The drive's poses with a wider heading sway (+-5 degrees: 0.6 rad turned in 3 s), and its joint
  // readings; no images (the warning is about the motion alone).
  const drive::Drive &d = liveDrive();
  for (const bool right_axis : {true, false}) {
    MeasuringNodeSettings s = liveSettings();
    if (!right_axis)
      s.joint_axis = Eigen::Vector3d(0, 0, 1); // the body turns about its +Y
    MeasuringNode node(s);
    REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
    node.setOdometryFrames("odom", "base_link", "/odom");
    REQUIRE(node.start("camera_optical", fixedMount).empty());
    for (const drive::Event &e : drive::events(d)) {
      if (e.stream == drive::Event::Pose) {
        MotionSample p = d.poses[e.index].second;
        p.heading *= 5;
        node.pushMotion(d.poses[e.index].first, wMv(p));
      } else if (e.stream == drive::Event::Joint) {
        node.pushJointState(d.joints[e.index].first, {"pan"}, {d.joints[e.index].second}, "/joint_states");
      }
    }
    const NodeDiagnostics diag = node.diagnostics();
    INFO("right axis " << right_axis << ": " << diag.message);
    if (right_axis) {
      CHECK_FALSE(diag.warn);
      CHECK(diag.message == "measuring");
    } else {
      CHECK(diag.warn);
      // About the body's y (either sign: the sum's), not the joint_axis given.
      CHECK((diag.message.rfind("the body turns about (0.00, 1.00, 0.00) in the body frame, not about joint_axis", 0) == 0 ||
             diag.message.rfind("the body turns about (0.00, -1.00, 0.00) in the body frame, not about joint_axis", 0) == 0));
    }
  }
}

TEST_CASE("MeasuringNode: a pan rig without joint readings, and image stamps far from the motion's, are warned about",
          "[live]")
{
  const drive::Drive &d = liveDrive();
  // The joint states never arrive (a wrong topic): no image is measured at the poses' yaw.
  {
    MeasuringNode node(liveSettings());
    REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
    node.setOdometryFrames("odom", "base_link", "/odom");
    REQUIRE(node.start("camera_optical", fixedMount).empty());
    std::size_t measured = 0;
    for (const drive::Event &e : drive::events(d)) {
      if (e.stream == drive::Event::Pose)
        node.pushMotion(d.poses[e.index].first, wMv(d.poses[e.index].second));
      else if (e.stream == drive::Event::Image)
        node.pushImage(d.image_times[e.index], d.images[e.index]);
      measured += node.process().size();
    }
    CHECK(measured == 0);
    const NodeDiagnostics diag = node.diagnostics();
    CHECK(diag.warn);
    CHECK(diag.message == "no readings of the pan joint pan yet: check the joint states topic and joint");
  }
  // The camera_latency's sign wrong: the images 2 x 0.5 s behind the motion, all dropped as stale.
  {
    MeasuringNodeSettings s = liveSettings();
    s.camera_latency = 1.0;
    MeasuringNode node(s);
    REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
    const std::vector<OnlineFrame> frames = liveRun(node);
    CHECK(frames.empty());
    const NodeDiagnostics diag = node.diagnostics();
    INFO(diag.message);
    CHECK(diag.warn);
    CHECK(diag.message.rfind("images dropped: their stamps are", 0) == 0);
    CHECK(diag.message.find("behind the motion's: check camera_latency and the clocks") != std::string::npos);
  }
}

TEST_CASE("MeasuringNode: restart after the clock jumped back measures the replayed streams afresh", "[live]")
{
  MeasuringNode node(liveSettings());
  node.restart(); // before start: nothing to do
  REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
  const std::size_t first = liveRun(node).size();
  CHECK(liveRun(node).empty()); // the same stamps again: all out of order, nothing measured
  node.restart();
  const std::size_t again = liveRun(node).size();
  CHECK(again == liveDrive().images.size()); // the poses before the first image are pushed this time
  CHECK(first + 1 >= again);
  const NodeDiagnostics diag = node.diagnostics();
  bool reported = false;
  for (const auto &[k, v] : diag.values)
    reported = reported || (k == "restarts (time jumped back)" && v == "1");
  CHECK(reported);
}

TEST_CASE("MeasuringNode: motion waiting for its transforms is pushed in order once they come, or dropped and counted",
          "[live]")
{
  const auto dropped = [](MeasuringNode &node) {
    for (const auto &[k, v] : node.diagnostics().values)
      if (k == "motion dropped (no transform)")
        return std::stoul(v);
    FAIL("no \"motion dropped (no transform)\" in the diagnostics");
    return 0UL;
  };
  SECTION("the queue's rules")
  {
    MeasuringNode node(liveSettings());
    REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
    node.setOdometryFrames("odom", "base_link", "/odom");
    node.queueMotion(0.05, 1); // before the start: ignored
    REQUIRE(node.start("camera_optical", fixedMount).empty());
    double covered_from = 0.15, covered_to = 0.35; // the transforms' span (a link's first and newest reading)
    std::vector<std::uint64_t> asked;
    const MeasuringNode::TransformAt at = [&](double t, std::uint64_t tag) -> std::optional<vpHomogeneousMatrix> {
      asked.push_back(tag);
      if (t < covered_from || t > covered_to)
        return std::nullopt;
      return vpHomogeneousMatrix(t, 0, 0, 0, 0, 0);
    };
    const auto was_asked = [&asked](std::uint64_t tag) { return std::find(asked.begin(), asked.end(), tag) != asked.end(); };
    for (int k = 1; k <= 4; ++k)
      node.queueMotion(0.1 * k, static_cast<std::uint64_t>(100 + k));
    node.queueMotion(0.35, 7); // before the last queued: in its place
    CHECK(node.resolveMotion(at) == 3); // 0.2, 0.3, 0.35; 0.1 is before the link's first reading: dropped
    CHECK(was_asked(103));             // the tag given back
    CHECK(was_asked(7));
    CHECK(dropped(node) == 1);
    node.queueMotion(0.25, 8); // not after the last pushed (0.35): ignored
    node.queueMotion(0.4, 9);  // queued already (tag 104): ignored
    CHECK(node.resolveMotion(at) == 0); // 0.4 waits
    CHECK_FALSE(was_asked(8));
    CHECK_FALSE(was_asked(9));
    covered_to = 0.41;
    CHECK(node.resolveMotion(at) == 1);
    // A stamp ahead of the others (a post-dated transform) waits; the earlier ones go through.
    node.queueMotion(0.9, 11);
    node.queueMotion(0.5, 12);
    node.queueMotion(0.6, 13);
    covered_to = 0.65;
    CHECK(node.resolveMotion(at) == 2);
    covered_to = 0.95;
    CHECK(node.resolveMotion(at) == 1);
    CHECK(dropped(node) == 1);
    // Bounded: a sample max_image_age (0.5 s) behind the newest queued is dropped.
    node.queueMotion(1.0, 14);
    node.queueMotion(1.6, 15);
    CHECK(dropped(node) == 2);
    covered_to = 2.0;
    CHECK(node.resolveMotion(at) == 1);
    // A pose the measurer refuses (not finite) is not retried: the next one goes through.
    vpHomogeneousMatrix nan_pose;
    nan_pose[0][3] = std::numeric_limits<double>::quiet_NaN();
    node.queueMotion(1.7, 16, nan_pose);
    node.queueMotion(1.8, 17, vpHomogeneousMatrix());
    CHECK_THROWS_AS(node.resolveMotion(at), Error);
    CHECK(node.resolveMotion(at) == 1);
    CHECK(dropped(node) == 2);
  }
  SECTION("the drive with a moving mount whose link comes after the odometry: every image measured, on the wall")
  {
    // The pan in the transforms (a pan link published from the joint states, 50 Hz, another phase
    // than the 100 Hz odometry): each odometry pose waits for the mount at its time.
    MeasuringNode node(liveSettings());
    REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
    const drive::Drive &d = liveDrive();
    std::size_t links = 0; // the pan link's readings so far: d.joints[0, links)
    const MeasuringNode::TransformAt mount_at = [&](double t, std::uint64_t) -> std::optional<vpHomogeneousMatrix> {
      if (links < 2 || t < d.joints.front().first || t > d.joints[links - 1].first)
        return std::nullopt;
      std::size_t k = 1;
      while (d.joints[k].first < t)
        ++k;
      MotionSample a, b;
      a.yaw = d.joints[k - 1].second;
      b.yaw = d.joints[k].second;
      const double s = (t - d.joints[k - 1].first) / (d.joints[k].first - d.joints[k - 1].first);
      return d.rig.vMc(interpolateMotion(a, b, s).yaw);
    };
    const auto moving = [](const std::string &, const std::string &) {
      MountLookup m;
      m.moving = true;
      return m;
    };
    std::vector<OnlineFrame> frames;
    std::size_t queued = 0, never = 0, pushed = 0;
    for (const drive::Event &e : drive::events(d)) {
      if (e.stream == drive::Event::Pose) {
        node.setOdometryFrames("odom", "base_link", "/odom");
        const double t = d.poses[e.index].first;
        if (node.started()) {
          ++queued;
          never += t < d.joints.front().first ? 1 : 0;
        }
        node.queueMotion(t, e.index, wMv(d.poses[e.index].second));
      } else if (e.stream == drive::Event::Joint) {
        links = e.index + 1; // the link's transform at this reading arrives
      } else {
        CHECK(node.start("camera_optical", moving).empty());
        node.pushImage(d.image_times[e.index], d.images[e.index]);
      }
      pushed += node.resolveMotion(mount_at);
      for (OnlineFrame &f : node.process())
        frames.push_back(std::move(f));
    }
    REQUIRE(node.movingMount());
    CHECK(dropped(node) == never);
    CHECK(pushed + never + 2 >= queued); // at most the last two wait for a link reading after the drive's end
    CHECK(frames.size() + 1 >= d.images.size()); // all but, at most, the one before the first pose
    std::size_t ok = 0, within = 0;
    for (const OnlineFrame &f : frames)
      for (const CloudPoint &c : node.cloud(f)) {
        ++ok;
        const double z = drive::wallDepth(d, wMv(f.pose), c.u, c.v); // the camera's own pose is the motion
        within += std::abs(c.c_P.z() - z) <= 3 * c.sigma_z ? 1 : 0;
      }
    INFO("ok points " << ok << ", within 3 sigma " << within);
    REQUIRE(ok > 1000);
    CHECK(static_cast<double>(within) >= kWithin3SigmaFraction * static_cast<double>(ok));
  }
}

TEST_CASE("MeasuringNode: streams from their own threads in real time, a consumer and a servo client beside them",
          "[live]")
{
  // The subject is the node's threads (a middleware's callbacks: one per stream, a consumer, a service),
  // not its bounds: the motion kept long, so that a loaded or sanitized run measures every image.
  MeasuringNodeSettings settings = liveSettings();
  settings.online.max_image_age = 1e3;
  settings.online.max_queued_images = 1000;
  settings.service_wait = 0.05;
  MeasuringNode node(settings);
  REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
  node.setOdometryFrames("odom", "base_link", "/odom");
  REQUIRE(node.start("camera_optical", fixedMount).empty()); // before the streams: none of them is ignored
  const drive::Drive &d = liveDrive();
  const double play = 1.5; // s of the drive played in real time
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(play + 60.0);
  std::atomic<int> done{0};
  std::atomic<std::size_t> images_pushed{0};
  std::atomic<double> last_image_t{-1.0};
  std::vector<std::thread> streams = drive::playInRealTime(
      d, play,
      [&](std::size_t i) {
        node.setOdometryFrames("odom", "base_link", "/odom"); // as each odometry message does
        node.pushMotion(d.poses[i].first, wMv(d.poses[i].second));
      },
      [&](std::size_t i) { node.pushJointState(d.joints[i].first, {"wheel", "pan"}, {0.5, d.joints[i].second}, "/joint_states"); },
      [&](std::size_t i) {
        node.pushImage(d.image_times[i], d.images[i]);
        ++images_pushed;
        last_image_t = d.image_times[i];
      },
      done);
  // A servo client: the points of the newest image it saw, asked at that image's stamp, over and over.
  std::mutex seen_mutex;
  ServoDepthRequest seen;
  std::size_t answered = 0, refused = 0;
  std::vector<std::string> unexpected;
  std::atomic<bool> consumer_done{false};
  std::thread servo([&] {
    while (!consumer_done.load()) {
      ServoDepthRequest q;
      {
        std::lock_guard<std::mutex> lock(seen_mutex);
        q = seen;
      }
      if (!q.ids.empty()) {
        const ServoDepthAnswer a = node.depths(q);
        if (a.error.empty() && a.depths.size() == q.ids.size())
          ++answered;
        else if (a.error.rfind("no motion around", 0) == 0)
          ++refused;
        else
          unexpected.push_back(a.error.empty() ? "wrong size" : a.error);
      }
      node.diagnostics();
      std::this_thread::sleep_for(std::chrono::milliseconds(7));
    }
  });
  std::vector<OnlineFrame> frames;
  std::size_t ok = 0, within = 0;
  for (;;) {
    const bool finished = done.load() >= 3;
    for (OnlineFrame &f : node.process()) {
      for (const CloudPoint &c : node.cloud(f)) {
        ++ok;
        within += std::abs(c.c_P.z() - drive::wallDepth(d, f.pose, c.u, c.v)) <= 3 * c.sigma_z ? 1 : 0;
      }
      {
        std::lock_guard<std::mutex> lock(seen_mutex);
        seen = ServoDepthRequest();
        seen.t = f.t;
        for (const OnlinePoint &p : f.points) {
          seen.ids.push_back(p.id);
          seen.u.push_back(p.u);
          seen.v.push_back(p.v);
        }
      }
      frames.push_back(std::move(f));
    }
    if (finished && (frames.empty() || frames.back().t >= last_image_t.load()))
      break;
    if (finished && std::chrono::steady_clock::now() > give_up)
      break; // a measurer that stopped measuring: the checks below fail
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  consumer_done = true;
  for (std::thread &t : streams)
    t.join();
  servo.join();
  INFO("images pushed " << images_pushed.load() << ", measured " << frames.size() << ", ok points "
                                 << ok << ", servo answered " << answered << ", refused " << refused);
  REQUIRE(images_pushed.load() > 30);
  // Every image measured, but at most the first (before the drive's first pose).
  CHECK(frames.size() + 1 >= images_pushed.load());
  for (std::size_t k = 1; k < frames.size(); ++k)
    CHECK(frames[k].t > frames[k - 1].t);
  REQUIRE(ok > 1000);
  CHECK(static_cast<double>(within) >= kWithin3SigmaFraction * static_cast<double>(ok));
  CHECK(answered > 0);
  CHECK(unexpected.empty());
  bool counted = false;
  for (const auto &[k, v] : node.diagnostics().values)
    counted = counted || (k == "images measured" && v == std::to_string(frames.size()));
  CHECK(counted);
}

TEST_CASE("MeasuringNode: restart() while another thread resolves queued motion (as a middleware's callbacks do)",
          "[live]")
{
  // The lookup asks the node for its frames, as the ROS node's does: restart() and resolveMotion()
  // must not wait for each other's locks (a deadlock hangs this test until ctest's timeout).
  MeasuringNode node(liveSettings());
  REQUIRE(node.setCameraInfo(liveCameraInfo(), "/camera/camera_info"));
  node.setOdometryFrames("odom", "base_link", "/odom");
  REQUIRE(node.start("camera_optical", fixedMount).empty());
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> pushed{0}, restarts{0};
  std::thread callbacks([&] {
    for (int k = 1; !stop.load(); ++k) {
      node.queueMotion(0.01 * k, static_cast<std::uint64_t>(k), vpHomogeneousMatrix(0.001 * k, 0, 0, 0, 0, 0));
      pushed += node.resolveMotion([&](double, std::uint64_t) -> std::optional<vpHomogeneousMatrix> {
        return node.bodyFrame() == "base_link" ? std::optional<vpHomogeneousMatrix>(vpHomogeneousMatrix())
                                               : std::nullopt;
      });
      node.diagnostics();
    }
  });
  for (int i = 0; i < 200; ++i) {
    node.restart();
    ++restarts;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  stop = true;
  callbacks.join();
  CHECK(restarts.load() == 200);
  CHECK(pushed.load() > 0);
}
