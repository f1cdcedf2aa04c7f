#include "csv.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
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

MotionLog readMotionCsv(const std::string &path, std::optional<double> fixed_yaw, const InputLimits &limits)
{
  CsvReader csv(path, limits);
  const std::size_t c_frame = csv.requireColumn("frame");
  // The 6-DoF form (tx, ty, tz, tux, tuy, tuz: wMv as a vpPoseVector) when any of its columns is
  // there; then all six are required and x, y, z, heading are not read.
  static const char *const kPose[6] = {"tx", "ty", "tz", "tux", "tuy", "tuz"};
  bool six_dof = false;
  for (const char *name : kPose)
    six_dof = six_dof || csv.column(name).has_value();
  std::size_t c_pose[6] = {0, 0, 0, 0, 0, 0};
  if (six_dof) {
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
  if (!c_yaw && six_dof && !fixed_yaw)
    fixed_yaw = 0.0; // a 6-DoF log without a pan joint: the camera is fixed to the vision frame
  if (!c_yaw) {
    if (!fixed_yaw)
      csv.failFile("no 'yaw' column and the rig file has no 'yaw'");
    if (!std::isfinite(*fixed_yaw))
      csv.failFile("no 'yaw' column and the fixed yaw is not a finite number");
  }
  const fs::path folder = fs::path(path).parent_path();

  MotionLog log;
  log.yaw_column = c_yaw.has_value();
  std::vector<std::size_t> lines;
  while (csv.next()) {
    MotionSample s;
    s.frame = csv.integer(c_frame);
    s.x = csv.number(c_pose[0]);
    s.y = csv.number(c_pose[1]);
    s.z = csv.number(c_pose[2]);
    if (six_dof) {
      s.six_dof = true;
      s.theta_u = Eigen::Vector3d(csv.number(c_pose[3]), csv.number(c_pose[4]), csv.number(c_pose[5]));
      if (!(s.theta_u.norm() <= 4 * M_PI))
        csv.fail("frame " + std::to_string(s.frame) + ": the rotation (tux, tuy, tuz) has a norm above 4 pi: not a "
                 "theta-u vector in radians");
    } else {
      s.heading = csv.number(c_pose[3]);
    }
    s.yaw = c_yaw ? csv.number(*c_yaw) : *fixed_yaw;
    if (!log.samples.empty()) {
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
  std::string out = six_dof ? "frame,tx,ty,tz,tux,tuy,tuz,yaw" : "frame,x,y,z,heading,yaw";
  out += with_images ? ",image\n" : "\n";
  for (std::size_t i = 0; i < motion.samples.size(); ++i) {
    const MotionSample &s = motion.samples[i];
    std::vector<double> values = {s.x, s.y, s.z, s.heading, s.yaw};
    if (six_dof)
      values = {s.x, s.y, s.z, s.theta_u.x(), s.theta_u.y(), s.theta_u.z(), s.yaw};
    for (double v : values)
      if (!std::isfinite(v))
        throwError(path + ": frame " + std::to_string(s.frame) + " has a non-finite value");
    out += std::to_string(s.frame);
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
