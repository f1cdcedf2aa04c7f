// The one estimation entry point (yawdepth::estimatePoints): each method through it gives exactly
// what the method's own function gives, refine starts from fused, unusable observations are taken
// out and flagged, bad options are refused with a reason, and the method words round-trip.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include "residual_statistics.h" // chi-square helpers, relativePoseSigma (modules/pipeline/src)
#include "scene_support.h"
#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/geometry/track_inputs.h>
#include <yawdepth/pipeline/pipeline.h>
#include <yawdepth/simulation/scene.h>
#include <yawdepth/window/stream_estimator.h>

using namespace yawdepth;
using yawdepth::test::paperCamera;
using yawdepth::test::paperRig;

namespace {

constexpr double kDeg = M_PI / 180.0;


Scene noisyScene(std::uint64_t seed)
{
  SceneOptions o;
  o.frames = 10;
  o.step = 0.02;
  o.yaw = 45 * kDeg;
  o.turn_rate = 0.5 * kDeg;
  o.points = 20;
  o.seed = seed;
  o.noise = NoiseModel{0.3, 1e-3, 0.05 * kDeg, 0.05 * kDeg};
  return simulateScene(paperCamera(), paperRig(), o);
}

// Bit-identical estimates (the pipeline adds no arithmetic of its own).
void requireSame(const std::vector<PointEstimate> &a, const std::vector<PointEstimate> &b)
{
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].status == b[i].status);
    CHECK(a[i].frame == b[i].frame);
    if (a[i].ok() && b[i].ok()) {
      CHECK(a[i].c_P == b[i].c_P);
      CHECK(a[i].c_cov == b[i].c_cov);
    }
  }
}

} // namespace

TEST_CASE("every method through estimatePoints gives what its own function gives", "[pipeline]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  const Scene s = noisyScene(7);
  PipelineOptions po;
  po.noise = NoiseModel{0.3, 1e-3, 0.05 * kDeg, 0.05 * kDeg};

  for (TrackMethod m : {TrackMethod::Paper, TrackMethod::Exact, TrackMethod::Fused}) {
    po.method = toMethod(m);
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, po);
    TrackEstimatorOptions to;
    to.method = m;
    to.noise = po.noise;
    std::vector<std::vector<bool>> flags;
    requireSame(r.points, estimateTracks(camera, rig, s.measured, s.tracks, to, &flags));
    CHECK(r.outliers == flags);
    REQUIRE(r.motion.size() == s.measured.size());
    CHECK(r.motion.back().x == s.measured.back().x); // the measured rows, as given
  }

  po.method = Method::Window;
  WindowOptions wo;
  wo.noise = po.noise;
  std::vector<std::vector<bool>> window_flags;
  const PipelineResult w = estimatePoints(camera, rig, s.measured, s.tracks, po);
  requireSame(w.points, windowTracks(camera, rig, s.measured, s.tracks, wo, &window_flags));
  CHECK(w.outliers == window_flags);
  std::size_t ok = 0;
  for (const PointEstimate &e : w.points)
    ok += e.ok() ? 1 : 0;
  CHECK(ok >= s.tracks.size() / 2); // a scene the methods can measure, not an all-degenerate one

  if (refineAvailable()) { // refine is started from fused on the same tracks
    po.method = Method::Fused;
    const std::vector<PointEstimate> fused = estimatePoints(camera, rig, s.measured, s.tracks, po).points;
    po.method = Method::Refine;
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, po);
    RefineOptions ro;
    ro.noise = po.noise;
    const RefineResult direct = refineWindow(camera, rig, s.measured, s.tracks, fused, ro);
    requireSame(r.points, direct.points);
    CHECK(r.outliers == direct.outliers);
    REQUIRE(r.motion.size() == direct.motion.size());
    CHECK(r.motion.back().x == direct.motion.back().x); // the refined rows
  }
}

TEST_CASE("an observation no method can use is taken out and flagged", "[pipeline]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  const Scene s = noisyScene(8);
  std::vector<Track> broken = s.tracks;
  REQUIRE(broken[0].observations.size() >= 4);
  std::vector<Track> without = s.tracks;
  broken[0].observations[1].u = std::numeric_limits<double>::quiet_NaN(); // not finite
  broken[1].observations[2].v = 1e6;                                       // far outside the image
  without[0].observations.erase(without[0].observations.begin() + 1);
  without[1].observations.erase(without[1].observations.begin() + 2);

  for (Method m : {Method::Exact, Method::Fused, Method::Window}) {
    PipelineOptions po;
    po.method = m;
    const PipelineResult r = estimatePoints(camera, rig, s.measured, broken, po);
    const PipelineResult clean = estimatePoints(camera, rig, s.measured, without, po);
    requireSame(r.points, clean.points);
    REQUIRE(r.outliers.size() == broken.size());
    CHECK(r.outliers[0].size() == broken[0].observations.size());
    CHECK(r.outliers[0][1]);
    CHECK(r.outliers[1][2]);
    // every other flag is the method's own, moved back onto the original observations
    for (std::size_t k = 0, kept = 0; k < broken[0].observations.size(); ++k)
      if (k != 1)
        CHECK(r.outliers[0][k] == clean.outliers[0][kept++]);
  }
}

