#include "csv.h"
#include "yaml_support.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <yaml-cpp/yaml.h>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

using io_detail::excerpt;
using io_detail::formatNumber;
using io_detail::NumberStatus;
using io_detail::parseDouble;
using io_detail::throwError;
using io_detail::where;
using io_detail::finiteNumber;

namespace {

/* A rig file is a few lines; anything much larger is not one. */
constexpr std::size_t kMaxRigFileBytes = 1 << 20;

/* A rig file's text is not empty and not binary. */
void checkRigText(const std::string &path, const std::string &text)
{
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throwError(path + ": empty file");
  if (text.find('\0') != std::string::npos)
    throwError(path + ": not a YAML file (it holds a NUL byte)");
}

/* Every key is one we know: a typo ('camera_ofset') must not silently drop a setting; no key is
   duplicated. Returns the mark of the 'yaw' key (null without one). */
YAML::Mark checkRigKeys(const std::string &path, const YAML::Node &root)
{
  // The *_sigma, yaw_offset_estimated and reprojection_rms_px keys are what calibrate-rig
  // writes beside the values (read as information, not used).
  static const std::set<std::string> kKnown = {"camera_offset",       "camera_pose",   "yaw",
                                               "yaw_offset",          "yaw_axis",      "camera_offset_sigma",
                                               "camera_pose_sigma",   "yaw_offset_sigma",
                                               "yaw_offset_estimated", "yaw_axis_sigma", "reprojection_rms_px",
                                               "time_offset",         "time_offset_sigma"};
  std::set<std::string> seen;
  YAML::Mark yaw_mark = YAML::Mark::null_mark();
  for (const auto &kv : root) {
    if (!kv.first.IsScalar())
      throwError(where(path, kv.first.Mark()) + "a key must be a name");
    const std::string &key = kv.first.Scalar();
    if (kKnown.count(key) == 0) {
      std::string known;
      for (const std::string &k : kKnown)
        known += (known.empty() ? "" : ", ") + k;
      throwError(where(path, kv.first.Mark()) + "unknown key '" + excerpt(key) + "' (known: " + known + ")");
    }
    if (key == "yaw")
      yaw_mark = kv.first.Mark();
    if (!seen.insert(key).second)
      throwError(where(path, kv.first.Mark()) + "duplicated key '" + key + "'");
  }
  return yaw_mark;
}

/* The n finite numbers of a sequence. */
std::vector<double> finiteNumbers(const std::string &path, const YAML::Node &node, const std::string &key,
                                  std::size_t n)
{
  if (!node.IsSequence() || node.size() != n)
    throwError(where(path, node.Mark()) + "'" + key + "' must be a sequence of " + std::to_string(n) + " numbers" +
               (node.IsSequence() ? " (it has " + std::to_string(node.size()) + ")" : ""));
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = finiteNumber(path, node[i], "'" + key + "' value " + std::to_string(i + 1));
  return v;
}

/* The camera mount: camera_offset or camera_pose (exactly one), and camera_pose_sigma. */
void readMount(const std::string &path, const YAML::Node &root, RigFile &rig)
{
  const YAML::Node offset = root["camera_offset"];
  const YAML::Node pose = root["camera_pose"];
  if (offset && pose)
    throwError(where(path, pose.Mark()) +
               "both 'camera_offset' and 'camera_pose': give one (camera_offset: [x, y, z] for a camera on a yaw "
               "joint with its axes along the vision frame's, camera_pose: [tx, ty, tz, tux, tuy, tuz] for any "
               "fixed mount)");
  if (!offset && !pose)
    throwError(path + ": missing key 'camera_offset' (or 'camera_pose')");
  if (offset) {
    const std::vector<double> v = finiteNumbers(path, offset, "camera_offset", 3);
    rig.camera_offset = Eigen::Vector3d(v[0], v[1], v[2]);
  } else {
    std::vector<double> v;
    if (pose.IsSequence() && pose.size() == 7) {
      // [tx, ty, tz, qx, qy, qz, qw]: the translation and the quaternion as tf_echo prints them (ROS order).
      v = finiteNumbers(path, pose, "camera_pose", 7);
      const Eigen::Vector3d tu = io_detail::thetaUOfQuaternion(
          v[3], v[4], v[5], v[6], [&](const std::string &why) { throwError(where(path, pose.Mark()) + "'camera_pose': " + why); });
      v = {v[0], v[1], v[2], tu.x(), tu.y(), tu.z()};
    } else {
      if (pose.IsSequence() && pose.size() != 6)
        throwError(where(path, pose.Mark()) + "'camera_pose' must be a sequence of 6 numbers (it has " +
                   std::to_string(pose.size()) + "): [tx, ty, tz, tux, tuy, tuz], or 7 with a quaternion [tx, ty, tz, "
                                                 "qx, qy, qz, qw]");
      v = finiteNumbers(path, pose, "camera_pose", 6);
    }
    // theta-u beyond pi is the same rotation as a smaller one, but a file with it is more likely wrong.
    if (!(Eigen::Vector3d(v[3], v[4], v[5]).norm() <= M_PI + 1e-6)) // printed digits of a half turn
      throwError(where(path, pose.Mark()) + "'camera_pose' rotation (tux, tuy, tuz) must have a norm of at most pi");
    rig.camera_pose = vpPoseVector(v[0], v[1], v[2], v[3], v[4], v[5]);
    rig.camera_offset = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  const YAML::Node pose_sigma = root["camera_pose_sigma"];
  if (pose_sigma) {
    if (!pose)
      throwError(where(path, pose_sigma.Mark()) + "'camera_pose_sigma' without 'camera_pose'");
    const std::vector<double> v = finiteNumbers(path, pose_sigma, "camera_pose_sigma", 6);
    rig.camera_pose_sigma = Eigen::Matrix<double, 6, 1>(v.data());
  }
}

/* The yaw (yaw_mark: its key's mark, for a key without a value) and the yaw offset. */
void readYaw(const std::string &path, const YAML::Node &root, const YAML::Mark &yaw_mark, RigFile &rig)
{
  const YAML::Node yaw = root["yaw"];
  if (yaw && !yaw.IsNull())
    rig.yaw = finiteNumber(path, yaw, "'yaw'");
  else if (yaw)
    throwError(where(path, yaw_mark) + "'yaw' has no value");

  const YAML::Node yaw_offset = root["yaw_offset"];
  if (yaw_offset) {
    if (yaw_offset.IsNull())
      throwError(where(path, yaw_offset.Mark()) + "'yaw_offset' has no value");
    rig.yaw_offset = finiteNumber(path, yaw_offset, "'yaw_offset'");
  }
}

/* The yaw axis, normalised: non-zero and within 2 deg of the vision frame's +Y. */
Eigen::Vector3d readYawAxis(const std::string &path, const YAML::Node &axis)
{
  if (!axis.IsSequence() || axis.size() != 3)
    throwError(where(path, axis.Mark()) + "'yaw_axis' must be a sequence of 3 numbers [x, y, z]");
  Eigen::Vector3d a;
  for (std::size_t i = 0; i < 3; ++i)
    a(static_cast<Eigen::Index>(i)) = finiteNumber(path, axis[i], "'yaw_axis' value " + std::to_string(i + 1));
  if (!(a.norm() > 1e-9))
    throwError(where(path, axis.Mark()) + "'yaw_axis' must not be zero");
  Eigen::Vector3d yaw_axis = a.normalized();
  // The estimators turn the camera about the vision frame's +Y: an axis far from it would be
  // silently wrong, so it is refused (a measured tilt of a degree or two is tolerated).
  constexpr double kMaxAxisTiltDeg = 2.0;
  const double tilt = std::acos(std::clamp(yaw_axis.y(), -1.0, 1.0)) * 180.0 / M_PI;
  if (!(tilt <= kMaxAxisTiltDeg))
    throwError(where(path, axis.Mark()) + "'yaw_axis' is " + std::to_string(static_cast<int>(tilt)) + "." +
               std::to_string(static_cast<int>(std::lround(tilt * 10)) % 10) +
               " deg from the vision frame's +Y; the estimators model the yaw axis along +Y, within 2 deg: "
               "level the mechanism or correct the file");
  return yaw_axis;
}

} // namespace

RigFile readRigFile(const std::string &path)
{
  const std::string text = readTextFile(path, kMaxRigFileBytes);
  checkRigText(path, text);

  RigFile rig;
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root || root.IsNull())
      throwError(path + ": empty file (no YAML content)");
    if (!root.IsMap())
      throwError(where(path, root.Mark()) + "not a YAML map of keys (expected 'camera_offset: [x, y, z]')");
    const YAML::Mark yaw_mark = checkRigKeys(path, root);
    readMount(path, root, rig);
    readYaw(path, root, yaw_mark, rig);
    const YAML::Node axis = root["yaw_axis"];
    if (axis)
      rig.yaw_axis = readYawAxis(path, axis);
    if (const YAML::Node t = root["time_offset"])
      rig.time_offset = finiteNumber(path, t, "'time_offset'");
    if (const YAML::Node t = root["time_offset_sigma"]) {
      rig.time_offset_sigma = finiteNumber(path, t, "'time_offset_sigma'");
      if (*rig.time_offset_sigma < 0)
        throwError(where(path, t.Mark()) + "'time_offset_sigma' must not be negative");
    }
  } catch (const YAML::Exception &e) {
    throwError(where(path, e.mark) + "not valid YAML (" + e.msg + ")");
  }
  return rig;
}

