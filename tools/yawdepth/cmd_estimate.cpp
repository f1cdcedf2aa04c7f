// `yawdepth estimate`: points from a motion log and feature tracks.
#include "commands.h"
#include "method_options.h"
#include "progress.h"

#include <memory>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/io/files.h>

namespace yawdepth::cli {

namespace {

struct EstimateArgs {
  std::string camera, camera_name, rig, tracks, out, outliers, ply;
  MotionOptions motion;
  bool outliers_given = false, ply_given = false, quiet = false;
  MethodArgs method;
  InputOptions input;
};

} // namespace

Runner addEstimate(CLI::App &app)
{
  auto args = std::make_shared<EstimateArgs>();
  CLI::App *sub = app.add_subcommand("estimate", "Estimate each feature's 3D point from a motion log and feature tracks.");
  addCameraOptions(sub, args->camera, args->camera_name, true);
  addRigOption(sub, args->rig, true);
  addMotionOptions(sub, args->motion, "Motion log (frame,x,y,z,heading,yaw or 6-DoF)");
  sub->add_option("--tracks", args->tracks, "Feature tracks CSV (frame,id,u,v)")->required();
  addMethodOptions(sub, args->method, "exact");
  sub->add_option("--outliers", args->outliers,
                  "fused/refine: also write the observations rejected as outliers (CSV frame,id,u,v)")
      ->each([args](const std::string &) { args->outliers_given = true; });
  sub->add_option("--out", args->out, "Output points CSV (default: standard output); never one of the inputs");
  sub->add_option("--ply", args->ply,
                  "Also write the ok points as a PLY point cloud (world frame of the motion log, with sigma_z and id)")
      ->each([args](const std::string &) { args->ply_given = true; });
  addInputOptions(sub, args->input);
  addVerbosityOptions(sub, args->quiet, "No summaries on stderr (the time alignment, the residual check)");

  return [args]() {
    args->method.noise.validate();
    args->method.gates.validate();
    // Before anything is read or written: no output may replace an input or another output.
    std::vector<NamedPath> inputs = {{"--camera", args->camera}, {"--rig", args->rig}, {"--tracks", args->tracks}};
    for (const NamedPath &m : args->motion.inputs())
      inputs.push_back(m);
    std::vector<NamedPath> outputs; // --out, unless it is standard output (none, or "-")
    if (!args->out.empty() && args->out != "-")
      outputs.push_back({"--out", args->out});
    if (args->outliers_given)
      outputs.push_back({"--outliers", args->outliers});
    if (args->ply_given)
      outputs.push_back({"--ply", args->ply});
    checkOutputs(inputs, outputs);
    const CameraModel camera = loadCameraFile(args->camera, args->camera_name);
    const RigFile rig_file = readCommandRig("estimate", args->rig);
    const YawRig rig = rigOf(rig_file);
    MotionLog motion = loadCommandMotion("estimate", args->motion, &rig_file, args->input.limits(), args->quiet).log;
    checkMotionSteps(motion, args->motion.name());
    applyRigFile(rig_file, motion.samples);
    const std::vector<Track> tracks = readTracksCsv(args->tracks, args->input.limits());
    stage("estimate", "inputs read: " + std::to_string(tracks.size()) + " tracks");
    checkTracksAgainstMotion(tracks, motion, args->tracks);

    const MethodRun run = runMethodOnLog(camera, rig, motion, tracks, args->method);
    if (args->outliers_given)
      writeTracksCsv(args->outliers, rejectedObservations(tracks, run.outliers));
    writePointOutputs(args->out, args->ply_given ? &args->ply : nullptr, rig, motion, run);
    stage("estimate", "points written");
    return 0;
  };
}

} // namespace yawdepth::cli
