// `yawdepth estimate`: points from a motion log and feature tracks.
#include "commands.h"

#include <iostream>
#include <memory>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/io/files.h>
#include <yawdepth/refine/refine.h>

namespace yawdepth::cli {

namespace {

struct EstimateArgs {
  std::string camera, camera_name, rig, motion, tracks, out, outliers;
  double robust_px = RefineOptions().robust_threshold_px;
  double outlier_px = RefineOptions().outlier_threshold_px;
  std::string method = "exact";
  NoiseModel noise;
  GateOptions gates;
};

} // namespace

Runner addEstimate(CLI::App &app)
{
  auto args = std::make_shared<EstimateArgs>();
  CLI::App *sub = app.add_subcommand("estimate", "Estimate each feature's 3D point from a motion log and feature tracks.");
  sub->add_option("--camera", args->camera, "Camera file: ViSP XML or OpenCV YAML/XML")->required();
  sub->add_option("--camera-name", args->camera_name, "Camera name in a ViSP XML file (optional when it holds one)");
  sub->add_option("--rig", args->rig, "Rig file (YAML with camera_offset)")->required();
  sub->add_option("--motion", args->motion, "Motion log CSV (frame,x,y,z,heading,yaw)")->required();
  sub->add_option("--tracks", args->tracks, "Feature tracks CSV (frame,id,u,v)")->required();
  sub->add_option("--method", args->method,
                  "paper: eq. (5) on the last increment as published; exact: finite-increment two-view form (exact on "
                  "noise-free data); fused: recursive filter over every frame; refine: joint MAP of every point with the "
                  "motion (Ceres)")
      ->check(CLI::IsMember({"paper", "exact", "fused", "refine"}))
      ->capture_default_str();
  sub->add_option("--sigma-px", args->noise.sigma_px, "Pixel noise (px)")->check(FiniteNonNegative)->capture_default_str();
  sub->add_option("--sigma-odom", args->noise.sigma_odom, "Odometry translation noise per increment, per axis (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-heading", args->noise.sigma_heading, "Heading noise per increment (rad)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-yaw", args->noise.sigma_yaw, "Noise of each yaw reading (rad)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--min-baseline", args->gates.min_baseline, "Camera translation below this is no_motion (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--min-parallax-px", args->gates.min_parallax_px, "Parallax below this is degenerate (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--robust-threshold-px", args->robust_px, "refine: scale of the robust loss (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--outlier-threshold-px", args->outlier_px,
                  "refine: observations with a larger reprojection error are flagged as outliers (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--outliers", args->outliers,
                  "fused/refine: also write the observations rejected as outliers (CSV frame,id,u,v)");
  sub->add_option("--out", args->out, "Output points CSV (default: standard output)");

  return [args]() {
    args->noise.validate();
    args->gates.validate();
    const CameraModel camera = loadCameraFile(args->camera, args->camera_name);
    const RigFile rig_file = readRigFile(args->rig);
    const YawRig rig(rig_file.camera_offset);
    const MotionLog motion = readMotionCsv(args->motion, rig_file.yaw);
    const std::vector<Track> tracks = readTracksCsv(args->tracks);
    checkTracksAgainstMotion(tracks, motion, args->tracks);

    const bool refine = args->method == "refine";
    if (refine && !refineAvailable())
      throw Error("method refine is unavailable: this yawdepth was built without Ceres");
    TrackEstimatorOptions options;
    options.method = refine ? Method::Fused : methodFromString(args->method);
    options.two_view.noise = args->noise;
    options.two_view.gates = args->gates;
    std::vector<std::vector<bool>> flags;
    std::vector<PointEstimate> estimates = estimateTracks(camera, rig, motion.samples, tracks, options, &flags);
    if (refine) {
      RefineOptions ro;
      ro.noise = args->noise;
      ro.gates = args->gates;
      ro.robust_threshold_px = args->robust_px;
      ro.outlier_threshold_px = args->outlier_px;
      RefineResult r = refineWindow(camera, rig, motion.samples, tracks, estimates, ro);
      estimates = std::move(r.points);
      flags = std::move(r.outliers);
    }
    if (!args->outliers.empty()) {
      std::vector<Track> rejected;
      for (std::size_t i = 0; i < tracks.size(); ++i) {
        Track t;
        t.id = tracks[i].id;
        for (std::size_t k = 0; k < tracks[i].observations.size() && k < flags[i].size(); ++k)
          if (flags[i][k])
            t.observations.push_back(tracks[i].observations[k]);
        if (!t.observations.empty())
          rejected.push_back(t);
      }
      writeTracksCsv(args->outliers, rejected);
    }
    std::vector<PointRow> rows;
    rows.reserve(tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i)
      rows.push_back({tracks[i].id, estimates[i]});

    if (args->out.empty() || args->out == "-")
      writePointsCsv(std::cout, rows);
    else
      writePointsCsv(args->out, rows);
    return 0;
  };
}

} // namespace yawdepth::cli