YawRig rigOf(const RigFile &rig)
{
  if (rig.camera_pose)
    return YawRig(vpHomogeneousMatrix(*rig.camera_pose));
  return YawRig(rig.camera_offset);
}

void writeRigFile(const std::string &path, const RigFile &rig)
{
  if (!rig.camera_offset.allFinite())
    throwError(path + ": camera_offset is not finite");
  if (rig.yaw && !std::isfinite(*rig.yaw))
    throwError(path + ": yaw is not finite");
  auto list = [](const double *v, int n) {
    std::string s = "[";
    for (int i = 0; i < n; ++i)
      s += (i ? ", " : "") + formatNumber(v[i]);
    return s + "]";
  };
  std::string out;
  if (rig.camera_pose) {
    const vpPoseVector &p = *rig.camera_pose;
    const double v[6] = {p[0], p[1], p[2], p[3], p[4], p[5]};
    for (double x : v)
      if (!std::isfinite(x))
        throwError(path + ": camera_pose is not finite");
    out = "camera_pose: " + list(v, 6) + "\n";
    if (rig.camera_pose_sigma) {
      if (!rig.camera_pose_sigma->allFinite())
        throwError(path + ": camera_pose_sigma is not finite");
      out += "camera_pose_sigma: " + list(rig.camera_pose_sigma->data(), 6) + "\n";
    }
  } else {
    out = "camera_offset: " + list(rig.camera_offset.data(), 3) + "\n";
  }
  if (rig.yaw)
    out += "yaw: " + formatNumber(*rig.yaw) + "\n";
  if (!std::isfinite(rig.yaw_offset))
    throwError(path + ": yaw_offset is not finite");
  if (rig.yaw_offset != 0.0)
    out += "yaw_offset: " + formatNumber(rig.yaw_offset) + "\n";
  if (rig.yaw_axis) {
    if (!rig.yaw_axis->allFinite())
      throwError(path + ": yaw_axis is not finite");
    out += "yaw_axis: [" + formatNumber(rig.yaw_axis->x()) + ", " + formatNumber(rig.yaw_axis->y()) + ", " +
           formatNumber(rig.yaw_axis->z()) + "]\n";
  }
  if (rig.time_offset) {
    if (!std::isfinite(*rig.time_offset))
      throwError(path + ": time_offset is not finite");
    out += "time_offset: " + formatNumber(*rig.time_offset) + "\n";
  }
  if (rig.time_offset_sigma) {
    if (!std::isfinite(*rig.time_offset_sigma))
      throwError(path + ": time_offset_sigma is not finite");
    out += "time_offset_sigma: " + formatNumber(*rig.time_offset_sigma) + "\n";
  }
  writeFileAtomically(path, out);
}

void applyRigFile(const RigFile &rig, std::vector<MotionSample> &motion)
{
  if (rig.yaw_offset != 0.0)
    for (MotionSample &s : motion)
      s.yaw += rig.yaw_offset;
}

} // namespace yawdepth