TEST_CASE("estimatePoints refuses options that cannot give an answer", "[pipeline]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  const Scene s = noisyScene(9);
  PipelineOptions po;
  po.method = Method::Fused;
  po.noise.sigma_px = 0.0;
  CHECK_THROWS_AS(estimatePoints(camera, rig, s.measured, s.tracks, po), Error);
  po.method = Method::Exact; // exact does not weigh observations: no pixel noise is fine
  CHECK_NOTHROW(estimatePoints(camera, rig, s.measured, s.tracks, po));
  po = PipelineOptions();
  po.noise.pixel_correlation = 0.5; // only a method that models it takes it
  for (Method m : {Method::Paper, Method::Exact, Method::Fused}) {
    CHECK_FALSE(modelsTrackerCorrelation(m));
    po.method = m;
    CHECK_THROWS_AS(po.validate(), Error);
  }
  for (Method m : {Method::Window, Method::Refine}) {
    CHECK(modelsTrackerCorrelation(m));
    if (!methodAvailable(m))
      continue;
    po.method = m;
    CHECK_NOTHROW(estimatePoints(camera, rig, s.measured, s.tracks, po));
  }
  po = PipelineOptions();
  po.method = Method::Window;
  po.window = 1;
  CHECK_THROWS_AS(estimatePoints(camera, rig, s.measured, s.tracks, po), Error);
  po = PipelineOptions();
  po.method = Method::Window;
  po.robust_threshold_px = 0.0;
  CHECK_THROWS_AS(estimatePoints(camera, rig, s.measured, s.tracks, po), Error);
  po = PipelineOptions();
  po.noise.sigma_odom = -1.0;
  CHECK_THROWS_AS(estimatePoints(camera, rig, s.measured, s.tracks, po), Error);
  po = PipelineOptions();
  po.method = Method::Refine;
  po.threads = 0;
  CHECK_THROWS_AS(estimatePoints(camera, rig, s.measured, s.tracks, po), Error);
  CHECK(methodAvailable(Method::Refine) == refineAvailable());
  CHECK(bestMethod() == (refineAvailable() ? Method::Refine : Method::Fused));
  if (!refineAvailable()) {
    po = PipelineOptions();
    po.method = Method::Refine;
    CHECK_THROWS_AS(estimatePoints(camera, rig, s.measured, s.tracks, po), Error);
  }
}

TEST_CASE("method words round-trip, and each API takes its typed subset", "[pipeline]")
{
  for (Method m : {Method::Paper, Method::Exact, Method::Fused, Method::Window, Method::Refine})
    CHECK(methodFromString(toString(m)) == m);
  CHECK(std::string(toString(Method::Window)) == "window");
  CHECK_THROWS_AS(methodFromString("kalman"), Error);
  // The typed subsets: each API takes only the methods it runs, and their words parse to them alone.
  for (TrackMethod m : {TrackMethod::Paper, TrackMethod::Exact, TrackMethod::Fused}) {
    CHECK(trackMethodFromString(toString(m)) == m);
    CHECK(std::string(toString(m)) == toString(toMethod(m)));
  }
  for (StreamMethod m : {StreamMethod::Fused, StreamMethod::Window}) {
    CHECK(streamMethodFromString(toString(m)) == m);
    CHECK(std::string(toString(m)) == toString(toMethod(m)));
  }
  CHECK_THROWS_WITH(trackMethodFromString("window"), Catch::Contains("does not estimate each track on its own"));
  CHECK_THROWS_WITH(trackMethodFromString("refine"), Catch::Contains("does not estimate each track on its own"));
  CHECK_THROWS_WITH(streamMethodFromString("paper"), Catch::Contains("does not run frame by frame"));
  CHECK_THROWS_WITH(streamMethodFromString("kalman"), Catch::Contains("unknown method"));
}

namespace {

// The observations of every frame of a scene, by row; feature `stop_id` not given from row `stop_row` on.
std::vector<std::vector<FeatureObservation>> framesOf(const Scene &s, long stop_id = -1, std::size_t stop_row = 0)
{
  std::vector<std::vector<FeatureObservation>> frames(s.measured.size());
  for (const Track &t : s.tracks)
    for (const Observation &o : t.observations) {
      const long row = rowOfFrame(s.measured, o.frame);
      REQUIRE(row >= 0);
      if (t.id == stop_id && static_cast<std::size_t>(row) >= stop_row)
        continue;
      frames[static_cast<std::size_t>(row)].push_back({t.id, o.u, o.v});
    }
  return frames;
}

} // namespace

