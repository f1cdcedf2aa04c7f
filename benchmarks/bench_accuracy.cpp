/*
  bench_accuracy: accuracy of every yawdepth method against the Cramer-Rao lower bound and
  against OpenCV's two-view triangulation, on seeded synthetic scenes with the paper's camera.

  A plain program that prints plain-text tables (docs/accuracy.md quotes them as they are):
    bench_accuracy [--trials N] [--seed S] [--quick] [--frames F] [--window K]
  --trials N  trials per scene (default 200); every trial draws new points and new noise.
  --seed S    base seed (default 1); trial t of scene s uses seed S + 100000 s + t.
  --quick     40 trials.
  --frames F  frames per scene (default 10, the paper's; with more, `window` marginalises the older
              frames: its 10-frame window is then smaller than the scene).
  --window K  the window estimator's window (default 10; 2 makes it an iterated EKF-SLAM: only the
              newest increment relinearised, everything older in the Gaussian prior).

  What it measures (see the printed header for the details):
  1. Depth zc of every point at its last observed frame, by paper / exact / fused / refine and by
     cv::triangulatePoints on the first and last observation with the measured motion; RMSE,
     RMSE normalised by the joint and by the per-point Cramer-Rao bound, and 2-sigma coverage.
  2. The same scenes with 5 % gross outliers: refine's, window's and fused's RMSE against the bound of the
     clean tracks, and their outlier recall and precision.
  3. Speed of refineWindow (30 points x 10 frames) and of fused per feature update.
*/
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/pipeline/pipeline.h>
#include <yawdepth/refine/refine.h>
#include <yawdepth/simulation/scene.h>

using namespace yawdepth;

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kGross = 10.0; // a "gross" error: |e| above this many per-point CRLBs

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

enum MethodIndex { kPaper = 0, kExact, kFused, kWindow, kRefine, kOpenCV, kMethods };
const char *const kMethodNames[kMethods] = {"paper", "exact", "fused", "window", "refine", "opencv"};

struct SceneSpec {
  double yaw_deg;
  double turn_deg; // heading change per frame
  int arm = -1;    // an arm scene (ArmPath) instead of the planar robot
  bool isArm() const { return arm >= 0; }
  const char *armName() const { return arm == 0 ? "approach" : arm == 1 ? "orbit" : "random"; }
  // The scene's name: long (the tables' headers) or short (the summary's rows).
  std::string label(bool brief) const
  {
    char buf[96];
    if (isArm())
      std::snprintf(buf, sizeof buf, brief ? "arm %s" : "arm, %s (6-DoF, hand-eye mount)", armName());
    else
      std::snprintf(buf, sizeof buf, brief ? "yaw %2.0f %s" : "yaw %2.0f deg, %s", yaw_deg,
                    turn_deg != 0 ? (brief ? "turning" : "turning 1 deg/frame") : "straight");
    return buf;
  }
  std::string name() const { return label(false); }
  std::string shortName() const { return label(true); }
};

/*! Adds each of the given members of `from` into the same member of `to` (a merge of sums). */
template <class T, class... Member>
void addEach(T &to, const T &from, Member... members)
{
  ((to.*members += from.*members), ...);
}

/*! Error statistics of one method over the points used. */
struct Acc {
  long n = 0;                 // points used
  double se = 0;              // sum of e^2 (m^2)
  double sum_e = 0;           // sum of e (m)
  double sn_joint = 0;        // sum of (e / crlb_joint)^2
  double sn_pp = 0;           // sum of (e / crlb_per_point)^2
  long covered = 0;           // |e| <= 2 sigma
  long not_ok = 0;            // points with >= 2 observations the method did not report ok
  long gross = 0;             // |e| > 10 per-point CRLB
  std::vector<double> abs_e;  // |e| of every point used (m), for the median
  void add(double e, double crlb_joint, double crlb_pp, double sigma)
  {
    ++n;
    abs_e.push_back(std::abs(e));
    if (std::abs(e) > kGross * crlb_pp)
      ++gross;
    se += e * e;
    sum_e += e;
    sn_joint += (e / crlb_joint) * (e / crlb_joint);
    sn_pp += (e / crlb_pp) * (e / crlb_pp);
    if (std::isfinite(sigma) && std::abs(e) <= 2 * sigma)
      ++covered;
  }
  void merge(const Acc &o)
  {
    addEach(*this, o, &Acc::n, &Acc::se, &Acc::sum_e, &Acc::sn_joint, &Acc::sn_pp, &Acc::covered, &Acc::not_ok,
            &Acc::gross);
    abs_e.insert(abs_e.end(), o.abs_e.begin(), o.abs_e.end());
  }
  double medianAbs() const
  {
    if (abs_e.empty())
      return NAN;
    std::vector<double> v = abs_e;
    const std::size_t h = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<long>(h), v.end());
    return v[h];
  }
  double rmse() const { return n ? std::sqrt(se / n) : NAN; }
  double bias() const { return n ? sum_e / n : NAN; }
  double ratioJoint() const { return n ? std::sqrt(sn_joint / n) : NAN; }
  double ratioPP() const { return n ? std::sqrt(sn_pp / n) : NAN; }
  double coverage() const { return n ? double(covered) / n : NAN; }
};

