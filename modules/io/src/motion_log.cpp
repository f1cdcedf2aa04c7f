#include "csv.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <Eigen/Geometry>
#include <sstream>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

namespace fs = std::filesystem;
using io_detail::CsvReader;
using io_detail::csvField;
using io_detail::formatNumber;
using io_detail::throwError;

long MotionLog::indexOf(long frame) const
{
  return rowOfFrame(samples, frame);
}

const MotionSample *MotionLog::find(long frame) const
{
  const long i = indexOf(frame);
  return i < 0 ? nullptr : &samples[static_cast<std::size_t>(i)];
}

namespace io_detail {

Eigen::Vector3d thetaUOfQuaternion(double qx, double qy, double qz, double qw, const std::function<void(const std::string &)> &fail)
{
  const double n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
  if (!(n > 0))
    fail("the quaternion (qx, qy, qz, qw) has norm 0");
  if (!(std::abs(n - 1.0) <= kQuaternionNormTolerance))
    fail("the quaternion (qx, qy, qz, qw) has norm " + formatNumber(n) + ": not a unit quaternion (more than " +
         formatNumber(kQuaternionNormTolerance) + " from 1)");
  const Eigen::Quaterniond q(qw / n, qx / n, qy / n, qz / n);
  return logSO3(q.toRotationMatrix());
}

void checkTimeIncreasing(double t, std::optional<double> previous, const std::function<void(const std::string &)> &fail)
{
  if (previous && !(t > *previous))
    fail("time " + formatNumber(t) + " s " + (t == *previous ? "is repeated" : "goes back") + " after " +
         formatNumber(*previous) + " s: times must be strictly increasing");
}

} // namespace io_detail

NoiseModel noiseForMotionLog(const NoiseModel &noise, bool six_dof, bool yaw_column, bool sigma_yaw_given)
{
  NoiseModel n = noise;
  if (six_dof && !yaw_column && !sigma_yaw_given)
    n.sigma_yaw = 0.0;
  return n;
}

MotionLog readMotionCsv(const std::string &path, std::optional<double> fixed_yaw, const InputLimits &limits)
{
  CsvReader csv(path, limits);
  // Frame-based (one row per frame) with `frame`; timestamped (pose samples at their own rate) with
  // `t` and no `frame` (then `t` of a frame-based log is informational and not read).
  const auto c_frame_opt = csv.column("frame");
  const auto c_time = c_frame_opt ? std::nullopt : csv.column("t");
  if (!c_frame_opt && !c_time)
    csv.failAt(csv.headerLine(), "missing column 'frame' in the header (or 't' for a timestamped log; TUM and "
                                 "EuRoC files are read as they are: see --motion-format)");
  const bool timestamped = c_time.has_value();
  // The 6-DoF forms (tx, ty, tz with tux, tuy, tuz: wMv as a vpPoseVector; or with qx, qy, qz, qw: a
  // Hamilton quaternion) when any of their columns is there; then all are required and x, y, z,
  // heading are not read.
  static const char *const kPose[6] = {"tx", "ty", "tz", "tux", "tuy", "tuz"};
  static const char *const kQuat[4] = {"qx", "qy", "qz", "qw"};
  bool theta_u = false, quaternion = false;
  for (int i = 3; i < 6; ++i)
    theta_u = theta_u || csv.column(kPose[i]).has_value();
  for (const char *name : kQuat)
    quaternion = quaternion || csv.column(name).has_value();
  if (theta_u && quaternion)
    csv.failAt(csv.headerLine(), "both a theta-u rotation (tux, tuy, tuz) and a quaternion (qx, qy, qz, qw): give one");
  bool six_dof = theta_u || quaternion;
  for (int i = 0; i < 3; ++i)
    six_dof = six_dof || csv.column(kPose[i]).has_value();
  std::size_t c_pose[7] = {0, 0, 0, 0, 0, 0, 0};
  if (quaternion) {
    for (int i = 0; i < 3; ++i)
      c_pose[i] = csv.requireColumn(kPose[i]);
    for (int i = 0; i < 4; ++i)
      c_pose[3 + i] = csv.requireColumn(kQuat[i]);
  } else if (six_dof) {
    for (int i = 0; i < 6; ++i)
      c_pose[i] = csv.requireColumn(kPose[i]);
  } else {
    c_pose[0] = csv.requireColumn("x");
    c_pose[1] = csv.requireColumn("y");
    c_pose[2] = csv.requireColumn("z");
    c_pose[3] = csv.requireColumn("heading");
  }
  const auto c_yaw = csv.column("yaw");
  const auto c_image = csv.column("image");
  if (timestamped && c_image)
    csv.failAt(csv.headerLine(), "an 'image' column in a timestamped log (column 't'): give the images and their "
                                 "times with --images");
  if (!c_yaw && six_dof && !fixed_yaw)
    fixed_yaw = 0.0; // a 6-DoF log without a pan joint: the camera is fixed to the vision frame
  if (!c_yaw) {
    if (!fixed_yaw)
      csv.failFile("no 'yaw' column and the rig file has no 'yaw'");
    if (!std::isfinite(*fixed_yaw))
      csv.failFile("no 'yaw' column and the fixed yaw is not a finite number");
  }
  const fs::path folder = fs::path(path).parent_path();
  const auto fail = [&](const std::string &why) { csv.fail(why); };

  MotionLog log;
  log.yaw_column = c_yaw.has_value();
  log.timestamped = timestamped;
  std::vector<std::size_t> lines;
  while (csv.next()) {
    MotionSample s;
    if (timestamped) {
      const double t = csv.number(*c_time);
      io_detail::checkTimeIncreasing(t, log.times.empty() ? std::nullopt : std::optional<double>(log.times.back()),
                                     fail);
      log.times.push_back(t);
      s.frame = static_cast<long>(log.samples.size());
    } else {
      s.frame = csv.integer(*c_frame_opt);
    }
    s.x = csv.number(c_pose[0]);
    s.y = csv.number(c_pose[1]);
    s.z = csv.number(c_pose[2]);
    if (quaternion) {
      s.six_dof = true;
      s.theta_u = io_detail::thetaUOfQuaternion(csv.number(c_pose[3]), csv.number(c_pose[4]), csv.number(c_pose[5]),
                                                csv.number(c_pose[6]), fail);
    } else if (six_dof) {
      s.six_dof = true;
      s.theta_u = Eigen::Vector3d(csv.number(c_pose[3]), csv.number(c_pose[4]), csv.number(c_pose[5]));
      if (!(s.theta_u.norm() <= 4 * M_PI))
        csv.fail((timestamped ? std::string() : "frame " + std::to_string(s.frame) + ": ") +
                 "the rotation (tux, tuy, tuz) has a norm above 4 pi: not a theta-u vector in radians");
    } else {
      s.heading = csv.number(c_pose[3]);
    }
    s.yaw = c_yaw ? csv.number(*c_yaw) : *fixed_yaw;
    if (!timestamped && !log.samples.empty()) {
      const long prev = log.samples.back().frame;
      if (s.frame == prev)
        csv.fail("frame " + std::to_string(s.frame) + " is repeated (first at line " +
                 std::to_string(lines.back()) + ")");
      if (s.frame < prev)
        csv.fail("frame " + std::to_string(s.frame) + " follows frame " + std::to_string(prev) +
                 ": frames must be strictly increasing");
    }
    if (c_image) {
      const std::string &img = csv.field(*c_image);
      log.images.push_back(img.empty() ? std::string() : (folder / img).string());
    }
    log.samples.push_back(s);
    lines.push_back(csv.line());
  }
  if (log.samples.empty())
    csv.failFile("no data rows after the header");
  return log;
}