TEST_CASE("inputs: one check for every method, one message per rule, and the tracks by row", "[pipeline][inputs]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  const Scene s = noisyScene(11);
  // The view: every observation's row, and each row's observations in track order.
  const TracksByFrame view = validateInputs(s.measured, s.tracks);
  std::size_t indexed = 0, observations = 0;
  for (std::size_t r = 0; r < s.measured.size(); ++r)
    for (const TracksByFrame::Entry &e : view.observedAt(r)) {
      CHECK(view.row(e.first, e.second) == r);
      CHECK(s.tracks[e.first].observations[e.second].frame == s.measured[r].frame);
      ++indexed;
    }
  for (const Track &t : s.tracks)
    observations += t.observations.size();
  CHECK(indexed == observations);

  // Each broken rule: the same one-line message whatever the method, naming the feature and frame.
  struct Broken {
    const char *what;
    std::vector<MotionSample> motion;
    std::vector<Track> tracks;
    std::string message;
  };
  std::vector<Broken> cases;
  {
    Broken b{"frames not increasing", s.measured, s.tracks, ""};
    std::swap(b.motion[3], b.motion[4]);
    b.message = "motion log: frame " + std::to_string(b.motion[4].frame) + " after frame " +
                std::to_string(b.motion[3].frame) + ": frames must be strictly increasing";
    cases.push_back(b);
  }
  {
    Broken b{"planar and 6-DoF rows", s.measured, s.tracks, ""};
    b.motion[5].six_dof = !b.motion[5].six_dof;
    b.message = "is 6-DoF after planar rows";
    if (b.motion[0].six_dof)
      b.message = "is planar after 6-DoF rows";
    cases.push_back(b);
  }
  {
    Broken b{"a frame not in the log", s.measured, s.tracks, ""};
    b.tracks[2].observations.back().frame = 100000;
    b.message = "feature " + std::to_string(b.tracks[2].id) + " is observed in frame 100000, which the motion log does not have";
    cases.push_back(b);
  }
  {
    Broken b{"observations out of order", s.measured, s.tracks, ""};
    auto &obs = b.tracks[1].observations;
    REQUIRE(obs.size() >= 3);
    std::swap(obs[1], obs[2]);
    b.message = "feature " + std::to_string(b.tracks[1].id) + ": frame " + std::to_string(obs[2].frame) + " after frame " +
                std::to_string(obs[1].frame) + ": observations must be in strictly increasing frame order";
    cases.push_back(b);
  }
  {
    Broken b{"an id in two tracks", s.measured, s.tracks, ""};
    b.tracks[3].id = b.tracks[0].id;
    b.message = "feature " + std::to_string(b.tracks[0].id) + " is in two tracks";
    cases.push_back(b);
  }
  for (const Broken &b : cases) {
    INFO(b.what);
    CHECK_THROWS_WITH(validateInputs(b.motion, b.tracks), Catch::Contains(b.message));
    for (Method m : {Method::Paper, Method::Exact, Method::Fused, Method::Window}) {
      PipelineOptions po;
      po.method = m;
      CHECK_THROWS_WITH(estimatePoints(camera, rig, b.motion, b.tracks, po), Catch::Contains(b.message));
    }
    CHECK_THROWS_WITH(windowTracks(camera, rig, b.motion, b.tracks), Catch::Contains(b.message));
    CHECK_THROWS_WITH(estimateTracks(camera, rig, b.motion, b.tracks), Catch::Contains(b.message));
  }

  // Derived views: fewer observations of the same tracks, or another reading of the same frames.
  std::vector<Track> fewer = s.tracks;
  fewer[0].observations.erase(fewer[0].observations.begin());
  const TracksByFrame less = view.withFewer(fewer);
  CHECK(less.row(0, 0) == view.row(0, 1));
  std::vector<Track> foreign = s.tracks;
  foreign[0].observations.front().frame += 1000;
  CHECK_THROWS_AS(view.withFewer(foreign), Error);
  std::vector<MotionSample> negated = s.measured;
  for (MotionSample &m : negated)
    m.yaw = -m.yaw;
  CHECK(&view.withMotion(negated).motion() == &negated);
  negated.pop_back();
  CHECK_THROWS_AS(view.withMotion(negated), Error);
}