/*! Clean-scene statistics of one scene (or pooled). */
struct CleanStats {
  long points = 0, few_obs = 0, no_bound = 0, used = 0;
  double crlb_joint_sq = 0, crlb_pp_sq = 0; // sums over used points
  std::array<Acc, kMethods> acc;
  void merge(const CleanStats &o)
  {
    addEach(*this, o, &CleanStats::points, &CleanStats::few_obs, &CleanStats::no_bound, &CleanStats::used,
            &CleanStats::crlb_joint_sq, &CleanStats::crlb_pp_sq);
    for (int m = 0; m < kMethods; ++m)
      acc[m].merge(o.acc[m]);
  }
};

/*! Outlier-scene statistics (fused and refine). */
struct OutlierStats {
  long points = 0, used = 0, corrupted = 0;
  std::array<Acc, 3> acc;                        // 0 fused, 1 refine, 2 window
  std::array<long, 3> tp{{0, 0, 0}}, fp{{0, 0, 0}}; // flagged and corrupted / flagged and clean
  void merge(const OutlierStats &o)
  {
    addEach(*this, o, &OutlierStats::points, &OutlierStats::used, &OutlierStats::corrupted);
    for (int m = 0; m < 3; ++m) {
      acc[m].merge(o.acc[m]);
      tp[m] += o.tp[m];
      fp[m] += o.fp[m];
    }
  }
};

/*! Depth zc at the last observation by cv::triangulatePoints from the first and last observation,
    with projection matrices from the measured motion; NaN when it fails. */
std::vector<double> triangulateOpenCV(const CameraModel &camera, const YawRig &rig,
                                      const std::vector<MotionSample> &measured, const std::map<long, std::size_t> &row,
                                      const std::vector<Track> &tracks)
{
  std::vector<double> zc(tracks.size(), NAN);
  auto projection = [&](long frame, Eigen::Matrix3d &R, Eigen::Vector3d &t) {
    // cMw = (wMv vMc(yaw))^-1 from the measured row; identity K (normalised points).
    fromVisp(wMc(rig, measured.at(row.at(frame))).inverse(), R, t);
    cv::Matx34d P;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        P(i, j) = R(i, j);
      P(i, 3) = t(i);
    }
    return P;
  };
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const auto &obs = tracks[i].observations;
    if (obs.size() < 2)
      continue;
    Eigen::Vector2d m1, m2;
    if (!camera.undistort(Eigen::Vector2d(obs.front().u, obs.front().v), m1) ||
        !camera.undistort(Eigen::Vector2d(obs.back().u, obs.back().v), m2))
      continue;
    Eigen::Matrix3d R1, R2;
    Eigen::Vector3d t1, t2;
    const cv::Matx34d P1 = projection(obs.front().frame, R1, t1);
    const cv::Matx34d P2 = projection(obs.back().frame, R2, t2);
    cv::Mat p1 = (cv::Mat_<double>(2, 1) << m1.x(), m1.y());
    cv::Mat p2 = (cv::Mat_<double>(2, 1) << m2.x(), m2.y());
    cv::Mat X;
    cv::triangulatePoints(cv::Mat(P1), cv::Mat(P2), p1, p2, X);
    X.convertTo(X, CV_64F);
    const double w = X.at<double>(3, 0);
    if (!(std::abs(w) > 0))
      continue;
    const Eigen::Vector3d w_P(X.at<double>(0, 0) / w, X.at<double>(1, 0) / w, X.at<double>(2, 0) / w);
    const Eigen::Vector3d c1 = R1 * w_P + t1, c2 = R2 * w_P + t2;
    if (std::isfinite(c2.z()) && c1.z() > 0 && c2.z() > 0) // cheirality, as "ok"
      zc[i] = c2.z();
  }
  return zc;
}

/*! Replace `fraction` of all observations by gross errors of 10 to 50 px in a random direction
    (kept inside the image). Returns per track, per observation, whether it was corrupted. */
