#pragma once
/*
  castle_truth.h: what bench_castle and bench_wide_baseline share about Debian's visp-images-data
  mbt-depth/Castle-simu: its depth maps (Depth/Depth_NNNN.bin), poses (CameraPose/Camera_NNN.txt), the
  cameras, and the truth of a pixel's depth (where its ray first meets the depth map's surface; see
  bench_castle.cpp). Header-only, not installed.
*/
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>
#include <Eigen/Core>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/core/types.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bench {
namespace castle {

/* The depth maps are rendered from a second camera (an RGB-D pair): the same intrinsics, the same
   axes, its centre 5 cm along the colour camera's -X (ViSP's own test of this sequence sets
   depth_M_color[0][3] = -0.05; the maps' content sits 60-70 px left of the images' at 0.5-0.6 m,
   700 x 0.05 / Z). */
inline const Eigen::Vector3d kDepthFromColour(-0.05, 0.0, 0.0);
/* Both cameras' intrinsics (Config/chateau.xml, chateau_depth.xml). */
constexpr double kFocal = 700.0, kU0 = 320.0, kV0 = 240.0;
/* A feature within this many pixels of an occluding edge of the depth map has no truth: a corner
   on a silhouette may be on either surface, and the two cameras see the edge from 5 cm apart. */
constexpr int kEdgePx = 3;
/* A ray that passes an occluding edge of the map within this share of its depth from the surface, on
   its way to the surface it meets, grazes a silhouette: a corner there may be on either side. */
constexpr double kGraze = 0.03;

struct DepthMap {
  int width = 0, height = 0;
  std::vector<float> z; // m, 0 = no depth
  float at(int u, int v) const { return z[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)]; }
};

inline DepthMap readDepth(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error(path + ": cannot open");
  unsigned char head[8];
  if (!in.read(reinterpret_cast<char *>(head), 8))
    throw Error(path + ": truncated header");
  const auto le32 = [](const unsigned char *b) {
    return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
           static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
  };
  DepthMap d;
  const std::uint32_t h = le32(head), w = le32(head + 4);
  if (h == 0 || w == 0 || h > 10000 || w > 10000)
    throw Error(path + ": implausible size " + std::to_string(w) + "x" + std::to_string(h));
  d.height = static_cast<int>(h);
  d.width = static_cast<int>(w);
  std::vector<unsigned char> raw(static_cast<std::size_t>(h) * w * 2);
  if (!in.read(reinterpret_cast<char *>(raw.data()), static_cast<std::streamsize>(raw.size())))
    throw Error(path + ": truncated depth data");
  d.z.resize(static_cast<std::size_t>(h) * w);
  for (std::size_t i = 0; i < d.z.size(); ++i)
    d.z[i] = static_cast<float>((raw[2 * i] | raw[2 * i + 1] << 8) / 32768.0);
  return d;
}

inline vpHomogeneousMatrix readPose(const std::string &path)
{
  std::ifstream in(path);
  if (!in)
    throw Error(path + ": cannot open");
  vpHomogeneousMatrix M;
  for (unsigned i = 0; i < 4; ++i)
    for (unsigned j = 0; j < 4; ++j)
      if (!(in >> M[i][j]))
        throw Error(path + ": expected a 4x4 matrix");
  if (!M.isAnHomogeneousMatrix(1e-6))
    throw Error(path + ": not a rigid transformation");
  return M;
}

/* Frames 1..frames of the sequence: the camera's motion (world = the object's frame, wMc = cMo^-1),
   the images' paths, the depth maps. */
struct Sequence {
  std::vector<MotionSample> motion;
  std::vector<std::string> images;
  std::vector<DepthMap> depth;
};

/* Reads frames 1..frames of the sequence in folder `data` (the images are read by the caller). */
inline Sequence readSequence(const std::string &data, int frames)
{
  Sequence q;
  char name[64];
  for (int k = 1; k <= frames; ++k) {
    std::snprintf(name, sizeof name, "/CameraPose/Camera_%03d.txt", k);
    q.motion.push_back(MotionSample::fromPose(k, readPose(data + name).inverse(), 0.0));
    std::snprintf(name, sizeof name, "/Images/Image_%04d.pgm", k);
    q.images.push_back(data + name);
    std::snprintf(name, sizeof name, "/Depth/Depth_%04d.bin", k);
    q.depth.push_back(readDepth(data + name));
  }
  return q;
}