TEST_CASE("StreamEstimator: fused and window frame by frame, estimates carried to the current pose", "[pipeline]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  SceneOptions so; // noise-free: the carried point must be the true point at the later pose
  so.frames = 12;
  so.yaw = 60 * kDeg;
  so.turn_rate = 0.5 * kDeg;
  so.points = 12;
  so.seed = 11;
  const Scene s = simulateScene(camera, rig, so);
  const std::size_t last = s.measured.size() - 1, stop_row = last - 2; // feature 0 unseen in the last 3 frames
  REQUIRE(s.tracks[0].observations.size() == s.measured.size());
  const auto frames = framesOf(s, 0, stop_row);

  for (StreamMethod m : {StreamMethod::Fused, StreamMethod::Window}) {
    StreamOptions o;
    o.method = m;
    StreamEstimator stream(camera, rig, o);
    FusedEstimator fused(camera, rig, fusedOptions(o));
    WindowEstimator window(camera, rig, windowOptions(o));
    for (std::size_t r = 0; r < frames.size(); ++r) {
      stream.addFrame(s.measured[r], frames[r]);
      if (m == StreamMethod::Fused)
        fused.addFrame(s.measured[r], frames[r]);
      else
        window.addFrame(s.measured[r], frames[r]);
    }
    CHECK(stream.method() == m);
    for (const Track &t : s.tracks) { // the same estimator, nothing added
      const PointEstimate a = stream.estimate(t.id);
      const PointEstimate b = m == StreamMethod::Fused ? fused.estimate(t.id) : window.estimate(t.id);
      CHECK(a.status == b.status);
      if (a.ok() && b.ok())
        CHECK(a.c_P == b.c_P);
    }
    // Feature 0's estimate is at its last observed frame; carried to the last pose it is the true
    // point there (noise-free data: only the estimator's weak prior and round-off remain).
    const PointEstimate at_frame = stream.estimate(0);
    REQUIRE(at_frame.ok());
    CHECK(at_frame.frame == s.measured[stop_row - 1].frame);
    const PointEstimate carried = stream.estimateAt(0, s.measured[last]);
    REQUIRE(carried.ok());
    const Eigen::Vector3d truth = s.cameraPoint(rig, 0, last);
    const Eigen::Vector3d truth_then = s.cameraPoint(rig, 0, stop_row - 1);
    CHECK((carried.c_P - truth).norm() < 1e-3 * truth.norm());
    CHECK((truth - truth_then).norm() > 0.02); // the carry moved it (two 2 cm steps and a turn)
    CHECK(carried.v_P.isApprox(rig.visionPoint(s.measured[last].yaw, carried.c_P)));
    CHECK(carried.c_cov.trace() == Approx(at_frame.c_cov.trace()).epsilon(1e-9)); // rotated, not scaled
    // At its own frame the carry changes nothing.
    const PointEstimate same = stream.estimateAt(0, s.measured[stop_row - 1]);
    CHECK((same.c_P - at_frame.c_P).norm() < 1e-12);
    // Forgotten: unknown.
    stream.forget(0);
    CHECK(stream.estimate(0).status == Status::TooFewFrames);
  }

  // A frame older than the rows kept can no longer be carried: fused keeps max_missing_frames + 1.
  StreamOptions o;
  o.method = StreamMethod::Fused;
  o.max_missing_frames = 1;
  StreamEstimator stream(camera, rig, o);
  for (std::size_t r = 0; r < frames.size(); ++r)
    stream.addFrame(s.measured[r], frames[r]);
  CHECK(stream.estimate(0).status == Status::TooFewFrames); // dropped by fused itself after 1 missing frame
  const PointEstimate kept = stream.estimateAt(1, s.measured[last]);
  CHECK(kept.ok());

  // What each method's options are made of: the one noise model, and the settings it takes.
  StreamOptions set;
  set.noise.sigma_px = 0.7;
  set.noise.sigma_odom = 2e-3;
  set.window = 6;
  set.prior_depth = 4;
  set.max_missing_frames = 7;
  const WindowOptions wo = windowOptions(set);
  const FusedOptions fo = fusedOptions(set);
  CHECK((wo.noise.sigma_px == 0.7 && wo.noise.sigma_odom == 2e-3 && wo.window == 6 && wo.prior_inverse_depth == 0.25));
  CHECK((fo.filter.noise.sigma_px == 0.7 && fo.filter.noise.sigma_odom == 2e-3 && fo.filter.prior_depth == 4 &&
         fo.max_missing_frames == 7));
  StreamOptions bad;
  bad.prior_depth = 0;
  CHECK_THROWS_AS(StreamEstimator(camera, rig, bad), Error);
  bad = StreamOptions();
  bad.window = 1;
  CHECK_THROWS_AS(StreamEstimator(camera, rig, bad), Error);
  // The noise model's rules for the method (NoiseModel::validateFor, the pipeline's too): fused
  // neither models the tracker's correlated errors nor takes a zero pixel noise; window models them.
  bad = StreamOptions();
  bad.noise.pixel_correlation = 0.5;
  CHECK_NOTHROW(StreamEstimator(camera, rig, bad));
  bad.method = StreamMethod::Fused;
  CHECK_THROWS_WITH(StreamEstimator(camera, rig, bad), Catch::Contains("does not model correlated tracker errors"));
  bad = StreamOptions();
  bad.method = StreamMethod::Fused;
  bad.noise.sigma_px = 0;
  CHECK_THROWS_WITH(StreamEstimator(camera, rig, bad), Catch::Contains("needs at least 1e-6 px"));
}

// ---------------------------------------------------------------------------------------------
// The residual check (residual_check.h)

TEST_CASE("residual check: chi-square quantiles and medians (Wilson-Hilferty)", "[pipeline][residuals]")
{
  // Reference values (R's qchisq). Wilson-Hilferty is within 4 % at 1-4 degrees of freedom (above the
  // true quantile: a gate a little wider), within 1 % from 10.
  constexpr double kSmallDofTol = 0.04, kLargeDofTol = 0.01;
  const struct {
    int dof;
    double q999, median;
  } ref[] = {{1, 10.828, 0.45494}, {2, 13.816, 1.38629}, {5, 20.515, 4.35146},
             {10, 29.588, 9.34182}, {50, 86.661, 49.3349}, {100, 149.449, 99.3341}};
  for (const auto &r : ref) {
    const double tol = r.dof < 10 ? kSmallDofTol : kLargeDofTol;
    INFO("dof " << r.dof);
    CHECK(chiSquareQuantile(r.dof, 0.999) == Approx(r.q999).epsilon(tol));
    CHECK(chiSquareMedian(r.dof) == Approx(r.median).epsilon(tol));
  }
  CHECK(chiSquareQuantile(10, 0.95) == Approx(18.307).epsilon(kLargeDofTol));
  CHECK_THROWS_AS(chiSquareQuantile(0, 0.99), Error);
  CHECK_THROWS_AS(chiSquareQuantile(3, 1.0), Error);
  CHECK_THROWS_AS(chiSquareQuantile(3, 0.4), Error);
  CHECK_THROWS_AS(chiSquareMedian(0), Error);
}