std::vector<std::vector<bool>> corrupt(std::vector<Track> &tracks, double fraction, double width, double height,
                                       std::mt19937_64 &rng)
{
  std::vector<std::vector<bool>> truth(tracks.size());
  std::vector<std::pair<std::size_t, std::size_t>> all;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    truth[i].assign(tracks[i].observations.size(), false);
    for (std::size_t j = 0; j < tracks[i].observations.size(); ++j)
      all.emplace_back(i, j);
  }
  std::shuffle(all.begin(), all.end(), rng);
  const std::size_t count = static_cast<std::size_t>(std::lround(fraction * static_cast<double>(all.size())));
  std::uniform_real_distribution<double> mag(10.0, 50.0), ang(0.0, 2 * M_PI);
  for (std::size_t k = 0; k < count && k < all.size(); ++k) {
    Observation &ob = tracks[all[k].first].observations[all[k].second];
    const double r = mag(rng);
    for (int attempt = 0; attempt < 100; ++attempt) {
      const double a = ang(rng);
      const double u = ob.u + r * std::cos(a), v = ob.v + r * std::sin(a);
      if (u >= 0 && u <= width - 1 && v >= 0 && v <= height - 1) {
        ob.u = u;
        ob.v = v;
        truth[all[k].first][all[k].second] = true;
        break;
      }
    }
  }
  return truth;
}

void countFlags(const std::vector<std::vector<bool>> &flags, const std::vector<std::vector<bool>> &truth, long &tp,
                long &fp)
{
  for (std::size_t i = 0; i < truth.size() && i < flags.size(); ++i)
    for (std::size_t j = 0; j < truth[i].size() && j < flags[i].size(); ++j)
      if (flags[i][j]) {
        if (truth[i][j])
          ++tp;
        else
          ++fp;
      }
}

std::string fmt(const char *f, double v)
{
  if (!std::isfinite(v))
    return "-";
  char buf[64];
  if (std::abs(v) >= 1e5)
    std::snprintf(buf, sizeof buf, "%.2e", v);
  else
    std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

void printRule(int width) { std::printf("%s\n", std::string(static_cast<std::size_t>(width), '-').c_str()); }

void printCleanTable(const std::string &title, const CleanStats &s, long trials, bool refine_ok)
{
  std::printf("\n%s\n", title.c_str());
  std::printf("  %ld trials, %ld points: %ld used (every method ok, >= 2 observations), %ld with < 2 observations,\n"
              "  %ld without a finite bound. CRLB of zc (RMS over used points): joint %.2f mm, per-point %.2f mm.\n",
              trials, s.points, s.used, s.few_obs, s.no_bound, s.used ? 1e3 * std::sqrt(s.crlb_joint_sq / s.used) : NAN,
              s.used ? 1e3 * std::sqrt(s.crlb_pp_sq / s.used) : NAN);
  const int W = 94;
  printRule(W);
  std::printf("%-8s %8s %10s %9s %9s %10s %10s %7s %9s\n", "method", "not ok", "RMSE zc", "median", "bias",
              "RMSE/CRLB", "RMSE/CRLB", "gross", "2-sigma");
  std::printf("%-8s %8s %10s %9s %9s %10s %10s %7s %9s\n", "", "(points)", "(mm)", "|e| (mm)", "(mm)", "joint",
              "per-point", "(pts)", "coverage");
  printRule(W);
  for (int m = 0; m < kMethods; ++m) {
    const Acc &a = s.acc[m];
    if (m == kRefine && !refine_ok) {
      std::printf("%-8s %s\n", kMethodNames[m], "refine: unavailable");
      continue;
    }
    const bool has_sigma = m != kOpenCV;
    std::printf("%-8s %8ld %10s %9s %9s %10s %10s %7ld %9s\n", kMethodNames[m], a.not_ok,
                fmt("%.2f", 1e3 * a.rmse()).c_str(), fmt("%.2f", 1e3 * a.medianAbs()).c_str(),
                fmt("%+.2f", 1e3 * a.bias()).c_str(), fmt("%.3f", a.ratioJoint()).c_str(),
                fmt("%.3f", a.ratioPP()).c_str(), a.gross, has_sigma ? fmt("%.3f", a.coverage()).c_str() : "-");
  }
  printRule(W);
}

void usage(const char *argv0)
{
  std::fprintf(stderr, "usage: %s [--trials N] [--seed S] [--quick] [--frames F] [--window K]\n", argv0);
}

/*! The command line. */
struct BenchArgs {
  long trials = 200;
  std::uint64_t seed = 1;
  int frames = 10, window = WindowOptions().window;
};

/*! Parse the command line into `args`: -1 to go on, else the exit status (usage or a bad value said). */
int parseArguments(int argc, char **argv, BenchArgs &args)
{
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--trials" && i + 1 < argc) {
      args.trials = std::strtol(argv[++i], nullptr, 10);
    } else if (a == "--seed" && i + 1 < argc) {
      args.seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--window" && i + 1 < argc) {
      args.window = static_cast<int>(std::strtol(argv[++i], nullptr, 10));
    } else if (a == "--frames" && i + 1 < argc) {
      args.frames = static_cast<int>(std::strtol(argv[++i], nullptr, 10));
    } else if (a == "--quick") {
      quick = true;
    } else if (a == "--help" || a == "-h") {
      usage(argv[0]);
      return 0;
    } else {
      usage(argv[0]);
      return 2;
    }
  }
  if (quick)
    args.trials = 40;
  if (args.trials < 1) {
    std::fprintf(stderr, "bench_accuracy: --trials must be >= 1\n");
    return 2;
  }
  if (args.window < 2 || args.window > 1000) {
    std::fprintf(stderr, "bench_accuracy: --window must be between 2 and 1000\n");
    return 2;
  }
  if (args.frames < 2 || args.frames > 1000) {
    std::fprintf(stderr, "bench_accuracy: --frames must be between 2 and 1000\n");
    return 2;
  }
  return -1;
}

