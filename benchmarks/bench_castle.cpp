/*
  bench_castle: natural-feature depth on someone else's rendered sequence, against its depth maps.

    bench_castle [--data DIR] [--frames N] [--max-features N] [--sigma-px S]

  Data: Debian's visp-images-data, mbt-depth/Castle-simu (ViSP's RGB-D tracker test sequence): 40
  rendered 640x480 gray images of a castle model, a 700 px pinhole camera (Config/chateau.xml),
  the ground-truth pose of the object in each camera (CameraPose/Camera_NNN.txt, cMo, 4x4) and a
  depth map per frame (Depth/Depth_NNNN.bin: height and width as little-endian uint32, then one
  little-endian uint16 per pixel, Z = value / 32768 m, 0 where nothing was rendered).

  The camera's motion is the given poses (world = the object's frame, wMc = cMo^-1, a 6-DoF log
  with absolute noise 0.1 mm and 0.1 mrad). Tracks: yawdepth::trackSequence (KLT with the epipolar
  gate); points: the window estimator, each at its last frame. Each ok point is moved into that
  frame's depth camera (5 cm beside the colour camera, see kDepthFromColour) and its depth compared
  with the depth map at its pixel there (nearest pixel; a point whose 3x3 neighbourhood has no
  depth or spans more than 2 % of depth, an occluding edge, has no truth and is counted apart).
  Reported: points per frame, median and 95th-percentile relative depth error, the share within
  2 sigma (the estimator's own), the largest error; for every ok point and for those whose own
  relative sigma is under 1 %.
*/
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <yawdepth/error.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/window/window_estimator.h>

#include "bench_common.h"

using namespace yawdepth;

namespace {

/* The depth maps are rendered from a second camera (an RGB-D pair): the same intrinsics, the same
   axes, its centre 5 cm along the colour camera's -X (ViSP's own test of this sequence sets
   depth_M_color[0][3] = -0.05; the maps' content sits 60-70 px left of the images' at 0.5-0.6 m,
   700 x 0.05 / Z). */
const Eigen::Vector3d kDepthFromColour(-0.05, 0.0, 0.0);

struct DepthMap {
  int width = 0, height = 0;
  std::vector<float> z; // m, 0 = no depth
  float at(int u, int v) const { return z[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)]; }
};

DepthMap readDepth(const std::string &path)
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

vpHomogeneousMatrix readPose(const std::string &path)
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

/* Depth truth at a pixel: NaN without depth, at the image border or across an occluding edge. */
double truthAt(const DepthMap &d, double u, double v)
{
  const int iu = static_cast<int>(std::lround(u)), iv = static_cast<int>(std::lround(v));
  if (iu < 1 || iv < 1 || iu >= d.width - 1 || iv >= d.height - 1)
    return std::nan("");
  float lo = 1e9f, hi = 0;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const float z = d.at(iu + du, iv + dv);
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
  if (!(lo > 0) || hi > 1.02f * lo)
    return std::nan("");
  return d.at(iu, iv);
}

double quantile(std::vector<double> v, double q)
{
  if (v.empty())
    return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[k];
}

/* The command line's values. */
struct Args {
  std::string data = "/usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu";
  int frames = 40, max_features = 300;
  double sigma_px = 0.3;
};

/* Frames 1..frames of the sequence: the camera's motion (world = the object's frame), the images' paths, the depth maps. */
struct Sequence {
  std::vector<MotionSample> motion;
  std::vector<std::string> images;
  std::vector<DepthMap> depth;
};

/* Reads frames 1..frames of the sequence in folder `data`. */
Sequence readSequence(const std::string &data, int frames)
{
  Sequence q;
  char name[64];
  for (int k = 1; k <= frames; ++k) {
    std::snprintf(name, sizeof name, "/CameraPose/Camera_%03d.txt", k);
    const vpHomogeneousMatrix cMo = readPose(data + name);
    q.motion.push_back(MotionSample::fromPose(k, cMo.inverse(), 0.0));
    std::snprintf(name, sizeof name, "/Images/Image_%04d.pgm", k);
    q.images.push_back(data + name);
    std::snprintf(name, sizeof name, "/Depth/Depth_%04d.bin", k);
    q.depth.push_back(readDepth(data + name));
  }
  return q;
}

/* The estimator's noise model: sigma_px on the pixels, the given poses' absolute 0.1 mm and 0.1 mrad. */
NoiseModel castleNoise(double sigma_px)
{
  NoiseModel noise;
  noise.sigma_px = sigma_px;
  noise.motion_noise = MotionNoise::Absolute;
  noise.sigma_odom = 1e-4;
  noise.sigma_rot = 1e-4;
  noise.sigma_yaw = 0;
  return noise;
}

/* One ok point against the depth map: relative depth error, own relative sigma, error within 2 sigma. */
struct Row {
  double rel, sigma_rel;
  bool within;
};