TEST_CASE("residual check: the pose noise between two rows of a log", "[pipeline][residuals]")
{
  constexpr double kRoundOff = 1e-12;
  // Planar, straight steps of d: after n increments var_rot = n s_h^2 (+ two yaw readings) and
  // var_t = n s_o^2 + s_h^2 d^2 (0 + 1 + ... + n-1): each step turned by the heading error so far.
  const double d = 0.02, so = 1e-3, sh = 2e-3, sy = 1e-3;
  std::vector<MotionSample> log(6);
  for (std::size_t i = 0; i < log.size(); ++i) {
    log[i].frame = static_cast<long>(i);
    log[i].z = d * static_cast<double>(i);
  }
  NoiseModel n{0.3, so, sh, sy};
  double sr = 0, st = 0;
  relativePoseSigma(n, log, 1, 5, sr, st);
  const double k = 4;
  CHECK(sr == Approx(std::sqrt(k * sh * sh + 2 * sy * sy)).epsilon(kRoundOff));
  CHECK(st == Approx(std::sqrt(k * so * so + sh * sh * d * d * k * (k - 1) / 2)).epsilon(kRoundOff));
  double sr2 = 0, st2 = 0;
  relativePoseSigma(n, log, 5, 1, sr2, st2); // either order
  CHECK(sr2 == Approx(sr).epsilon(kRoundOff));
  CHECK(st2 == Approx(st).epsilon(kRoundOff));
  relativePoseSigma(n, log, 3, 3, sr, st);
  CHECK(sr == 0.0);
  CHECK(st == 0.0);
  // Per pose (kinematics): two independent pose errors, however far apart.
  n.motion_noise = MotionNoise::Absolute;
  relativePoseSigma(n, log, 0, 5, sr, st);
  CHECK(sr == Approx(std::sqrt(2 * sh * sh + 2 * sy * sy)).epsilon(kRoundOff));
  CHECK(st == Approx(std::sqrt(2.0) * so).epsilon(kRoundOff));
  CHECK_THROWS_AS(relativePoseSigma(n, log, 0, 6, sr, st), Error);
}

namespace {

// The regime where the pixels set the residuals (an arm's kinematics, a renderer's poses): motion
// noise of 10 um and 1 urad per increment, under 0.01 px at the paper's 1734 px focal length.
const NoiseModel kFineMotion{0.3, 1e-5, 1e-6, 1e-6};

// A scene of 60 points over 20 frames with pixel noise `true_px` and kFineMotion's motion noise.
Scene residualScene(double true_px, std::uint64_t seed)
{
  SceneOptions o = test::paperScene(45 * kDeg, 0.3 * kDeg, 20, seed);
  o.points = 60;
  o.noise = kFineMotion;
  o.noise.sigma_px = true_px;
  return simulateScene(paperCamera(), paperRig(), o);
}

PipelineOptions residualOptions(double model_px, bool check, Method method = Method::Fused)
{
  PipelineOptions po;
  po.method = method;
  po.noise = kFineMotion;
  po.noise.sigma_px = model_px;
  po.residual_check.enabled = check;
  return po;
}

// 2-sigma coverage of the ok points' depth.
double depthCoverage(const Scene &s, const std::vector<PointEstimate> &points, int &ok)
{
  int covered = 0;
  ok = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].ok())
      continue;
    ++ok;
    const std::size_t row = static_cast<std::size_t>(rowOfFrame(s.measured, points[i].frame));
    const double z_true = s.cameraPoint(paperRig(), s.tracks[i].id, row).z();
    covered += std::abs(points[i].c_P.z() - z_true) <= 2 * points[i].sigmaZ() ? 1 : 0;
  }
  return ok > 0 ? double(covered) / ok : 0.0;
}

} // namespace