/* The depth map at a sub-pixel position, bilinear; NaN outside, without depth or across an occluding
   edge (the 2x2 cell spans more than 2 % of depth). */
inline double bilinearDepth(const DepthMap &d, double u, double v)
{
  const int iu = static_cast<int>(std::floor(u)), iv = static_cast<int>(std::floor(v));
  if (iu < 0 || iv < 0 || iu >= d.width - 1 || iv >= d.height - 1)
    return std::nan("");
  const double z00 = d.at(iu, iv), z10 = d.at(iu + 1, iv), z01 = d.at(iu, iv + 1), z11 = d.at(iu + 1, iv + 1);
  const double lo = std::min({z00, z10, z01, z11}), hi = std::max({z00, z10, z01, z11});
  if (!(lo > 0) || hi > 1.02 * lo)
    return std::nan("");
  const double a = u - iu, b = v - iv;
  return (1 - a) * (1 - b) * z00 + a * (1 - b) * z10 + (1 - a) * b * z01 + a * b * z11;
}

/* Whether the depth map spans more than 2 % of depth within kEdgePx pixels of where the ray meets it
   at depth z (x, y: the ray's normalised coordinates): a point there may be on either surface. */
inline bool occludingEdgeNear(const DepthMap &d, double x, double y, double z)
{
  const Eigen::Vector3d d_P = Eigen::Vector3d(x * z, y * z, z) + kDepthFromColour;
  const int iu = static_cast<int>(std::lround(kFocal * d_P.x() / d_P.z() + kU0));
  const int iv = static_cast<int>(std::lround(kFocal * d_P.y() / d_P.z() + kV0));
  float lo = 1e9f, hi = 0;
  for (int dv = -kEdgePx; dv <= kEdgePx; ++dv)
    for (int du = -kEdgePx; du <= kEdgePx; ++du) {
      const int u = iu + du, v = iv + dv;
      const float zz = u >= 0 && v >= 0 && u < d.width && v < d.height ? d.at(u, v) : 0.0f;
      lo = std::min(lo, zz);
      hi = std::max(hi, zz);
    }
  return !(lo > 0) || hi > 1.02f * lo;
}

/* Depth (the colour camera's Z) where the ray of colour pixel (u, v) first meets the depth map's
   surface; NaN when it meets none, or where the map has no usable depth (see the file). */
inline double rayTruth(const DepthMap &d, double u, double v)
{
  const double x = (u - kU0) / kFocal, y = (v - kV0) / kFocal;
  // The gap between the ray's depth and the map's at the depth camera's pixel of the ray at depth z.
  const auto gap = [&](double z) {
    const Eigen::Vector3d d_P = Eigen::Vector3d(x * z, y * z, z) + kDepthFromColour;
    return z - bilinearDepth(d, kFocal * d_P.x() / d_P.z() + kU0, kFocal * d_P.y() / d_P.z() + kV0);
  };
  double z_prev = 0, g_prev = std::nan("");
  bool grazed = false; // the ray passed an occluding edge within kGraze of a surface: it may hit either side
  for (double z = 0.05; z < 5.0; z *= 1.002) { // steps of 0.2 %: under a pixel of epipolar motion
    const double g = gap(z);
    if (std::isfinite(g) != std::isfinite(g_prev) && z_prev > 0 &&
        std::abs(std::isfinite(g) ? g : g_prev) < kGraze * z)
      grazed = true;
    if (std::isfinite(g) && std::isfinite(g_prev) && g_prev < 0 && g >= 0) {
      if (grazed)
        return std::nan("");
      double lo = z_prev, hi = z;
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (lo + hi), gm = gap(mid);
        if (!std::isfinite(gm))
          return std::nan(""); // the crossing is on an occluding edge
        (gm < 0 ? lo : hi) = mid;
      }
      const double z_hit = 0.5 * (lo + hi);
      return occludingEdgeNear(d, x, y, z_hit) ? std::nan("") : z_hit;
    }
    if (std::isfinite(g) && g >= 0 && !std::isfinite(g_prev) && z_prev > 0)
      return std::nan(""); // came out from behind an edge already past the surface
    z_prev = z;
    g_prev = g;
  }
  return std::nan("");
}

} // namespace castle
} // namespace bench
} // namespace yawdepth
