#include "csv.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <vector>
#include <tuple>
#include <yawdepth/error.h>
#include <yawdepth/geometry/track_inputs.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

using io_detail::CsvReader;
using io_detail::formatNumber;
using io_detail::throwError;

std::vector<Track> readTracksCsv(const std::string &path, const InputLimits &limits)
{
  CsvReader csv(path, limits);
  const std::size_t c_frame = csv.requireColumn("frame");
  const std::size_t c_id = csv.requireColumn("id");
  const std::size_t c_u = csv.requireColumn("u");
  const std::size_t c_v = csv.requireColumn("v");

  struct Obs {
    Observation o;
    std::size_t line;
  };
  std::map<long, std::vector<Obs>> by_id;
  bool any = false;
  while (csv.next()) {
    Obs ob;
    ob.o.frame = csv.integer(c_frame);
    const long id = csv.integer(c_id);
    ob.o.u = csv.number(c_u);
    ob.o.v = csv.number(c_v);
    ob.line = csv.line();
    by_id[id].push_back(ob);
    any = true;
  }
  if (!any)
    csv.failFile("no data rows after the header");

  std::vector<Track> tracks;
  tracks.reserve(by_id.size());
  for (auto &[id, obs] : by_id) {
    std::stable_sort(obs.begin(), obs.end(), [](const Obs &a, const Obs &b) { return a.o.frame < b.o.frame; });
    Track t;
    t.id = id;
    t.observations.reserve(obs.size());
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if (i > 0 && obs[i].o.frame == obs[i - 1].o.frame) {
        const std::size_t a = std::min(obs[i].line, obs[i - 1].line), b = std::max(obs[i].line, obs[i - 1].line);
        csv.failAt(b, "feature " + std::to_string(id) + " is observed twice in frame " +
                          std::to_string(obs[i].o.frame) + " (first at line " + std::to_string(a) + ")");
      }
      t.observations.push_back(obs[i].o);
    }
    tracks.push_back(std::move(t));
  }
  return tracks;
}

void checkTracksAgainstMotion(const std::vector<Track> &tracks, const MotionLog &motion,
                              const std::string &tracks_path)
{
  try {
    validateInputs(motion.samples, tracks); // the estimators' rules, in one place
  } catch (const Error &e) {
    throwError(tracks_path + ": " + e.what());
  }
}

void writeTracksCsv(const std::string &path, const std::vector<Track> &tracks)
{
  struct Row {
    long frame, id;
    double u, v;
  };
  std::vector<Row> rows;
  for (const Track &t : tracks)
    for (const Observation &o : t.observations) {
      if (!std::isfinite(o.u) || !std::isfinite(o.v))
        throwError(path + ": feature " + std::to_string(t.id) + " has a non-finite pixel in frame " +
                   std::to_string(o.frame));
      rows.push_back({o.frame, t.id, o.u, o.v});
    }
  std::stable_sort(rows.begin(), rows.end(),
                   [](const Row &a, const Row &b) { return std::tie(a.frame, a.id) < std::tie(b.frame, b.id); });
  std::string out = "frame,id,u,v\n";
  for (const Row &r : rows) {
    out += std::to_string(r.frame);
    out += ',';
    out += std::to_string(r.id);
    out += ',';
    out += formatNumber(r.u);
    out += ',';
    out += formatNumber(r.v);
    out += '\n';
  }
  writeFileAtomically(path, out);
}