/* Every ok point against the depth map of its last frame; `ok` counts them, `no_truth` those without truth there. */
std::vector<Row> compareWithDepth(const std::vector<PointEstimate> &est, const std::vector<Track> &tracks,
                                  const std::vector<DepthMap> &depth, int frames, int &ok, int &no_truth)
{
  std::vector<Row> rows;
  ok = no_truth = 0;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const PointEstimate &e = est[i];
    if (!e.ok())
      continue;
    ++ok;
    const Track &t = tracks[i];
    const auto obs = std::find_if(t.observations.begin(), t.observations.end(),
                                  [&](const Observation &o) { return o.frame == e.frame; });
    if (obs == t.observations.end() || e.frame < 1 || e.frame > frames) {
      ++no_truth;
      continue;
    }
    // The point in the depth camera: 5 cm to the colour camera's left (x - 0.05), same axes.
    const Eigen::Vector3d d_P = e.c_P + kDepthFromColour;
    const double z = truthAt(depth[static_cast<std::size_t>(e.frame - 1)], 700.0 * d_P.x() / d_P.z() + 320.0,
                             700.0 * d_P.y() / d_P.z() + 240.0);
    if (!std::isfinite(z)) {
      ++no_truth;
      continue;
    }
    const double err = d_P.z() - z;
    rows.push_back({std::abs(err) / z, e.sigmaZ() / e.c_P.z(), std::abs(err) <= 2 * e.sigmaZ()});
  }
  return rows;
}

/* The table: every ok point with truth, then those whose own relative sigma is under 1 %. */
void printTable(const std::vector<Row> &rows, int frames)
{
  std::printf("| points | count | per frame | median rel. error | 95th pct | within 2 sigma | largest |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (int subset = 0; subset < 2; ++subset) {
    std::vector<double> rel;
    int within = 0;
    for (const Row &r : rows)
      if (subset == 0 || r.sigma_rel < 0.01) {
        rel.push_back(r.rel);
        within += r.within ? 1 : 0;
      }
    const std::string label = subset == 0 ? "every ok point with truth" : "own sigma under 1 %";
    std::printf("| %s | %zu | %.1f | %.3f %% | %.3f %% | %.3f | %.2f %% |\n", label.c_str(), rel.size(),
                static_cast<double>(rel.size()) / frames, 100 * quantile(rel, 0.5), 100 * quantile(rel, 0.95),
                rel.empty() ? 0.0 : static_cast<double>(within) / static_cast<double>(rel.size()),
                rel.empty() ? 0.0 : 100 * *std::max_element(rel.begin(), rel.end()));
  }
}

} // namespace

int main(int argc, char **argv)
{
  Args a;
  bench::CommandLine cli("[--data DIR] [--frames N (2-40)] [--max-features N] [--sigma-px S]");
  cli.option("--data", a.data).option("--frames", a.frames);
  cli.option("--max-features", a.max_features).option("--sigma-px", a.sigma_px);
  if (!cli.parse(argc, argv))
    return 2;
  if (a.frames < 2 || a.frames > 40 || a.max_features < 1 || !(a.sigma_px > 0)) {
    std::fprintf(stderr, "bench_castle: --frames must be in [2, 40], --max-features >= 1, --sigma-px > 0\n");
    return 2;
  }
  try {
    const CameraModel camera = CameraModel::brown(700, 700, 320, 240, {0, 0, 0, 0}, 640, 480);
    const YawRig rig; // the camera is the vision frame
    const Sequence q = readSequence(a.data, a.frames);
    const NoiseModel noise = castleNoise(a.sigma_px);
    KltOptions ko;
    ko.max_features = a.max_features;
    const auto t0 = std::chrono::steady_clock::now();
    const SequenceTracks seq = trackSequence(camera, rig, q.motion, q.images, noise, ko);
    const auto t1 = std::chrono::steady_clock::now();
    WindowOptions wo;
    wo.noise = noise;
    const std::vector<PointEstimate> est = windowTracks(camera, rig, q.motion, seq.tracks, wo);
    const auto t2 = std::chrono::steady_clock::now();
    int ok = 0, no_truth = 0;
    const std::vector<Row> rows = compareWithDepth(est, seq.tracks, q.depth, a.frames, ok, no_truth);

    const double track_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    const double est_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
    std::printf("yawdepth on Castle-simu (visp-images-data mbt-depth, someone else's renderer): KLT tracks + window "
                "estimator vs the depth maps\n");
    std::printf("Reproduce: build/benchmarks/bench_castle --frames %d --max-features %d --sigma-px %g\n", a.frames,
                a.max_features, a.sigma_px);
    std::printf("%d frames; %zu tracks over 2+ frames (%d detected; cut: %d epipolar, %d forward-backward); %d ok "
                "points, %d without depth truth (background, occluding edge)\n",
                a.frames, seq.tracks.size(), seq.totals.detected, seq.totals.lost_epipolar, seq.totals.lost_fb, ok,
                no_truth);
    std::printf("tracking %.1f ms/frame, estimation %.1f ms/frame (this machine, one core)\n", track_ms / a.frames,
                est_ms / a.frames);
    printTable(rows, a.frames);
  } catch (const Error &e) {
    std::fprintf(stderr, "bench_castle: %s\n", e.what());
    return 1;
  }
  return 0;
}
