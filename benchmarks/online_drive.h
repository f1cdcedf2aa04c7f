#pragma once
/*
  online_drive.h: the rendered drive of issue 37, one owner for test_online, bench_online and the ROS
  node's test bag (tests/ros/make_drive_bag.cpp). Header-only, not installed.

  Scene: klt_wall.h's textured wall, kWallDepth = 2 m in front of the first camera (smoothed uniform
  noise, seeded; each frame blurred 0.8 px, noise 2 gray levels, photo_like.h's response curve and
  JPEG round trip), 640x480, focal 600 px. The vision frame drives 0.12 m/s along x with a heading
  sway of +-1 degree (3.75 rad/s), the pan sweeps +-1.7 degrees (2 rad/s); the camera sits 5 cm left
  of the pan axis (YawRig (-0.05, 0, 0)).
  Streams, as a robot gives them: poses at 100 Hz from t = 0 and joint readings at 50 Hz from
  t = 0.003 (the motion clock), images at 30 Hz from t = 0.0137 on the camera clock, which runs
  kTimeOffset = 20 ms behind (the image at camera time t was taken at motion time t + 0.02, the
  measurer's time_offset). Poses and joint readings go on kMargin = 0.3 s past the last image. Each
  image is rendered at interpolateMotion() of the pushed samples around its motion time (what the
  measurer computes), so the render and the measurer agree exactly.
*/
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <functional>
#include <thread>
#include <utility>
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

#include "klt_wall.h"
#include "photo_like.h"

namespace yawdepth::bench::drive {

using wall::kFocal;
using wall::kHeight;
using wall::kU0;
using wall::kV0;
using wall::kWallDepth;
using wall::kWidth;

constexpr double kTimeOffset = 0.02;  // s: motion time = camera time + kTimeOffset
constexpr double kMargin = 0.3;       // s of poses and joint readings past the last image
constexpr double kPosePeriod = 0.01;  // s (100 Hz)
constexpr double kJointPhase = 0.003, kJointPeriod = 0.02; // s (50 Hz)
constexpr double kImagePhase = 0.0137, kImagePeriod = 1.0 / 30.0; // s, camera clock (30 Hz)

/* The truth's motion-log row at motion time `t` (its yaw the joint's). */
inline MotionSample truthRow(double t)
{
  MotionSample m;
  m.x = 0.12 * t;
  m.heading = 0.0175 * std::sin(3.75 * t);
  m.yaw = 0.03 * std::sin(2.0 * t);
  return m;
}

/* The drive: what each stream pushes (times on their clocks) and each image's truth. */
struct Drive {
  YawRig rig{Eigen::Vector3d(-0.05, 0, 0)};
  std::vector<std::pair<double, MotionSample>> poses; // motion clock, 100 Hz
  std::vector<std::pair<double, double>> joints;      // motion clock, 50 Hz, another phase
  std::vector<double> image_times;                    // camera clock, 30 Hz, another phase
  std::vector<MotionSample> image_poses;              // each image's pose (rendered with it)
  std::vector<cv::Mat> images;                        // 8-bit gray, 640x480
};

/* interpolateMotion() of the drive's samples around motion time `t` (the reference the measurer
   must match): the pose from the poses, the yaw from the joint readings. */
inline MotionSample expectedPose(const Drive &d, double t)
{
  auto upper = [](const auto &buffer, double v) {
    return static_cast<std::size_t>(
        std::upper_bound(buffer.begin(), buffer.end(), v, [](double a, const auto &e) { return a < e.first; }) -
        buffer.begin());
  };
  const std::size_t j = upper(d.poses, t), k = upper(d.joints, t);
  MotionSample s = interpolateMotion(d.poses[j - 1].second, d.poses[j].second,
                                     (t - d.poses[j - 1].first) / (d.poses[j].first - d.poses[j - 1].first));
  MotionSample a, b;
  a.yaw = d.joints[k - 1].second;
  b.yaw = d.joints[k].second;
  s.yaw = interpolateMotion(a, b, (t - d.joints[k - 1].first) / (d.joints[k].first - d.joints[k - 1].first)).yaw;
  return s;
}

/* Renders `seconds` of images (see the file); seeded by `seed`: the same drive on every call. */
inline Drive renderDrive(double seconds, unsigned seed)
{
  Drive d;
  for (int j = 0; j * kPosePeriod <= seconds + kMargin; ++j)
    d.poses.emplace_back(j * kPosePeriod, truthRow(j * kPosePeriod));
  for (int j = 0; kJointPhase + j * kJointPeriod <= seconds + kMargin; ++j)
    d.joints.emplace_back(kJointPhase + j * kJointPeriod, truthRow(kJointPhase + j * kJointPeriod).yaw);
  for (int k = 0; kImagePhase + k * kImagePeriod <= seconds; ++k)
    d.image_times.push_back(kImagePhase + k * kImagePeriod);
  // The texture (as klt_wall.h's): smoothed uniform noise, seeded.
  cv::Mat noise(kHeight, kWidth, CV_32F), smooth, texture;
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 2.0);
  cv::normalize(smooth, smooth, 20, 235, cv::NORM_MINMAX);
  smooth.convertTo(texture, CV_8U);
  for (double tc : d.image_times)
    d.image_poses.push_back(expectedPose(d, tc + kTimeOffset));
  for (const MotionSample &s : d.image_poses) {
    const vpHomogeneousMatrix cMc0 = wMc(d.rig, s).inverse() * wMc(d.rig, d.image_poses.front());
    cv::Mat warped, blurred, frame_noise(kHeight, kWidth, CV_32F), f;
    cv::warpPerspective(texture, warped, cv::Mat(planeHomography(cMc0, kWallDepth, kFocal, kU0, kV0)), texture.size(),
                        cv::INTER_CUBIC, cv::BORDER_REFLECT);
    cv::GaussianBlur(warped, blurred, cv::Size(0, 0), 0.8);
    rng.fill(frame_noise, cv::RNG::NORMAL, 0.0, 2.0);
    blurred.convertTo(f, CV_32F);
    d.images.push_back(photoFinish(f + frame_noise));
  }
  return d;
}

