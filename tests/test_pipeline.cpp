// The one estimation entry point (yawdepth::estimatePoints): each method through it gives exactly
// what the method's own function gives, refine starts from fused, unusable observations are taken
// out and flagged, bad options are refused with a reason, and the method words round-trip.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include "scene_support.h"
#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
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

  for (Method m : {Method::Paper, Method::Exact, Method::Fused}) {
    po.method = m;
    const PipelineResult r = estimatePoints(camera, rig, s.measured, s.tracks, po);
    TrackEstimatorOptions to;
    to.method = m;
    to.two_view.noise = po.noise;
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

TEST_CASE("method words round-trip, and estimateTracks sends window and refine to the pipeline", "[pipeline]")
{
  for (Method m : {Method::Paper, Method::Exact, Method::Fused, Method::Window, Method::Refine})
    CHECK(methodFromString(toString(m)) == m);
  CHECK(std::string(toString(Method::Window)) == "window");
  CHECK_THROWS_AS(methodFromString("kalman"), Error);
  const Scene s = noisyScene(10);
  TrackEstimatorOptions to;
  for (Method m : {Method::Window, Method::Refine}) {
    to.method = m;
    CHECK_THROWS_AS(estimateTracks(paperCamera(), paperRig(), s.measured, s.tracks, to), Error);
    CHECK_THROWS_AS(estimateTrack(paperCamera(), paperRig(), s.measured, s.tracks[0], to), Error);
  }
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

  for (Method m : {Method::Fused, Method::Window}) {
    StreamOptions o;
    o.method = m;
    StreamEstimator stream(camera, rig, o);
    FusedEstimator fused(camera, rig, o.fused);
    WindowEstimator window(camera, rig, o.window);
    for (std::size_t r = 0; r < frames.size(); ++r) {
      stream.addFrame(s.measured[r], frames[r]);
      if (m == Method::Fused)
        fused.addFrame(s.measured[r], frames[r]);
      else
        window.addFrame(s.measured[r], frames[r]);
    }
    CHECK(stream.method() == m);
    CHECK((stream.fusedEstimator() != nullptr) == (m == Method::Fused));
    CHECK((stream.windowEstimator() != nullptr) == (m == Method::Window));
    for (const Track &t : s.tracks) { // the same estimator, nothing added
      const PointEstimate a = stream.estimate(t.id);
      const PointEstimate b = m == Method::Fused ? fused.estimate(t.id) : window.estimate(t.id);
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
  o.method = Method::Fused;
  o.fused.max_missing_frames = 1;
  StreamEstimator stream(camera, rig, o);
  for (std::size_t r = 0; r < frames.size(); ++r)
    stream.addFrame(s.measured[r], frames[r]);
  CHECK(stream.estimate(0).status == Status::TooFewFrames); // dropped by fused itself after 1 missing frame
  const PointEstimate kept = stream.estimateAt(1, s.measured[last]);
  CHECK(kept.ok());

  for (Method m : {Method::Paper, Method::Exact, Method::Refine}) {
    StreamOptions bad;
    bad.method = m;
    CHECK_THROWS_AS(StreamEstimator(camera, rig, bad), Error);
  }
}