/*! What the benchmark runs on: the scenes and, for planar and arm scenes, camera, rig and noise. */
struct Setup {
  CameraModel paper_camera =
      CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
  YawRig paper_rig{Eigen::Vector3d(-0.1503, 0, 0)};
  NoiseModel paper_noise{0.3, 1e-3, 0.05 * kDeg, 0.05 * kDeg};
  std::vector<SceneSpec> specs = {{0, 0},     {45, 0},    {90, 0},    {0, 1},   {45, 1},
                                  {90, 1},    {0, 0, 0},  {0, 0, 1},  {0, 0, 2}};
  // Arm scenes: the franka set's camera (RealSense, 600 px) and a hand-eye mount like its eMc;
  // 1 mm and 0.05 deg per increment per axis, no pan joint (the yaw is exact).
  CameraModel arm_camera = CameraModel::brown(601.7, 602.1, 324.4, 239.6, {0.046, 0.11, -0.0039, 0.0003}, 640, 480);
  YawRig arm_rig{vpHomogeneousMatrix(0.0577, -0.0339, -0.0423, 0.0018, 0.0092, 1.5818)};
  NoiseModel arm_noise = armNoise(paper_noise);
  double outlier_fraction = 0.05;
  bool refine_ok = refineAvailable();

  static NoiseModel armNoise(NoiseModel n)
  {
    n.sigma_yaw = 0.0;
    n.sigma_rot = 0.05 * kDeg;
    return n;
  }
};

void printHeader(const BenchArgs &args, bool refine_ok)
{
  std::printf("yawdepth accuracy benchmark: depth zc of each point at its last observed frame\n");
  std::printf("================================================================================\n");
  std::printf("Methods: paper (eq. 5, last increment), exact (two-view, last increment), fused (per-feature\n"
              "  filter over all frames), window (sliding-window smoother of points + motion, %d frames, older ones\n"
              "  marginalised; frame by frame, each point read when its last frame leaves the window), refine (joint\n"
              "  MAP of points + motion over all frames, initialised with fused), opencv (cv::triangulatePoints on\n"
              "  the first and last observation, measured motion).\n", args.window);
  std::printf("Scenes: paper's camera (fx 1734.1, fy 1734.5, u0 319.2, v0 241.4, Brown distortion, 640x480),\n"
              "  rig offset (-0.1503, 0, 0) m; yaw 0/45/90 deg x straight / turning 1 deg per frame;\n"
              "  %d frames, 0.02 m forward per frame; 30 points, depth 0.5 to 3 m in the first frame.\n", args.frames);
  std::printf("Noise (simulation = estimators' model): pixels 0.3 px, odometry 1 mm per axis per increment,\n"
              "  heading 0.05 deg per increment, yaw reading 0.05 deg.\n");
  std::printf("Arm scenes (6-DoF motion log): camera fx 601.7, fy 602.1, u0 324.4, v0 239.6, Brown distortion,\n"
              "  640x480; camera_pose (0.0577, -0.0339, -0.0423 m; theta-u 0.0018, 0.0092, 1.5818 rad); 10 frames of\n"
              "  armTrajectory (approach: 30 %% of 0.6 m toward the target; orbit: 40 deg around it at 0.6 m; random:\n"
              "  poses within 9 cm and 17 deg of roll), 30 points at 0.4 to 0.8 m; noise 0.3 px, 1 mm and 0.05 deg per\n"
              "  increment per axis, no yaw joint.\n");
  std::printf("Bound: CRLB of zc from depthCramerRao at the truth; joint = all points + motion (the bound\n"
              "  for refine), per-point = one point + motion (the bound for per-feature methods).\n"
              "  RMSE/CRLB = sqrt(mean((e/crlb)^2)); 1.0 means the bound is reached. 2-sigma coverage =\n"
              "  fraction of points with |e| <= 2 sigma_zc (the method's own covariance).\n");
  std::printf("Points of one trial share the motion noise, hence many trials: %ld per scene; trial t of scene s\n"
              "  (s = 0..5 in the order of the tables) uses seed %llu + 100000 s + t.\n",
              args.trials, static_cast<unsigned long long>(args.seed));
  std::printf("Reproduce: cmake -S . -B build-acc -DYAWDEPTH_BUILD_TESTS=OFF -DYAWDEPTH_BUILD_EXAMPLES=OFF &&\n"
              "  cmake --build build-acc --target bench_accuracy && build-acc/benchmarks/bench_accuracy --trials %ld --seed %llu"
              " --frames %d --window %d\n",
              args.trials, static_cast<unsigned long long>(args.seed), args.frames, args.window);
  std::printf("refine: %s\n", refine_ok ? "available (Ceres)" : "unavailable (built without Ceres)");
  std::fflush(stdout);
}

