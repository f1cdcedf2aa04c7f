/*
  bench_refine_scale: time and memory of `refine` (refineWindow: the robust solve, the final solve
  and every point's covariance) against the number of points and frames. Plain-text table on stdout.

    bench_refine_scale [--points P,P,...] [--frames F,F,...] [--scene in-view|wall|both]
                       [--threads T] [--limit S] [--seed N]
  --points   point counts (default 100,300,1000)
  --frames   frame counts (default 100,200,500,1000)
  --scene    in-view: every point seen in every frame (side view, 1 mm per frame, points 2 to 3 m
             away: the densest problem, the motion of every frame tied to every point);
             wall: a robot driving past a wall of points 1.5 to 3 m to its side (2 cm per frame,
             yaw 60 deg, the paper's 21-degree lens), each point seen while it is in the image (40 to
             80 frames): the shape of a real long log. Default: both.
  --threads  RefineOptions::threads (default 1)
  --limit    seconds per case before it is stopped and reported as over the limit (default 600)
  --seed     scene seed (default 1)

  Each case runs in its own process (fork), so that its peak memory (the child's maximum resident
  set size, from wait4) is its own. Noise: 0.3 px, 1 mm and 0.05 deg per increment, yaw readings
  0.05 deg; 640x480 images. Times are wall-clock on this machine, scene generation not
  included; cov_s is the part of time_s spent on the covariances (after both solves).
*/
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include <yawdepth/refine/refine.h>
#include <yawdepth/simulation/scene.h>

using namespace yawdepth;

namespace {

constexpr double kDeg = M_PI / 180.0;
using Clock = std::chrono::steady_clock;

struct Outcome {
  double seconds = 0;
  double covariance_seconds = 0; // of seconds: every point's covariance (after the solves)
  long observations = 0;
  int iterations = 0;
  int ok = 0;
  double median_rel_err = 0;
};

std::vector<int> parseList(const char *s)
{
  std::vector<int> v;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty())
      v.push_back(std::atoi(item.c_str()));
  return v;
}

Scene makeScene(const CameraModel &camera, const YawRig &rig, bool wall, int points, int frames, std::uint64_t seed)
{
  SceneOptions so;
  so.frames = frames;
  so.seed = seed;
  so.noise = NoiseModel{0.3, 1e-3, 0.05 * kDeg, 0.05 * kDeg};
  if (!wall) {
    so.yaw = 90 * kDeg;
    so.step = 0.001;
    so.points = points;
    so.min_depth = 2.0;
    so.max_depth = 3.0;
    so.margin_px = 120; // 1 m of travel moves a point at 2 m by 300 px: start it well inside
  } else {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    so.yaw = 60 * kDeg;
    so.step = 0.02;
    const double length = frames * so.step + 4.0;
    for (int i = 0; i < points; ++i)
      so.world_points.emplace_back(1.5 + 1.5 * uni(rng), -0.3 + 0.6 * uni(rng), -1.0 + length * uni(rng));
  }
  return simulateScene(camera, rig, so);
}

Outcome runCase(bool wall, int points, int frames, int threads, std::uint64_t seed)
{
  // in-view: a wide lens (53 deg across), so that every point stays in view; wall: the paper's
  // camera (21 deg across), so that each point is seen for 40 to 80 frames.
  const CameraModel camera = wall ? CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {0, 0, 0, 0}, 640, 480)
                                  : CameraModel::brown(600, 600, 320, 240, {0, 0, 0, 0}, 640, 480);
  const YawRig rig(Eigen::Vector3d(-0.15, 0, 0));
  const Scene s = makeScene(camera, rig, wall, points, frames, seed);
  RefineOptions o;
  o.noise = NoiseModel{0.3, 1e-3, 0.05 * kDeg, 0.05 * kDeg};
  o.threads = threads;
  double covariance_start = -1;
  o.progress = [&covariance_start](const RefineProgress &p) {
    if (p.stage == RefineProgress::Stage::Covariance)
      covariance_start = p.seconds;
  };
  Outcome out;
  for (const Track &t : s.tracks)
    out.observations += static_cast<long>(t.observations.size());
  const auto t0 = Clock::now();
  const RefineResult r = refineWindow(camera, rig, s.measured, s.tracks, {}, o);
  out.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  out.covariance_seconds = covariance_start >= 0 ? out.seconds - covariance_start : 0;
  out.iterations = r.iterations;
  std::vector<double> err;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    if (r.points[i].status != Status::Ok)
      continue;
    ++out.ok;
    std::size_t row = 0;
    while (row + 1 < s.measured.size() && s.measured[row].frame != r.points[i].frame)
      ++row;
    const double z = s.cameraPoint(rig, s.tracks[i].id, row).z();
    err.push_back(std::abs(r.points[i].c_P.z() - z) / z);
  }
  if (!err.empty()) {
    std::nth_element(err.begin(), err.begin() + static_cast<long>(err.size() / 2), err.end());
    out.median_rel_err = err[err.size() / 2];
  }
  return out;
}

} // namespace

