#include "method_options.h"

#include "commands.h"
#include "progress.h"

#include <cmath>
#include <cstdio>
#include <iostream>

#include <yawdepth/error.h>
#include <yawdepth/pipeline/pipeline.h>

namespace yawdepth::cli {

std::string bestMethod() { return toString(yawdepth::bestMethod()); }

void addMotionNoiseOptions(CLI::App *sub, MethodArgs &args)
{
  sub->add_option("--sigma-odom", args.noise.sigma_odom, "Odometry translation noise per increment, per axis (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-heading", args.noise.sigma_heading, "Heading noise per increment (rad), planar motion logs")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-rot", args.noise.sigma_rot, "Rotation noise per increment, per axis (rad), 6-DoF motion logs")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--odom-per-metre", args.noise.odom_per_metre,
                  "Odometry translation noise per metre travelled, per axis (m/m), added to --sigma-odom in variance: "
                  "the drift of wheel odometry whatever the rate of the images (increment noise only)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--rot-per-radian", args.noise.rot_per_radian,
                  "Rotation noise per radian turned (rad/rad), added to --sigma-heading/--sigma-rot in variance "
                  "(increment noise only)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--rot-per-metre", args.noise.rot_per_metre,
                  "Rotation noise per metre travelled (rad/m): wheel slip turning the heading (increment noise only)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--pixel-correlation", args.noise.pixel_correlation,
                  "window, refine: correlation of the tracker's errors from one image of a track to the next (AR(1), 0 to 0.99); "
                  "0: independent, or, with the residual check on and per-increment motion noise, measured from the residuals")
      ->check(CLI::Range(0.0, kMaxPixelCorrelation))
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--motion-noise", [&args](const std::string &w) { args.noise.motion_noise = motionNoiseFromString(w); },
         "How the motion log errs: increment (odometry, VIO: --sigma-odom/--sigma-heading/--sigma-rot per increment, "
         "the errors accumulate) or absolute (forward kinematics, motion capture: the same sigmas per pose)")
      ->check(CLI::IsMember({"increment", "absolute"}))
      ->default_str("increment");
  args.sigma_yaw_option = sub->add_option("--sigma-yaw", args.noise.sigma_yaw,
                                          "Noise of each yaw reading (rad); 0 by default for a 6-DoF log without a yaw column")
                              ->check(FiniteNonNegative)
                              ->capture_default_str();
}

