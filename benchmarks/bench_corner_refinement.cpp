/*!
  \file bench_corner_refinement.cpp
  \brief Per-corner error of each chessboard corner refinement against the renderer's exact truth,
  and the time per frame of the renderer and of each detection.

  Scenes: `accuracyScenes(24, 7)` of render_scenes.h (seeded random poses: the paper's camera or a
  wide camera with strong barrel distortion, 5x4, 7x6 or 6x6 boards of 20 mm squares, tilts up to
  40 degrees, any roll), each rendered under three conditions (blur 0.7 px and noise 2 gray levels,
  the ideal render, blur 1.2 px and noise 4), image seed 100 + scene. Methods: the detector with no
  refinement (OpenCV's findChessboardCornersSB with its ACCURACY flag), OpenCV's cornerSubPix (the
  detector's window, and the common 11x11), yawdepth's saddle and gradient refinements (the default).
  The 6x6 boards, symmetric and seen without history, get the top-left labelling: an error above
  3 px counts as a wrong id, not in the RMS. RMS is of the 2D error (px), not per coordinate.

  Plain table on stdout. Usage: bench_corner_refinement [--scenes N] [--seed S]
*/
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>
#include <opencv2/core.hpp>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/render/renderer.h>

#include "render_scenes.h"

using namespace yawdepth;
using namespace yawdepth::bench;

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Refinement {
  const char *name;
  CornerRefinement refinement;
  int window; // DetectorOptions::subpixel_window (0: the detector's own)
};

} // namespace

int main(int argc, char **argv) {
  int count = 24;
  std::uint64_t seed = 7;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--scenes") == 0 && i + 1 < argc)
      count = std::atoi(argv[++i]);
    else if (std::strcmp(argv[i], "--seed") == 0 && i + 1 < argc)
      seed = std::strtoull(argv[++i], nullptr, 10);
    else {
      std::fprintf(stderr, "usage: bench_corner_refinement [--scenes N] [--seed S]\n");
      return 2;
    }
  }
  const YawRig rig = paperRig();
  const std::vector<AccuracyScene> scenes = accuracyScenes(count, seed);
  const Refinement methods[] = {{"SB+ACCURACY", CornerRefinement::None, 0},
                                {"cornerSubPix", CornerRefinement::OpenCV, 0},
                                {"cornerSubPix11", CornerRefinement::OpenCV, 5}, // the common 11x11 window
                                {"saddle", CornerRefinement::Saddle, 0},
                                {"gradient", CornerRefinement::Gradient, 0}};
  struct Cond {
    const char *name;
    double blur, noise;
  };
  std::printf("bench_corner_refinement: %zu scenes (seed %llu), error against the renderer's truth, 2D RMS in px\n",
              scenes.size(), static_cast<unsigned long long>(seed));
  for (const Cond cond : {Cond{"blur 0.7 noise 2", 0.7, 2.0}, Cond{"blur 0 noise 0", 0.0, 0.0},
                          Cond{"blur 1.2 noise 4", 1.2, 4.0}}) {
    std::map<std::string, ErrorStats> stats;
    std::map<std::string, int> id_errors, failures;
    std::map<std::string, double> det_ms;
    double render_ms = 0;
    for (std::size_t i = 0; i < scenes.size(); ++i) {
      const AccuracyScene &sc = scenes[i];
      RenderOptions ro;
      ro.blur_sigma_px = cond.blur;
      ro.noise_sigma = cond.noise;
      ro.seed = 100 + i;
      const auto t0 = Clock::now();
      const cv::Mat img = renderBoard(sc.cam, rig, sc.sample, sc.board, sc.wMb, ro);
      render_ms += msSince(t0);
      for (const Refinement &m : methods) {
        DetectorOptions o;
        o.refinement = m.refinement;
        if (m.window > 0)
          o.subpixel_window = m.window;
        PatternDetector det(sc.board.pattern, o);
        const auto t1 = Clock::now();
        const FrameDetection d = det.detect(img, 0);
        det_ms[m.name] += msSince(t1);
        if (!d.found) {
          ++failures[m.name];
          continue;
        }
        for (const auto &f : d.features) {
          const Eigen::Vector2d e = Eigen::Vector2d(f.u, f.v) - sc.truth.at(f.id);
          if (e.norm() > 3)
            ++id_errors[m.name];
          else
            stats[m.name].add(e);
        }
      }
    }
    const double n = static_cast<double>(scenes.size());
    std::printf("\n%s: render %.1f ms per 640x480 frame (mean)\n", cond.name, render_ms / n);
    std::printf("  %-14s %6s %9s %9s %9s %9s %9s %8s %10s\n", "method", "n", "rms px", "bias u", "bias v", "max px",
                "wrong ids", "failed", "ms/detect");
    for (const Refinement &m : methods) {
      const ErrorStats &s = stats[m.name];
      std::printf("  %-14s %6ld %9.4f %+9.4f %+9.4f %9.4f %9d %8d %10.1f\n", m.name, s.n, s.rms(), s.biasX(),
                  s.biasY(), s.max, id_errors[m.name], failures[m.name], det_ms[m.name] / n);
    }
  }
  return 0;
}