TEST_CASE("residual check: the pixel noise from the residuals, the sigmas scaled when it was larger",
          "[pipeline][residuals]")
{
  constexpr double kFactorTol = 0.15; // s0 from the median of 60 tracks' chi-square ratios
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  SECTION("the noise model right: s0 near 1, nothing scaled much, almost nothing cut")
  {
    const Scene s = residualScene(0.3, 21);
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, true));
    CHECK(std::sqrt(r.residuals.variance_factor) == Approx(1.0).margin(kFactorTol));
    CHECK(r.residuals.sigma_scale <= 1 + kFactorTol);
    CHECK(r.residuals.noise_scale == 1.0); // within 10 %: not estimated again
    CHECK(r.residuals.tracks_used >= 50);
    CHECK(r.residuals.inconsistent <= 1);
  }
  SECTION("pixels twice as noisy as the model: the model scaled by s0 near 2, estimated again, coverage restored")
  {
    // fused rejects the observations its 0.3 px model finds too far (they are not in the residuals):
    // s0 comes out somewhat under 2. After the second run with the model scaled, s0 is near 1.
    constexpr double kLowTol = 0.2, kCutShare = 0.1;
    const Scene s = residualScene(0.6, 22);
    const PipelineResult plain = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, false));
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, true));
    CHECK(r.residuals.noise_scale >= 2.0 * (1 - kLowTol));
    CHECK(r.residuals.noise_scale <= 2.0 * (1 + kFactorTol));
    CHECK(std::sqrt(r.residuals.variance_factor) == Approx(1.0).margin(0.25));
    CHECK(r.residuals.inconsistent <= kCutShare * r.residuals.tracks_used);
    std::vector<double> ratio;
    for (std::size_t i = 0; i < r.points.size(); ++i)
      if (r.points[i].ok() && plain.points[i].ok())
        ratio.push_back(r.points[i].sigmaZ() / plain.points[i].sigmaZ());
    REQUIRE(ratio.size() >= 40);
    std::sort(ratio.begin(), ratio.end());
    CHECK(ratio[ratio.size() / 2] == Approx(r.residuals.noise_scale).epsilon(0.25));
    int ok_plain = 0, ok_checked = 0;
    const double before = depthCoverage(s, plain.points, ok_plain), after = depthCoverage(s, r.points, ok_checked);
    INFO("2-sigma coverage " << before << " -> " << after);
    CHECK(after >= 0.9);
    CHECK(after > before);
  }
  SECTION("pixels five times more precise than the model: the model made tighter, sigmas that say so")
  {
    const Scene s = residualScene(0.06, 28);
    const PipelineResult plain = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, false));
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, true));
    CHECK(r.residuals.noise_scale == Approx(0.2).epsilon(0.3));
    int ok_plain = 0, ok_checked = 0;
    const double before = depthCoverage(s, plain.points, ok_plain), after = depthCoverage(s, r.points, ok_checked);
    INFO("2-sigma coverage " << before << " -> " << after);
    CHECK(before > 0.99); // the model's sigmas 5 times too large
    CHECK(after >= 0.9);
    CHECK(after <= 0.99);
    CHECK(ok_checked >= ok_plain - 3);
  }
}

TEST_CASE("residual check: a track that is not one point is inconsistent, the others stay ok", "[pipeline][residuals]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  Scene s = residualScene(0.3, 23);
  // Track 0 slides down the image, 0.4 px more each frame (a T-junction: where a near edge crosses a
  // far one, the corner moves along the near edge): across the epipolar lines of this forward motion
  // (nearly horizontal here), too slowly for a frame-to-frame gate, 8 px over the track. A slide
  // along the epipolar line would only change the depth: no check on one track can see that.
  REQUIRE(s.tracks[0].observations.size() >= 10);
  for (std::size_t k = 0; k < s.tracks[0].observations.size(); ++k)
    s.tracks[0].observations[k].v += 0.4 * static_cast<double>(k);
  // window: its robust loss takes the slide in (fused's own gate would reject the track here).
  const PipelineResult plain =
      estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, false, Method::Window));
  const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, true, Method::Window));
  CHECK(plain.points[0].ok()); // what the method alone makes of it
  CHECK(r.points[0].status == Status::Inconsistent);
  CHECK(r.residuals.tracks[0].rms_px > 1.0);
  int ok_plain = 0, ok_checked = 0;
  for (std::size_t i = 1; i < r.points.size(); ++i) {
    ok_plain += plain.points[i].ok() ? 1 : 0;
    ok_checked += r.points[i].ok() ? 1 : 0;
  }
  CHECK(ok_checked >= ok_plain - 1);
}

TEST_CASE("residual check: correlated tracker errors raise the sigmas they make too small", "[pipeline][residuals]")
{
  // Each track's pixel errors an AR(1) sequence along the track (correlation 0.9 per frame, 0.3 px
  // per axis): a tracker whose error persists from frame to frame. window weighs every frame as new
  // information; the check finds the correlation in the residuals and raises its depth sigmas.
  constexpr double kRho = 0.9, kSigma = 0.3;
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  Scene s = residualScene(0.0, 25);
  std::mt19937_64 rng(26);
  std::normal_distribution<double> g(0.0, kSigma * std::sqrt(1 - kRho * kRho));
  std::normal_distribution<double> g0(0.0, kSigma);
  for (Track &t : s.tracks) {
    Eigen::Vector2d e(g0(rng), g0(rng));
    for (Observation &o : t.observations) {
      o.u += e.x();
      o.v += e.y();
      e = kRho * e + Eigen::Vector2d(g(rng), g(rng));
    }
  }
  const PipelineResult plain = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(kSigma, false, Method::Window));
  const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(kSigma, true, Method::Window));
  // The correlation measured (the whitened residuals' zero), and window run with it: its own sigmas
  // are then honest, the floor has little to raise.
  constexpr double kCorrelationTolerance = 0.1;
  INFO("correlation measured " << r.residuals.correlation << ", " << r.residuals.correlation_scaled << " raised");
  CHECK(std::abs(r.residuals.correlation - kRho) < kCorrelationTolerance);
  int ok_plain = 0, ok_checked = 0;
  const double before = depthCoverage(s, plain.points, ok_plain), after = depthCoverage(s, r.points, ok_checked);
  INFO("2-sigma coverage " << before << " (" << ok_plain << " ok) -> " << after << " (" << ok_checked << " ok)");
  CHECK(before < 0.85);
  CHECK(after >= 0.90);
  CHECK(ok_checked >= ok_plain - 3);
  // White errors: no correlation found, nothing raised (the first test case's scene).
  const Scene w = residualScene(0.3, 21);
  const PipelineResult white = estimatePoints(camera, rig, w.measured, w.tracks, residualOptions(0.3, true, Method::Window));
  INFO("white errors: model w " << white.residuals.error_model.white << ", phi " << white.residuals.error_model.phi
                                 << ", variance " << white.residuals.error_model.variance);
  CHECK(white.residuals.correlation < 0.2);
  CHECK(white.residuals.correlation_scaled <= 3);
}

