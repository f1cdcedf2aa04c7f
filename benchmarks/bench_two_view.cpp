// Per-point cost of the `fused` filter update and of the two-view depth estimators (estimatePaper, estimateExact, each with and
// without covariance) and of CameraModel::undistort, on a fixed set of ~1000 random, valid, noisy
// two-view problems made with simulateScene() and the paper's camera and rig.
//
// Each benchmark iteration solves one problem, cycling through the set; items processed = points,
// so the "items_per_second" column is points per second.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/estimation/depth_filter.h>
#include <yawdepth/estimation/two_view.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/simulation/scene.h>

namespace {

using yawdepth::CameraModel;
using yawdepth::MotionSample;
using yawdepth::TwoViewOptions;
using yawdepth::YawRig;

struct Problem {
  MotionSample prev, cur;
  Eigen::Vector2d uv_prev, uv_cur;
};

struct Fixture {
  CameraModel camera;
  YawRig rig;
  std::vector<Problem> problems;
};

constexpr std::size_t kProblemCount = 1000;
// Camera yaws at frame 0 of the scenes (rad); the scenes also yaw and turn slowly.
constexpr double kYaws[] = {0.0, M_PI / 8, M_PI / 4, 3 * M_PI / 8, M_PI / 2, -M_PI / 4};

Fixture makeFixture()
{
  Fixture f{CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480),
            YawRig(Eigen::Vector3d(-0.1503, 0.0, 0.0)),
            {}};
  const TwoViewOptions check; // default gates and noise
  std::uint64_t seed = 1;
  while (f.problems.size() < kProblemCount) {
    for (double yaw : kYaws) {
      yawdepth::SceneOptions opt;
      opt.frames = 4;
      opt.points = 40;
      opt.yaw = yaw;
      opt.yaw_rate = 0.002;
      opt.turn_rate = 0.001;
      opt.noise = yawdepth::NoiseModel{0.3, 1e-3, 0.05 * M_PI / 180.0, 0.05 * M_PI / 180.0};
      opt.seed = seed++;
      const yawdepth::Scene scene = yawdepth::simulateScene(f.camera, f.rig, opt);
      for (const yawdepth::Track &track : scene.tracks) {
        // Pairs of consecutive observations; frames are motion-log indices in a simulated scene.
        for (std::size_t i = 1; i < track.observations.size(); ++i) {
          const yawdepth::Observation &a = track.observations[i - 1], &b = track.observations[i];
          if (b.frame != a.frame + 1)
            continue;
          Problem p{scene.measured[static_cast<std::size_t>(a.frame)],
                    scene.measured[static_cast<std::size_t>(b.frame)], Eigen::Vector2d(a.u, a.v),
                    Eigen::Vector2d(b.u, b.v)};
          // Keep only problems both methods accept, so every benchmark does the full work.
          if (!yawdepth::estimateExact(f.camera, f.rig, p.prev, p.cur, p.uv_prev, p.uv_cur, check).ok() ||
              !yawdepth::estimatePaper(f.camera, f.rig, p.prev, p.cur, p.uv_prev, p.uv_cur, check).ok())
            continue;
          f.problems.push_back(p);
          if (f.problems.size() == kProblemCount)
            return f;
        }
      }
    }
  }
  return f;
}

const Fixture &fixture()
{
  static const Fixture f = makeFixture();
  return f;
}

template <yawdepth::PointEstimate (*Estimate)(const CameraModel &, const YawRig &, const MotionSample &,
                                              const MotionSample &, const Eigen::Vector2d &,
                                              const Eigen::Vector2d &, const TwoViewOptions &)>