void checkMotionSteps(const MotionLog &motion, const std::string &motion_path)
{
  const std::vector<MotionSample> &m = motion.samples;
  if (m.size() < 2)
    return;
  std::vector<double> steps;
  steps.reserve(m.size() - 1);
  for (std::size_t k = 1; k < m.size(); ++k)
    steps.push_back((m[k].position() - m[k - 1].position()).norm());
  std::vector<double> sorted; // the finite steps (a non-finite one is refused below)
  for (double d : steps)
    if (std::isfinite(d))
      sorted.push_back(d);
  double median = 0;
  if (!sorted.empty()) {
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
    median = sorted[sorted.size() / 2];
  }
  constexpr double kMaxRatio = 1000, kMinJump = 1.0, kMinScale = 0.01;
  const double limit = std::max(kMinJump, kMaxRatio * std::max(median, kMinScale));
  for (std::size_t k = 1; k < m.size(); ++k) {
    const auto where = [&]() { return motion_path + ": the row of frame " + std::to_string(m[k].frame); };
    const double step = steps[k - 1];
    if (!(step <= limit)) {
      std::ostringstream msg;
      msg << where() << " is " << step << " m from the previous row, over " << limit
          << " m (1000 times the log's median step of " << median << " m): a glitch in the log?";
      throw Error(msg.str());
    }
    const double dyaw = std::abs(m[k].yaw - m[k - 1].yaw);
    const double dheading = m[k].six_dof ? 0.0 : std::abs(m[k].heading - m[k - 1].heading);
    // One wrap of the angle (+pi to -pi: a difference up to 2 pi + pi) is a reading's convention;
    // beyond, the reading jumped.
    constexpr double kMaxTurn = 3 * M_PI;
    if (!(dyaw <= kMaxTurn) || !(dheading <= kMaxTurn)) {
      std::ostringstream msg;
      msg << where() << " turns the " << (dyaw > kMaxTurn ? "yaw" : "heading") << " by "
          << (dyaw > kMaxTurn ? dyaw : dheading)
          << " rad from the previous row: more than a wrap of the angle plus half a turn, not a reading of one motion";
      throw Error(msg.str());
    }
  }
}

namespace {
constexpr double kFullTurn = 2 * M_PI;
constexpr double kMaxPlausibleStep = 1.0; // rad between two rows
constexpr double kMaxLeverArm = 2.0;      // m from the vision frame's origin to the camera

std::string number(double v)
{
  std::ostringstream out;
  out << v;
  return out.str();
}
} // namespace

std::vector<std::string> motionWarnings(const MotionLog &motion, const std::string &motion_path)
{
  std::vector<std::string> out;
  const std::vector<MotionSample> &m = motion.samples;
  const auto angles = [&](const char *name, auto value, bool present, bool winds) {
    if (!present || m.empty())
      return;
    double largest = 0, step = 0;
    long at = m.front().frame;
    for (std::size_t k = 0; k < m.size(); ++k) {
      largest = std::max(largest, std::abs(value(m[k])));
      const double d = k > 0 ? std::abs(wrapAngle(value(m[k]) - value(m[k - 1]))) : 0.0;
      if (d > step) {
        step = d;
        at = m[k].frame;
      }
    }
    if (!winds && largest > kFullTurn)
      out.push_back(motion_path + ": the " + name + " column reaches " + number(largest) +
                    " rad, beyond a full turn: degrees given as radians?");
    else if (step > kMaxPlausibleStep)
      out.push_back(motion_path + ": the " + name + " turns by " + number(step) + " rad at frame " +
                    std::to_string(at) + ": degrees given as radians?");
  };
  const bool six = !m.empty() && m.front().six_dof;
  // A heading winds up as the robot turns; a pan joint seldom passes a full turn.
  angles("yaw", [](const MotionSample &s) { return s.yaw; }, motion.yaw_column, false);
  angles("heading", [](const MotionSample &s) { return s.heading; }, !six, true);
  if (six)
    for (const MotionSample &s : m)
      if (s.theta_u.norm() > M_PI + 1e-9) {
        out.push_back(motion_path + ": the theta-u rotation of frame " + std::to_string(s.frame) + " is " +
                      number(s.theta_u.norm()) + " rad, beyond half a turn: degrees given as radians?");
        break;
      }
  return out;
}

std::vector<std::string> rigWarnings(const RigFile &rig, const std::string &rig_path)
{
  std::vector<std::string> out;
  const Eigen::Vector3d t = rig.camera_pose ? Eigen::Vector3d((*rig.camera_pose)[0], (*rig.camera_pose)[1], (*rig.camera_pose)[2])
                                            : rig.camera_offset;
  if (t.norm() > kMaxLeverArm)
    out.push_back(rig_path + ": the camera is " + number(t.norm()) + " m from the vision frame's origin (" +
                  (rig.camera_pose ? "camera_pose" : "camera_offset") + "): millimetres given as metres?");
  if (std::abs(rig.yaw_offset) > kFullTurn)
    out.push_back(rig_path + ": yaw_offset is " + number(rig.yaw_offset) + " rad, beyond a full turn: degrees?");
  return out;
}

} // namespace yawdepth