TEST_CASE("max_depth_sigma: an ok depth not resolved to the share asked is degenerate", "[pipeline][residuals]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  const Scene s = residualScene(0.3, 27);
  PipelineOptions po = residualOptions(0.3, false);
  const PipelineResult all = estimatePoints(camera, rig, s.measured, s.tracks, po);
  po.max_depth_sigma = 0.01;
  const PipelineResult gated = estimatePoints(camera, rig, s.measured, s.tracks, po);
  int kept = 0, cut = 0;
  for (std::size_t i = 0; i < all.points.size(); ++i) {
    if (!all.points[i].ok())
      continue;
    const bool precise = all.points[i].sigmaZ() <= 0.01 * all.points[i].c_P.z();
    CHECK(gated.points[i].status == (precise ? Status::Ok : Status::Degenerate));
    (precise ? kept : cut) += 1;
  }
  CHECK(kept > 0);
  CHECK(cut > 0);
  po.max_depth_sigma = -1;
  CHECK_THROWS_AS(po.validate(), Error);
  po.max_depth_sigma = std::nan("");
  CHECK_THROWS_AS(po.validate(), Error);
}

TEST_CASE("residual check: bad options and input", "[pipeline][residuals]")
{
  ResidualCheckOptions o;
  o.gate_probability = 1.0;
  CHECK_THROWS_AS(o.validate(), Error);
  o.gate_probability = 0.5;
  CHECK_THROWS_AS(o.validate(), Error);
  o = ResidualCheckOptions();
  o.min_tracks = 0;
  CHECK_THROWS_AS(o.validate(), Error);
  PipelineOptions po;
  po.residual_check.gate_probability = std::nan("");
  CHECK_THROWS_AS(po.validate(), Error);
  const Scene s = residualScene(0.3, 24);
  std::vector<PointEstimate> fewer(s.tracks.size() - 1);
  CHECK_THROWS_AS(checkResiduals(paperCamera(), paperRig(), s.measured, s.tracks, {}, NoiseModel(),
                                 ResidualCheckOptions(), fewer),
                  Error);
}