/* The wall in the world (the motion log's frame): Z = kWallDepth in the first image's camera. Returns
   the depth (camera Z, the camera at wMcam) where the ray of pixel (u, v) meets it, NaN when behind. */
inline double wallDepth(const Drive &d, const vpHomogeneousMatrix &wMcam, double u, double v)
{
  const vpHomogeneousMatrix c0Mc = wMc(d.rig, d.image_poses.front()).inverse() * wMcam;
  const double x = (u - kU0) / kFocal, y = (v - kV0) / kFocal;
  const double dz = c0Mc[2][0] * x + c0Mc[2][1] * y + c0Mc[2][2];
  const double t = (kWallDepth - c0Mc[2][3]) / dz;
  return t > 0 ? t : std::nan("");
}
/* The same, the camera at a motion-log row of the drive's rig. */
inline double wallDepth(const Drive &d, const MotionSample &pose, double u, double v)
{
  return wallDepth(d, wMc(d.rig, pose), u, v);
}

/* One push of the drive: its motion-clock time, its stream and its index in that stream. */
struct Event {
  double t_motion;
  enum Stream { Pose, Joint, Image } stream;
  std::size_t index;
};

/* Every stream's pushes in motion-clock order (images at camera time + kTimeOffset), the poses in
   (stall_from, stall_to) left out. */
inline std::vector<Event> events(const Drive &d, double stall_from = 1e9, double stall_to = 1e9)
{
  std::vector<Event> e;
  for (std::size_t i = 0; i < d.poses.size(); ++i)
    if (!(d.poses[i].first > stall_from && d.poses[i].first < stall_to))
      e.push_back({d.poses[i].first, Event::Pose, i});
  for (std::size_t i = 0; i < d.joints.size(); ++i)
    e.push_back({d.joints[i].first, Event::Joint, i});
  for (std::size_t i = 0; i < d.image_times.size(); ++i)
    e.push_back({d.image_times[i] + kTimeOffset, Event::Image, i});
  std::stable_sort(e.begin(), e.end(), [](const Event &a, const Event &b) { return a.t_motion < b.t_motion; });
  return e;
}

/* The drive's first `seconds` played in real time, as a robot's streams arrive: one thread per stream
   (poses and joint readings to `seconds` + 0.1 s, images to `seconds`), each calling its callback with
   the index in its stream at that push's motion time from 50 ms after the call (images at camera
   time + kTimeOffset); `done` counts the streams finished. Join the threads returned. */
inline std::vector<std::thread> playInRealTime(const Drive &d, double seconds,
                                               const std::function<void(std::size_t)> &pose,
                                               const std::function<void(std::size_t)> &joint,
                                               const std::function<void(std::size_t)> &image, std::atomic<int> &done)
{
  const auto start = std::chrono::steady_clock::now() + std::chrono::milliseconds(50);
  const auto at = [start](double t) {
    return start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(t));
  };
  const auto stream = [at, &done](std::vector<double> times, double until, std::function<void(std::size_t)> push) {
    return std::thread([at, &done, times = std::move(times), until, push = std::move(push)] {
      for (std::size_t i = 0; i < times.size() && times[i] <= until; ++i) {
        std::this_thread::sleep_until(at(times[i]));
        push(i);
      }
      ++done;
    });
  };
  std::vector<double> pose_t, joint_t, image_t;
  for (const auto &p : d.poses)
    pose_t.push_back(p.first);
  for (const auto &j : d.joints)
    joint_t.push_back(j.first);
  for (double t : d.image_times)
    image_t.push_back(t + kTimeOffset);
  std::vector<std::thread> threads;
  threads.push_back(stream(std::move(pose_t), seconds + 0.1, pose));
  threads.push_back(stream(std::move(joint_t), seconds + 0.1, joint));
  threads.push_back(stream(std::move(image_t), seconds + kTimeOffset, image));
  return threads;
}

} // namespace yawdepth::bench::drive