/* `image` as written in a CSV in `folder`: relative to it when inside it, else absolute. */
static std::string imageForFolder(const std::string &image, const fs::path &folder)
{
  if (image.empty())
    return image;
  std::error_code ec;
  const fs::path img = fs::absolute(fs::path(image), ec).lexically_normal();
  if (ec)
    return image;
  const fs::path dir = fs::absolute(folder.empty() ? fs::path(".") : folder, ec).lexically_normal();
  if (ec)
    return image;
  const fs::path rel = img.lexically_relative(dir);
  if (!rel.empty() && *rel.begin() != ".." && rel != ".")
    return rel.generic_string();
  // Outside the folder: an absolute path reads back the same from anywhere.
  return fs::path(image).is_absolute() ? image : img.string();
}

void writeMotionCsv(const std::string &path, const MotionLog &motion)
{
  const bool with_images = !motion.images.empty();
  if (with_images && motion.images.size() != motion.samples.size())
    throwError(path + ": the motion log has " + std::to_string(motion.samples.size()) + " samples but " +
               std::to_string(motion.images.size()) + " images");
  const fs::path folder = fs::path(path).parent_path();
  const bool six_dof = !motion.samples.empty() && motion.samples.front().six_dof;
  for (const MotionSample &s : motion.samples)
    if (s.six_dof != six_dof)
      throwError(path + ": the motion log mixes planar and 6-DoF rows (frame " + std::to_string(s.frame) + ")");
  const bool with_times = !motion.times.empty();
  if (with_times && motion.times.size() != motion.samples.size())
    throwError(path + ": the motion log has " + std::to_string(motion.samples.size()) + " samples but " +
               std::to_string(motion.times.size()) + " times");
  if (motion.timestamped && !with_times)
    throwError(path + ": a timestamped motion log without times");
  if (motion.timestamped && with_images)
    throwError(path + ": a timestamped motion log with images (align it to the images first)");
  // A timestamped log is written with `t` for `frame`; a frame-based one with times (an aligned log)
  // gets `t` after `frame`, informational.
  std::string out = motion.timestamped ? "t" : with_times ? "frame,t" : "frame";
  out += six_dof ? ",tx,ty,tz,tux,tuy,tuz,yaw" : ",x,y,z,heading,yaw";
  out += with_images ? ",image\n" : "\n";
  for (std::size_t i = 0; i < motion.samples.size(); ++i) {
    const MotionSample &s = motion.samples[i];
    std::vector<double> values = {s.x, s.y, s.z, s.heading, s.yaw};
    if (six_dof)
      values = {s.x, s.y, s.z, s.theta_u.x(), s.theta_u.y(), s.theta_u.z(), s.yaw};
    for (double v : values)
      if (!std::isfinite(v))
        throwError(path + ": frame " + std::to_string(s.frame) + " has a non-finite value");
    if (with_times && !std::isfinite(motion.times[i]))
      throwError(path + ": frame " + std::to_string(s.frame) + " has a non-finite time");
    if (motion.timestamped) {
      out += formatNumber(motion.times[i]);
    } else {
      out += std::to_string(s.frame);
      if (with_times)
        out += ',' + formatNumber(motion.times[i]);
    }
    for (double v : values) {
      out += ',';
      out += formatNumber(v);
    }
    if (with_images) {
      out += ',';
      out += csvField(imageForFolder(motion.images[i], folder));
    }
    out += '\n';
  }
  writeFileAtomically(path, out);
}

} // namespace yawdepth