TEST_CASE("estimatePoints: the whole log against the noise model, and points their tracks cannot confirm",
          "[pipeline][residuals]")
{
  const CameraModel camera = paperCamera();
  const YawRig rig = paperRig();
  SECTION("the model right: s0 measured, no warning, no mistake, the same points as without the rule")
  {
    const Scene s = residualScene(0.3, 41);
    for (const Method m : {Method::Fused, Method::Window, Method::Refine}) {
      const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, false, m));
      INFO(toString(m) << " s0 " << r.consistency.s0);
      CHECK(r.consistency.tracks_used >= 40);
      CHECK(r.consistency.s0 < 1.5);
      CHECK_FALSE(r.consistency.mistake);
      CHECK(r.warnings.empty());
    }
  }
  SECTION("pixels twice as noisy, the check off: a warning that the sigmas are too small")
  {
    const Scene s = residualScene(0.6, 42);
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, false, Method::Window));
    CHECK(r.consistency.s0 > 1.5);
    CHECK_FALSE(r.consistency.mistake);
    REQUIRE(r.warnings.size() == 1);
    CHECK(r.warnings[0].find("too small") != std::string::npos);
    // With the check on, the model is re-estimated and the whole log's figure kept from the first run.
    const PipelineResult c = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, true, Method::Window));
    CHECK(c.residuals.noise_scale > 1.5);
    CHECK(c.consistency.s0 == Approx(r.consistency.s0));
    CHECK(c.warnings.empty());
  }
  SECTION("random tracks (every pixel uniform over the image): a mistake, warned, no ok point left")
  {
    // (A frame offset on this scene's even steps is another consistent scene: tests/mistakes_cli.sh
    // shifts an arm's uneven ones.)
    const Scene s = residualScene(0.3, 43);
    std::vector<Track> random = s.tracks;
    std::mt19937_64 rng(43);
    std::uniform_real_distribution<double> U(0, 1);
    for (Track &t : random)
      for (Observation &o : t.observations) {
        o.u = camera.width() * U(rng);
        o.v = camera.height() * U(rng);
      }
    for (const Method m : {Method::Fused, Method::Window, Method::Refine})
      for (const bool check : {false, true}) {
        const PipelineResult r = estimatePoints(camera, rig, s.measured, random, residualOptions(0.3, check, m));
        INFO(toString(m) << (check ? " checked" : "") << " s0 " << r.consistency.s0 << " rejected "
                         << r.consistency.outlier_share);
        int ok = 0;
        for (const PointEstimate &p : r.points)
          ok += p.ok() ? 1 : 0;
        CHECK(ok == 0);
        CHECK(r.consistency.mistake);
        CHECK(r.warnings.size() == 1);
      }
  }
  SECTION("a flipped lever arm or yaw sign: a warning that names it; the rig and log as given: none")
  {
    const Scene s = residualScene(0.3, 45);
    const YawRig flipped(Eigen::Vector3d(0.1503, 0.0, 0.0));
    std::vector<MotionSample> yaw_negated = s.measured;
    for (MotionSample &row : yaw_negated)
      row.yaw = -row.yaw;
    auto names = [](const PipelineResult &r, const std::string &what) {
      for (const std::string &w : r.warnings)
        if (w.find("with " + what) != std::string::npos && w.find("flipped the tracks fit better") != std::string::npos)
          return true;
      return false;
    };
    for (const Method m : {Method::Fused, Method::Window, Method::Refine}) {
      INFO(toString(m));
      const PipelineResult right = estimatePoints(camera, rig, s.measured, s.tracks, residualOptions(0.3, false, m));
      CHECK(right.warnings.empty());
      CHECK(names(estimatePoints(camera, flipped, s.measured, s.tracks, residualOptions(0.3, false, m)),
                  "the lever arm's sign"));
      const PipelineResult y = estimatePoints(camera, rig, yaw_negated, s.tracks, residualOptions(0.3, true, m));
      CHECK(names(y, "the yaw's sign"));
    }
  }
  SECTION("small clean scenes (about as many tracks as min_tracks): no doubt raised")
  {
    // A held-out check found it: 25 points over 12 frames, the pan turning; fused as given checked 19
    // tracks (under min_tracks, so no s0), the negated yaw 20 at s0 2.2, and "the yaw's sign" was
    // named on a clean log. An unmeasured fit as given is a mistake only when the alternative fits.
    int runs = 0;
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      SceneOptions o = test::paperScene(0.3, 0.01, 12, seed);
      o.points = 25;
      o.yaw_rate = 0.02;
      o.lateral_step = 0.005;
      o.noise = NoiseModel{0.3, 0.001, 0.0008, 0.0008};
      const Scene s = simulateScene(camera, rig, o);
      for (const Method m : {Method::Fused, Method::Window}) {
        PipelineOptions po;
        po.method = m;
        po.noise = o.noise;
        const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, po);
        INFO("seed " << seed << " " << toString(m));
        for (const std::string &w : r.warnings)
          CHECK(w.find("flipped the tracks fit better") == std::string::npos);
        ++runs;
      }
    }
    CHECK(runs == 24);
  }
  SECTION("a wall beside a drive, the rig and log as given: no doubt raised, although a flipped yaw fits part of it")
  {
    // examples/bag_drive's geometry: the camera looks sideways at a wall 0.62 m away while the body
    // turns 4 deg and the pan 20 deg; short tracks, the pixels far better than the model (as KLT on
    // a render) and the motion too. A flipped yaw loses tracks to the gates and fits the rest better
    // (without kMinTrackShare in rig_doubts.cpp both methods warned).
    SceneOptions o = test::paperScene(1.36, 0.07 / 69, 70, 46);
    o.step = 0.35 / 69;
    o.yaw_rate = 0.35 / 69;
    o.noise = NoiseModel{0.08, 0.0002, 0.0, 0.0}; // simulate --sigma-odom 0.0002, KLT's 0.08 px
    std::mt19937_64 rng(46);
    std::uniform_real_distribution<double> U(0, 1);
    for (int i = 0; i < 600; ++i)
      o.world_points.emplace_back(0.62, -0.15 + 0.3 * U(rng), -0.1 + 0.6 * U(rng));
    const Scene s = simulateScene(camera, rig, o);
    // Short tracks, as a tracker's: a random span of 2 to 12 observations of each point.
    std::vector<Track> tracks;
    for (const Track &t : s.tracks) {
      const std::size_t n = t.observations.size();
      if (n < 2)
        continue;
      const std::size_t len = std::min<std::size_t>(n, 2 + static_cast<std::size_t>(11 * U(rng)));
      const std::size_t first = static_cast<std::size_t>((n - len + 1) * U(rng)) % (n - len + 1);
      Track cut = t;
      cut.observations.assign(t.observations.begin() + first, t.observations.begin() + first + len);
      tracks.push_back(cut);
    }
    REQUIRE(tracks.size() >= 100);
    for (const Method m : {Method::Fused, Method::Window}) {
      INFO(toString(m));
      PipelineOptions po = residualOptions(0.3, true, m);
      po.noise = NoiseModel{0.3, 0.0002, 0.05 * kDeg, 0.05 * kDeg}; // measure's defaults, --sigma-odom 0.0002
      const PipelineResult r = estimatePoints(camera, rig, s.measured, tracks, po);
      for (const std::string &w : r.warnings)
        INFO(w);
      CHECK(r.warnings.empty());
    }
  }
  SECTION("an ok point whose observations were mostly rejected is inconsistent")
  {
    const Scene s = residualScene(0.3, 44);
    std::vector<Track> tracks = s.tracks;
    // One track's observations all but the last two moved by 40 px: the methods reject them.
    Track &t = tracks.front();
    REQUIRE(t.observations.size() >= 8);
    for (std::size_t k = 0; k + 2 < t.observations.size(); ++k)
      t.observations[k].u += (k % 2 ? 40.0 : -40.0);
    for (const Method m : {Method::Window, Method::Refine}) {
      const PipelineResult r = estimatePoints(camera, rig, s.measured, tracks, residualOptions(0.3, false, m));
      INFO(toString(m) << " status " << toString(r.points.front().status));
      CHECK_FALSE(r.points.front().ok());
    }
  }
}