/*! Run times and refine's failures, over every trial. */
struct Timings {
  std::vector<double> refine_ms, refine_arm_ms;
  double fused_ms = 0, window_ms = 0;
  long fused_obs = 0, window_frames = 0;
  long refine_errors = 0;
};

/*! One scene's estimators: camera, rig, noise and the methods through the one entry point, as the
    command line runs them. */
struct SceneRun {
  const SceneSpec &spec;
  const CameraModel &camera;
  const YawRig &rig;
  PipelineOptions opt;
  bool refine_ok;
  double outlier_fraction;

  PipelineResult estimate(Method m, const Scene &scene, const std::vector<Track> &tracks)
  {
    opt.method = m;
    return estimatePoints(camera, rig, scene.measured, tracks, opt);
  }
  /*! refine's result through `take`, or, when it throws, the first message on stderr and a count. */
  template <class Take> void estimateRefine(const Scene &scene, const std::vector<Track> &tracks, Timings &timings, Take take)
  {
    try {
      const auto t0 = Clock::now();
      const PipelineResult rr = estimate(Method::Refine, scene, tracks);
      take(rr, msSince(t0));
    } catch (const std::exception &e) {
      if (timings.refine_errors++ == 0)
        std::fprintf(stderr, "refine threw: %s\n", e.what());
    }
  }
};

/*! One trial's scene and what every method is measured against. */
struct Trial {
  Scene scene;
  std::map<long, std::size_t> row;           // frame -> row of the motion
  std::vector<double> crlb_joint, crlb_pp;   // per track
  std::vector<double> z_true;                // true zc at each track's last observation
};

Trial makeTrial(const SceneRun &run, const SceneOptions &so)
{
  Trial t;
  t.scene = simulateScene(run.camera, run.rig, so);
  for (std::size_t k = 0; k < t.scene.truth.size(); ++k)
    t.row[t.scene.truth[k].frame] = k;
  const std::size_t n = t.scene.tracks.size();
  t.crlb_joint = depthCramerRao(run.camera, run.rig, t.scene.truth, t.scene.tracks, t.scene.w_points, run.opt.noise, true);
  t.crlb_pp = depthCramerRao(run.camera, run.rig, t.scene.truth, t.scene.tracks, t.scene.w_points, run.opt.noise, false);
  t.z_true.assign(n, NAN);
  for (std::size_t i = 0; i < n; ++i)
    if (!t.scene.tracks[i].observations.empty())
      t.z_true[i] =
          t.scene.cameraPoint(run.rig, t.scene.tracks[i].id, t.row.at(t.scene.tracks[i].observations.back().frame)).z();
  return t;
}

bool hasBound(const Trial &t, std::size_t i)
{
  return std::isfinite(t.crlb_joint[i]) && t.crlb_joint[i] > 0 && std::isfinite(t.crlb_pp[i]) && t.crlb_pp[i] > 0;
}

/*! The clean scene: every method's zc and sigma_zc (NaN where not ok), timed; then the points every
    method reported ok into `cs`. */