int main(int argc, char **argv)
{
  std::vector<int> point_counts{100, 300, 1000}, frame_counts{100, 200, 500, 1000};
  std::string scene = "both";
  int threads = 1, limit = 600;
  std::uint64_t seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "bench_refine_scale: %s needs a value\n", a.c_str());
      return 2;
    }
    const char *v = argv[++i];
    if (a == "--points")
      point_counts = parseList(v);
    else if (a == "--frames")
      frame_counts = parseList(v);
    else if (a == "--scene")
      scene = v;
    else if (a == "--threads")
      threads = std::max(1, std::atoi(v));
    else if (a == "--limit")
      limit = std::max(1, std::atoi(v));
    else if (a == "--seed")
      seed = std::strtoull(v, nullptr, 10);
    else {
      std::fprintf(stderr, "bench_refine_scale: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (scene != "in-view" && scene != "wall" && scene != "both") {
    std::fprintf(stderr, "bench_refine_scale: --scene is in-view, wall or both\n");
    return 2;
  }
  std::printf("refine (robust solve, final solve, covariances) on one process per case; %d thread(s); limit %d s\n",
              threads, limit);
  std::printf("%-8s %7s %7s %10s %10s %8s %10s %6s %7s %9s\n", "scene", "points", "frames", "obs", "time_s", "cov_s",
              "peak_MB", "iters", "ok", "med_err%");
  for (const bool wall : {false, true}) {
    if ((wall && scene == "in-view") || (!wall && scene == "wall"))
      continue;
    for (int f : frame_counts)
      for (int p : point_counts) {
        int fd[2];
        if (pipe(fd) != 0)
          return 1;
        std::fflush(stdout);
        const pid_t pid = fork();
        if (pid == 0) {
          close(fd[0]);
          alarm(static_cast<unsigned>(limit));
          const Outcome o = runCase(wall, p, f, threads, seed);
          if (write(fd[1], &o, sizeof o) != static_cast<ssize_t>(sizeof o))
            _exit(1);
          _exit(0);
        }
        close(fd[1]);
        Outcome o;
        const bool got = read(fd[0], &o, sizeof o) == static_cast<ssize_t>(sizeof o);
        close(fd[0]);
        int status = 0;
        struct rusage ru {};
        wait4(pid, &status, 0, &ru);
        const double peak_mb = static_cast<double>(ru.ru_maxrss) / 1024.0;
        const char *name = wall ? "wall" : "in-view";
        if (got && WIFEXITED(status) && WEXITSTATUS(status) == 0)
          std::printf("%-8s %7d %7d %10ld %10.2f %8.2f %10.0f %6d %7d %9.3f\n", name, p, f, o.observations, o.seconds,
                      o.covariance_seconds, peak_mb, o.iterations, o.ok, 100 * o.median_rel_err);
        else if (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM)
          std::printf("%-8s %7d %7d %10s %10s %8s %10.0f %6s %7s %9s\n", name, p, f, "-",
                      (">" + std::to_string(limit)).c_str(), "-", peak_mb, "-", "-", "-");
        else
          std::printf("%-8s %7d %7d   failed (status %d)\n", name, p, f, status);
        std::fflush(stdout);
      }
  }
  return 0;
}