void addMethodOptions(CLI::App *sub, MethodArgs &args, const std::string &default_method)
{
  args.command = sub->get_name();
  args.method = default_method;
  args.robust_px = RefineOptions().robust_threshold_px;
  args.outlier_px = RefineOptions().outlier_threshold_px;
  args.method_option = sub->add_option("--method", args.method,
                  "paper: eq. (5) on the last increment as published; exact: finite-increment two-view form (exact on "
                  "noise-free data); fused: recursive filter per feature over every frame (cheapest); window: "
                  "frame-by-frame smoother of every point with the last 10 frames' motion, older frames marginalised "
                  "(at the joint bound, what a servo loop gets); refine: joint MAP of every point with the motion over "
                  "all frames (Ceres)")
      ->check(CLI::IsMember({"paper", "exact", "fused", "window", "refine"}))
      ->capture_default_str();
  sub->add_option("--sigma-px", args.noise.sigma_px, "Pixel noise (px)")->check(FiniteNonNegative)->capture_default_str();
  addMotionNoiseOptions(sub, args);
  sub->add_option("--min-baseline", args.gates.min_baseline, "Camera translation below this is no_motion (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--min-parallax-px", args.gates.min_parallax_px, "Parallax below this is degenerate (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--robust-threshold-px", args.robust_px, "refine and window: scale of the robust loss (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--outlier-threshold-px", args.outlier_px,
                  "refine and window: observations with a larger reprojection error are flagged as outliers (px)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--threads", args.threads, "refine: threads of the solver (Ceres)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  args.residual_option =
      sub->add_option("--residual-check", args.residual_check,
                      "fused, window, refine: every ok point against its whole track; the noise model scaled to what "
                      "the residuals show (the method run again) when they see all of it, the sigmas raised when they "
                      "show more noise, and a track that is not one point (chi-square gate at 99.9 %, at the model "
                      "given) inconsistent (on by default with --features klt)")
          ->check(CLI::IsMember({"on", "off"}))
          ->capture_default_str();
  args.max_depth_sigma_option =
      sub->add_option("--max-depth-sigma", args.max_depth_sigma,
                      "An ok point whose depth sigma exceeds this share of its depth is degenerate (0: no such gate; "
                      "0.05 by default with --features klt)")
          ->check(FiniteNonNegative)
          ->capture_default_str();
}

NoiseModel noiseForLog(const MethodArgs &args, bool six_dof, bool yaw_column)
{
  return noiseForMotionLog(args.noise, six_dof, yaw_column,
                           args.sigma_yaw_option != nullptr && args.sigma_yaw_option->count() > 0);
}


std::vector<Track> rejectedObservations(const std::vector<Track> &tracks, const std::vector<std::vector<bool>> &outliers)
{
  std::vector<Track> rejected;
  for (std::size_t i = 0; i < tracks.size() && i < outliers.size(); ++i) {
    Track t;
    t.id = tracks[i].id;
    for (std::size_t k = 0; k < tracks[i].observations.size() && k < outliers[i].size(); ++k)
      if (outliers[i][k])
        t.observations.push_back(tracks[i].observations[k]);
    if (!t.observations.empty())
      rejected.push_back(t);
  }
  return rejected;
}

MethodRun runMethodOnLog(const CameraModel &camera, const YawRig &rig, const MotionLog &motion,
                         const std::vector<Track> &tracks, const MethodArgs &args)
{
  PipelineOptions po;
  po.method = methodFromString(args.method);
  po.noise = noiseForLog(args, !motion.samples.empty() && motion.samples.front().six_dof, motion.yaw_column);
  po.gates = args.gates;
  po.robust_threshold_px = args.robust_px;
  po.outlier_threshold_px = args.outlier_px;
  po.threads = args.threads;
  po.residual_check.enabled = args.residual_check == "on";
  po.max_depth_sigma = args.max_depth_sigma;
  PipelineResult r;
  {
    ProgressLine line;
    if (po.method == Method::Refine)
      po.progress = line.refineCallback();
    r = estimatePoints(camera, rig, motion.samples, tracks, po);
  }
  stage(args.command, args.method + " on " + std::to_string(tracks.size()) + " tracks x " +
                          std::to_string(motion.samples.size()) + " frames");
  const bool checked = po.residual_check.enabled && po.method != Method::Paper && po.method != Method::Exact;
  if (checked && !verbosity().quiet && r.residuals.noise_scale != 1.0)
    std::fprintf(stderr, "residual check: the noise model scaled by %.3g from the residuals (pixel noise %.3g px), "
                 "estimated again\n", r.residuals.noise_scale, r.noise.sigma_px);
  if (checked && !verbosity().quiet)
    std::fprintf(stderr,
                 "residual check: pixel noise from the residuals %.3g px (model %.3g px)%s; tracker errors' "
                 "correlation %.2f (%d depths' sigma raised for it); %d of %d tracks not one point (inconsistent)\n",
                 r.noise.sigma_px * std::sqrt(r.residuals.variance_factor), r.noise.sigma_px,
                 r.residuals.sigma_scale > 1 ? (", sigmas scaled by " + std::to_string(r.residuals.sigma_scale).substr(0, 5)).c_str() : "",
                 r.residuals.correlation, r.residuals.correlation_scaled, r.residuals.inconsistent,
                 r.residuals.tracks_used);
  for (const std::string &w : r.warnings)
    warn(args.command, w);
  MethodRun run;
  run.outliers = std::move(r.outliers);
  run.motion_estimate = std::move(r.motion);
  run.rows.reserve(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i)
    run.rows.push_back({tracks[i].id, r.points[i]});
  return run;
}

void writePointOutputs(const std::string &out, const std::string *ply, const YawRig &rig, const MotionLog &motion,
                       const MethodRun &run, const std::map<std::pair<long, long>, int> &gray)
{
  if (ply != nullptr)
    writePointsPly(*ply, plyPoints(rig, run.motion_estimate.empty() ? motion.samples : run.motion_estimate, run.rows,
                                   gray));
  if (out.empty() || out == "-")
    writePointsCsv(std::cout, run.rows);
  else
    writePointsCsv(out, run.rows);
}

} // namespace yawdepth::cli