void cleanTrial(SceneRun &run, const Trial &t, CleanStats &cs, Timings &timings)
{
  const Scene &scene = t.scene;
  const std::size_t n = scene.tracks.size();
  std::array<std::vector<double>, kMethods> z, sig;
  for (int m = 0; m < kMethods; ++m) {
    z[m].assign(n, NAN);
    sig[m].assign(n, NAN);
  }
  auto take = [&](int m, const std::vector<PointEstimate> &est) {
    for (std::size_t i = 0; i < n && i < est.size(); ++i)
      if (est[i].ok()) {
        z[m][i] = est[i].c_P.z();
        sig[m][i] = est[i].sigmaZ();
      }
  };
  take(kPaper, run.estimate(Method::Paper, scene, scene.tracks).points);
  take(kExact, run.estimate(Method::Exact, scene, scene.tracks).points);
  auto t0 = Clock::now();
  take(kFused, run.estimate(Method::Fused, scene, scene.tracks).points);
  timings.fused_ms += msSince(t0);
  for (const Track &tr : scene.tracks)
    timings.fused_obs += static_cast<long>(tr.observations.size());
  t0 = Clock::now();
  take(kWindow, run.estimate(Method::Window, scene, scene.tracks).points);
  timings.window_ms += msSince(t0);
  timings.window_frames += static_cast<long>(scene.measured.size());
  if (run.refine_ok)
    run.estimateRefine(scene, scene.tracks, timings, [&](const PipelineResult &rr, double ms) {
      (run.spec.isArm() ? timings.refine_arm_ms : timings.refine_ms).push_back(ms);
      take(kRefine, rr.points);
    });
  z[kOpenCV] = triangulateOpenCV(run.camera, run.rig, scene.measured, t.row, scene.tracks);

  for (std::size_t i = 0; i < n; ++i) {
    ++cs.points;
    if (scene.tracks[i].observations.size() < 2) {
      ++cs.few_obs;
      continue;
    }
    bool all_ok = true;
    for (int m = 0; m < kMethods; ++m) {
      if (m == kRefine && !run.refine_ok)
        continue;
      if (!std::isfinite(z[m][i])) {
        ++cs.acc[m].not_ok;
        all_ok = false;
      }
    }
    if (!all_ok)
      continue;
    if (!hasBound(t, i)) {
      ++cs.no_bound;
      continue;
    }
    ++cs.used;
    cs.crlb_joint_sq += t.crlb_joint[i] * t.crlb_joint[i];
    cs.crlb_pp_sq += t.crlb_pp[i] * t.crlb_pp[i];
    for (int m = 0; m < kMethods; ++m)
      if (std::isfinite(z[m][i]))
        cs.acc[m].add(z[m][i] - t.z_true[i], t.crlb_joint[i], t.crlb_pp[i], sig[m][i]);
  }
}

/*! The same scene with gross outliers (seeded from `seed`): fused, window and refine, their flags
    against the corrupted observations, their errors into `os`. */
void outlierTrial(SceneRun &run, const Trial &t, std::uint64_t seed, OutlierStats &os, Timings &timings)
{
  const std::size_t n = t.scene.tracks.size();
  std::vector<Track> tracks = t.scene.tracks;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + 12345);
  const std::vector<std::vector<bool>> corrupted =
      corrupt(tracks, run.outlier_fraction, run.camera.width(), run.camera.height(), rng);
  for (const auto &c : corrupted)
    os.corrupted += std::count(c.begin(), c.end(), true);
  const PipelineResult fused_r = run.estimate(Method::Fused, t.scene, tracks);
  const std::vector<PointEstimate> &fused_o = fused_r.points;
  countFlags(fused_r.outliers, corrupted, os.tp[0], os.fp[0]);
  const PipelineResult window_r = run.estimate(Method::Window, t.scene, tracks);
  const std::vector<PointEstimate> &window_o = window_r.points;
  countFlags(window_r.outliers, corrupted, os.tp[2], os.fp[2]);
  std::vector<PointEstimate> refine_o(n);
  if (run.refine_ok)
    run.estimateRefine(t.scene, tracks, timings, [&](const PipelineResult &rr, double) {
      refine_o = rr.points;
      countFlags(rr.outliers, corrupted, os.tp[1], os.fp[1]);
    });
  for (std::size_t i = 0; i < n; ++i) {
    ++os.points;
    if (tracks[i].observations.size() < 2)
      continue;
    const bool f_ok = fused_o[i].ok(), r_ok = !run.refine_ok || refine_o[i].ok(), w_ok = window_o[i].ok();
    if (!f_ok)
      ++os.acc[0].not_ok;
    if (!r_ok)
      ++os.acc[1].not_ok;
    if (!w_ok)
      ++os.acc[2].not_ok;
    if (!f_ok || !r_ok || !w_ok)
      continue;
    if (!hasBound(t, i))
      continue;
    ++os.used;
    const double zt = t.z_true[i], cj = t.crlb_joint[i], cp = t.crlb_pp[i];
    os.acc[0].add(fused_o[i].c_P.z() - zt, cj, cp, fused_o[i].sigmaZ());
    if (run.refine_ok)
      os.acc[1].add(refine_o[i].c_P.z() - zt, cj, cp, refine_o[i].sigmaZ());
    os.acc[2].add(window_o[i].c_P.z() - zt, cj, cp, window_o[i].sigmaZ());
  }
}