void runTwoView(benchmark::State &state, bool covariance)
{
  const Fixture &f = fixture();
  TwoViewOptions options;
  options.compute_covariance = covariance;
  std::size_t i = 0;
  for (auto _ : state) {
    const Problem &p = f.problems[i];
    yawdepth::PointEstimate e = Estimate(f.camera, f.rig, p.prev, p.cur, p.uv_prev, p.uv_cur, options);
    benchmark::DoNotOptimize(e);
    if (++i == f.problems.size())
      i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_EstimatePaper(benchmark::State &state) { runTwoView<yawdepth::estimatePaper>(state, false); }
void BM_EstimatePaperCov(benchmark::State &state) { runTwoView<yawdepth::estimatePaper>(state, true); }
void BM_EstimateExact(benchmark::State &state) { runTwoView<yawdepth::estimateExact>(state, false); }
void BM_EstimateExactCov(benchmark::State &state) { runTwoView<yawdepth::estimateExact>(state, true); }

// One pixel undistorted per iteration (the current pixel of each problem), without the Jacobian.
void BM_Undistort(benchmark::State &state)
{
  const Fixture &f = fixture();
  std::size_t i = 0;
  Eigen::Vector2d m;
  for (auto _ : state) {
    bool ok = f.camera.undistort(f.problems[i].uv_cur, m);
    benchmark::DoNotOptimize(ok);
    benchmark::DoNotOptimize(m);
    if (++i == f.problems.size())
      i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

// Same, also computing d(x,y)/d(u,v) as the estimators do for their covariance.
void BM_UndistortJacobian(benchmark::State &state)
{
  const Fixture &f = fixture();
  std::size_t i = 0;
  Eigen::Vector2d m;
  Eigen::Matrix2d J;
  for (auto _ : state) {
    bool ok = f.camera.undistort(f.problems[i].uv_cur, m, &J);
    benchmark::DoNotOptimize(ok);
    benchmark::DoNotOptimize(m);
    benchmark::DoNotOptimize(J);
    if (++i == f.problems.size())
      i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

// The `fused` filter's per-feature update: one DepthFilter::step() with an observation, the
// increment model being shared by all features of a frame (computed once per frame, not timed here)
// and the observation already undistorted (as a tracker delivers it).
struct FilterProblem {
  yawdepth::DepthFilter filter; // state before the timed step
  yawdepth::IncrementModel inc;
  Eigen::Vector2d m;
  Eigen::Matrix2d cov;
};

std::vector<FilterProblem> makeFilterProblems(int steps_before)
{
  const Fixture &f = fixture();
  std::vector<FilterProblem> out;
  const yawdepth::NoiseModel noise{0.3, 1e-3, 0.05 * M_PI / 180.0, 0.05 * M_PI / 180.0};
  yawdepth::DepthFilter::Options fo;
  fo.noise = noise;
  std::uint64_t seed = 1000;
  while (out.size() < kProblemCount) {
    for (double yaw : kYaws) {
      yawdepth::SceneOptions opt;
      opt.frames = steps_before + 2;
      opt.points = 40;
      opt.yaw = yaw;
      opt.noise = noise;
      opt.seed = seed++;
      const yawdepth::Scene scene = yawdepth::simulateScene(f.camera, f.rig, opt);
      std::vector<yawdepth::IncrementModel> inc;
      for (std::size_t k = 0; k + 1 < scene.measured.size(); ++k)
        inc.push_back(yawdepth::IncrementModel::between(f.rig, scene.measured[k], scene.measured[k + 1]));
      for (const yawdepth::Track &track : scene.tracks) {
        if (track.observations.size() != scene.measured.size())
          continue;
        yawdepth::DepthFilter filter(fo, f.camera.kx(), f.camera.ky());
        bool ok = true;
        for (std::size_t k = 0; k < track.observations.size() && ok; ++k) {
          Eigen::Vector2d m;
          Eigen::Matrix2d J;
          ok = f.camera.undistort(Eigen::Vector2d(track.observations[k].u, track.observations[k].v), m, &J);
          const Eigen::Matrix2d cov = noise.sigma_px * noise.sigma_px * J * J.transpose();
          if (!ok)
            break;
          if (k == 0) {
            filter.initialize(0, scene.measured[0].yaw, m, cov);
          } else if (k + 1 < track.observations.size()) {
            filter.step(inc[k - 1], &m, &cov);
          } else {
            out.push_back({filter, inc[k - 1], m, cov});
          }
        }
        if (out.size() == kProblemCount)
          return out;
      }
    }
  }
  return out;
}

void runFilterStep(benchmark::State &state, int steps_before)
{
  static std::vector<std::vector<FilterProblem>> cache(16);
  std::vector<FilterProblem> &problems = cache.at(static_cast<std::size_t>(steps_before));
  if (problems.empty())
    problems = makeFilterProblems(steps_before);
  std::size_t i = 0;
  for (auto _ : state) {
    FilterProblem &p = problems[i];
    yawdepth::DepthFilter filter = p.filter;
    const auto u = filter.step(p.inc, &p.m, &p.cov);
    benchmark::DoNotOptimize(u);
    benchmark::DoNotOptimize(filter);
    if (++i == problems.size())
      i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

// The first update after a feature appears (diffuse prior: the iterated update works hardest).
void BM_FusedFirstUpdate(benchmark::State &state) { runFilterStep(state, 0); }
// A steady-state update (the feature has been tracked for 8 frames).
void BM_FusedUpdate(benchmark::State &state) { runFilterStep(state, 8); }

// The shared per-frame work of `fused`: the increment model with its noise derivatives.
void BM_IncrementModel(benchmark::State &state)
{
  const Fixture &f = fixture();
  std::size_t i = 0;
  for (auto _ : state) {
    const Problem &p = f.problems[i];
    yawdepth::IncrementModel inc = yawdepth::IncrementModel::between(f.rig, p.prev, p.cur);
    benchmark::DoNotOptimize(inc);
    if (++i == f.problems.size())
      i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

} // namespace

BENCHMARK(BM_FusedFirstUpdate);
BENCHMARK(BM_FusedUpdate);
BENCHMARK(BM_IncrementModel);
BENCHMARK(BM_EstimatePaper);
BENCHMARK(BM_EstimatePaperCov);
BENCHMARK(BM_EstimateExact);
BENCHMARK(BM_EstimateExactCov);
BENCHMARK(BM_Undistort);
BENCHMARK(BM_UndistortJacobian);

// BENCHMARK_MAIN(), plus a context line describing the problem set (built before timing starts).
int main(int argc, char **argv)
{
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv))
    return 1;
  const Fixture &f = fixture();
  std::ostringstream yaws;
  for (double y : kYaws)
    yaws << (yaws.tellp() > 0 ? " " : "") << y * 180.0 / M_PI;
  benchmark::AddCustomContext("problems", std::to_string(f.problems.size()) +
                                              " noisy consecutive-frame pairs (0.3 px, 1 mm, 0.05 deg), both methods ok");
  benchmark::AddCustomContext("scene_yaws_deg", yaws.str() + " (+0.115 deg/frame yaw, +0.057 deg/frame turn)");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
