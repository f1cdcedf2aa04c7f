// PLY point clouds of the measured points (`--ply FILE`).
#include "csv.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

using io_detail::formatNumber;

std::vector<PlyPoint> plyPoints(const YawRig &rig, const std::vector<MotionSample> &samples,
                                const std::vector<PointRow> &rows, const std::map<std::pair<long, long>, int> &gray)
{
  std::map<long, const MotionSample *> by_frame;
  for (const MotionSample &s : samples)
    by_frame[s.frame] = &s;
  std::vector<PlyPoint> points;
  for (const PointRow &r : rows) {
    const PointEstimate &e = r.estimate;
    if (!e.ok())
      continue;
    const auto it = by_frame.find(e.frame);
    if (it == by_frame.end())
      throw Error("point cloud: point " + std::to_string(r.id) + " is at frame " + std::to_string(e.frame) +
                  ", which the motion does not have");
    const vpHomogeneousMatrix wMc_frame = wMc(rig, *it->second);
    PlyPoint p;
    p.id = r.id;
    for (int k = 0; k < 3; ++k)
      p.w_P[k] = wMc_frame[k][0] * e.c_P.x() + wMc_frame[k][1] * e.c_P.y() + wMc_frame[k][2] * e.c_P.z() + wMc_frame[k][3];
    p.sigma_z = e.sigmaZ();
    const auto g = gray.find({e.frame, r.id});
    p.gray = g == gray.end() ? -1 : g->second;
    if (!p.w_P.allFinite())
      throw Error("point cloud: point " + std::to_string(r.id) + " is not finite in the world frame");
    points.push_back(p);
  }
  return points;
}

std::string plyText(const std::vector<PlyPoint> &points)
{
  bool colour = !points.empty();
  for (const PlyPoint &p : points) {
    if (p.gray > 255)
      throw Error("point cloud: gray level " + std::to_string(p.gray) + " of point " + std::to_string(p.id) +
                  " is above 255");
    if (p.id < INT32_MIN || p.id > INT32_MAX)
      throw Error("point cloud: feature id " + std::to_string(p.id) + " does not fit PLY's int (32 bits)");
    colour = colour && p.gray >= 0;
  }
  std::string out = "ply\nformat ascii 1.0\n"
                    "comment yawdepth points: x y z in the motion log's world frame (m), sigma_z the 1-sigma depth (m)\n"
                    "element vertex " +
                    std::to_string(points.size()) +
                    "\nproperty double x\nproperty double y\nproperty double z\n";
  if (colour)
    out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "property double sigma_z\nproperty int id\nend_header\n";
  for (const PlyPoint &p : points) {
    out += formatNumber(p.w_P.x()) + ' ' + formatNumber(p.w_P.y()) + ' ' + formatNumber(p.w_P.z());
    if (colour) {
      const std::string g = std::to_string(p.gray);
      out += ' ' + g + ' ' + g + ' ' + g;
    }
    out += ' ' + formatNumber(p.sigma_z) + ' ' + std::to_string(p.id) + '\n';
  }
  return out;
}

void writePointsPly(const std::string &path, const std::vector<PlyPoint> &points)
{
  writeFileAtomically(path, plyText(points));
}

} // namespace yawdepth