/*! Every trial of scene `si`: clean into `cs`, with outliers into `os`. */
void runScene(const Setup &setup, const BenchArgs &args, std::size_t si, CleanStats &cs, OutlierStats &os,
              Timings &timings)
{
  const SceneSpec &spec = setup.specs[si];
  const bool arm = spec.isArm();
  SceneRun run{spec, arm ? setup.arm_camera : setup.paper_camera, arm ? setup.arm_rig : setup.paper_rig, {},
               setup.refine_ok, setup.outlier_fraction};
  const NoiseModel &noise = arm ? setup.arm_noise : setup.paper_noise;
  run.opt.noise = noise;
  run.opt.window = args.window;
  SceneOptions so;
  so.frames = args.frames;
  so.step = 0.02;
  so.yaw = spec.yaw_deg * kDeg;
  so.turn_rate = spec.turn_deg * kDeg;
  so.points = 30;
  so.min_depth = arm ? 0.4 : 0.5;
  so.max_depth = arm ? 0.8 : 3.0;
  so.noise = noise;
  for (long trial = 0; trial < args.trials; ++trial) {
    so.seed = args.seed + 100000ULL * si + static_cast<std::uint64_t>(trial);
    if (arm)
      so.vision_poses = armTrajectory(run.rig, static_cast<ArmPath>(spec.arm), so.frames, 0.6, so.seed);
    const Trial t = makeTrial(run, so);
    cleanTrial(run, t, cs, timings);
    outlierTrial(run, t, so.seed, os, timings);
  }
}

/*! Table 1: one table per scene, then pooled over the planar and over the arm scenes (returned). */
void printCleanTables(const Setup &setup, const std::vector<CleanStats> &clean, long trials, CleanStats &pooled,
                      CleanStats &pooled_arm)
{
  std::printf("\n1. CLEAN SCENES: depth zc at the last observed frame\n");
  std::printf("   not ok = points (>= 2 observations) the method did not report ok; each is excluded for all methods.\n"
              "   gross = points with |e| > %.0f x their per-point CRLB (they dominate an RMSE; the median does not).\n",
              kGross);
  for (std::size_t si = 0; si < setup.specs.size(); ++si) {
    printCleanTable("Scene: " + setup.specs[si].name(), clean[si], trials, setup.refine_ok);
    (setup.specs[si].isArm() ? pooled_arm : pooled).merge(clean[si]);
  }
  printCleanTable("Pooled over the six planar scenes (normalised squared errors pooled)", pooled, trials, setup.refine_ok);
  printCleanTable("Pooled over the three arm scenes (normalised squared errors pooled)", pooled_arm, trials,
                  setup.refine_ok);
}

void printSummaryRow(const std::string &name, const CleanStats &s, bool refine_ok)
{
  std::printf("%-16s", name.c_str());
  for (int m = 0; m < kMethods; ++m) {
    if (m == kRefine && !refine_ok) {
      std::printf(" %20s", "unavailable");
      continue;
    }
    const std::string cell = fmt("%.2f", 1e3 * s.acc[m].rmse()) + " [" + fmt("%.2f", s.acc[m].ratioJoint()) + "]";
    std::printf(" %20s", cell.c_str());
  }
  std::printf("\n");
}

/*! A table's rows: `print` of each scene's statistics (its short name), a rule, the pooled planar
    and arm statistics, a rule. */
template <class Stats, class PrintRows>
void printSceneRows(const Setup &setup, const std::vector<Stats> &per_scene, const Stats &pooled,
                    const Stats &pooled_arm, int width, PrintRows print)
{
  for (std::size_t si = 0; si < setup.specs.size(); ++si)
    print(setup.specs[si].shortName(), per_scene[si], setup.refine_ok);
  printRule(width);
  print("pooled planar", pooled, setup.refine_ok);
  print("pooled arm", pooled_arm, setup.refine_ok);
  printRule(width);
}

/*! Compact summary: RMSE/CRLB(joint) per scene and method. */
void printSummaryTable(const Setup &setup, const std::vector<CleanStats> &clean, const CleanStats &pooled,
                       const CleanStats &pooled_arm)
{
  std::printf("\nSummary: RMSE zc (mm) [RMSE/CRLB joint] per scene\n");
  const int W = 16 + 21 * kMethods;
  printRule(W);
  std::printf("%-16s", "scene");
  for (int m = 0; m < kMethods; ++m)
    std::printf(" %20s", kMethodNames[m]);
  std::printf("\n");
  printRule(W);
  printSceneRows(setup, clean, pooled, pooled_arm, W, printSummaryRow);
}

void printOutlierRows(const std::string &name, const OutlierStats &s, bool refine_ok)
{
  for (int m : {0, 2, 1}) {
    const char *mname = m == 0 ? "fused" : m == 1 ? "refine" : "window";
    if (m == 1 && !refine_ok) {
      std::printf("%-16s %-7s %s\n", "", mname, "refine: unavailable");
      continue;
    }
    const Acc &a = s.acc[m];
    const double recall = s.corrupted ? double(s.tp[m]) / s.corrupted : NAN;
    const long flagged = s.tp[m] + s.fp[m];
    const double precision = flagged ? double(s.tp[m]) / flagged : NAN;
    std::printf("%-16s %-7s %7ld %10s %9s %10s %10s %6ld %9s %7s %9s\n", m == 0 ? name.c_str() : "", mname,
                a.not_ok, fmt("%.2f", 1e3 * a.rmse()).c_str(), fmt("%.2f", 1e3 * a.medianAbs()).c_str(),
                fmt("%.3f", a.ratioJoint()).c_str(), fmt("%.3f", a.ratioPP()).c_str(), a.gross,
                fmt("%.3f", a.coverage()).c_str(), fmt("%.3f", recall).c_str(), fmt("%.3f", precision).c_str());
  }
}

/*! Table 2: the outlier scenes, per scene and pooled. */
void printOutlierTable(const Setup &setup, const std::vector<OutlierStats> &dirty)
{
  std::printf("\n2. OUTLIER SCENES: the same scenes, %.0f %% of observations moved by 10 to 50 px in a random\n"
              "   direction (inside the image). Bound: CRLB of the clean tracks (inlier CRLB).\n"
              "   recall = corrupted observations flagged / corrupted; precision = flagged and corrupted / flagged.\n",
              100 * setup.outlier_fraction);
  OutlierStats op, op_arm;
  for (std::size_t si = 0; si < setup.specs.size(); ++si)
    (setup.specs[si].isArm() ? op_arm : op).merge(dirty[si]);
  const int W = 112;
  printRule(W);
  std::printf("%-16s %-7s %7s %10s %9s %10s %10s %6s %9s %7s %9s\n", "scene", "method", "not ok", "RMSE zc", "median",
              "RMSE/CRLB", "RMSE/CRLB", "gross", "2-sigma", "outlier", "outlier");
  std::printf("%-16s %-7s %7s %10s %9s %10s %10s %6s %9s %7s %9s\n", "", "", "(pts)", "(mm)", "|e| (mm)", "joint",
              "per-point", "(pts)", "coverage", "recall", "precision");
  printRule(W);
  printSceneRows(setup, dirty, op, op_arm, W, printOutlierRows);
  std::printf("  pooled planar: %ld points, %ld used (fused, window and refine ok, >= 2 observations), %ld corrupted observations.\n",
              op.points, op.used, op.corrupted);
}

/*! Table 3: speed, and the total run time. */
void printSpeed(const Timings &timings, bool refine_ok, double total_s, long trials, std::size_t scenes)
{
  std::printf("\n3. SPEED (one thread, this machine)\n");
  if (refine_ok && !timings.refine_ms.empty()) {
    std::vector<double> t = timings.refine_ms;
    std::sort(t.begin(), t.end());
    const double median = t.size() % 2 ? t[t.size() / 2] : 0.5 * (t[t.size() / 2 - 1] + t[t.size() / 2]);
    std::printf("  refine (estimatePoints: fused start + refineWindow), 30 points x 10 frames, default options (%zu runs): "
                "min %.2f ms, median %.2f ms\n",
                t.size(), t.front(), median);
    if (!timings.refine_arm_ms.empty()) {
      std::vector<double> ta = timings.refine_arm_ms;
      std::sort(ta.begin(), ta.end());
      std::printf("  refine on the arm scenes (6-DoF chain, %zu runs): min %.2f ms, median %.2f ms\n", ta.size(),
                  ta.front(), ta[ta.size() / 2]);
    }
  } else {
    std::printf("  refine: unavailable\n");
  }
  std::printf("  fused (estimatePoints, Method::Fused): %.2f us per feature update (%ld observations)\n",
              timings.fused_obs ? 1e3 * timings.fused_ms / timings.fused_obs : NAN, timings.fused_obs);
  std::printf("  window (estimatePoints, Method::Window, 30 points): %.3f ms per frame (%ld frames; see bench_window for the cost table)\n",
              timings.window_frames ? timings.window_ms / timings.window_frames : NAN, timings.window_frames);
  if (timings.refine_errors)
    std::printf("  refine threw %ld times (counted as not ok)\n", timings.refine_errors);
  std::printf("\nTotal run time: %.1f s (%ld trials x %zu scenes, clean and with outliers)\n", total_s, trials, scenes);
}

} // namespace

int main(int argc, char **argv)
{
  BenchArgs args;
  const int status = parseArguments(argc, argv, args);
  if (status >= 0)
    return status;
  const Setup setup;
  printHeader(args, setup.refine_ok);

  const auto t_start = Clock::now();
  std::vector<CleanStats> clean(setup.specs.size());
  std::vector<OutlierStats> dirty(setup.specs.size());
  Timings timings;
  for (std::size_t si = 0; si < setup.specs.size(); ++si)
    runScene(setup, args, si, clean[si], dirty[si], timings);
  const double total_s = msSince(t_start) / 1e3;

  CleanStats pooled, pooled_arm;
  printCleanTables(setup, clean, args.trials, pooled, pooled_arm);
  printSummaryTable(setup, clean, pooled, pooled_arm);
  printOutlierTable(setup, dirty);
  printSpeed(timings, setup.refine_ok, total_s, args.trials, setup.specs.size());
  return 0;
}
