// `yawdepth import`: a user's recording (a timestamped pose log and timestamped images, or ViSP
// pose files and their images) written as the frame-based motion log every command reads.
#include "commands.h"

#include <filesystem>
#include <iostream>
#include <memory>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>
#include <yawdepth/io/recording.h>

namespace yawdepth::cli {

namespace {

struct ImportArgs {
  MotionOptions motion;
  std::string rig, out_dir;
  InputOptions input;
  bool quiet = false;
};

int runImport(const ImportArgs &a)
{
  const std::string out = (std::filesystem::path(a.out_dir) / "motion.csv").string();
  std::vector<NamedPath> inputs = a.motion.inputs();
  if (!a.rig.empty())
    inputs.push_back({"--rig", a.rig});
  checkOutputs(inputs, {{"--out-dir", out}});
  RigFile rig_file;
  if (!a.rig.empty())
    rig_file = readCommandRig("import", a.rig);
  const LoadedMotion m =
      loadMotion(a.motion.input(), a.rig.empty() ? std::nullopt : rig_file.yaw,
                 a.rig.empty() ? std::nullopt : rig_file.time_offset, a.input.limits());
  if (m.log.timestamped)
    throw Error(a.motion.name() + ": a timestamped log needs --images to be imported");
  std::error_code ec;
  std::filesystem::create_directories(a.out_dir, ec);
  if (ec || !std::filesystem::is_directory(a.out_dir))
    throw Error("--out-dir " + a.out_dir + ": cannot create the folder" + (ec ? ": " + ec.message() : std::string()));
  for (const std::string &image : m.log.images)
    inputs.push_back({"--images' image", image});
  checkOutputs(inputs, {{"--out-dir", out}});
  writeMotionCsv(out, m.log);
  if (!a.quiet) {
    std::cout << "read " << a.motion.name() << " (" << toString(m.format) << ")";
    if (m.alignment)
      std::cout << " and " << a.motion.images << ": " << m.alignment->summary() << "; time offset " << m.time_offset
                << " s";
    std::cout << "\nwrote " << out << ": " << m.log.samples.size() << " frames"
              << (m.log.images.empty() ? "" : " with their images") << "\n";
  }
  return 0;
}

} // namespace

Runner addImport(CLI::App &app)
{
  auto a = std::make_shared<ImportArgs>();
  CLI::App *sub = app.add_subcommand(
      "import", "Write a recording (a timestamped pose log with timestamped images, or ViSP pose files with their "
                "images) as the frame-based motion log every command reads: each image's pose interpolated at its "
                "time (SE(3)), images outside the log or in its gaps skipped and counted.");
  addMotionOptions(sub, a->motion, "Motion log");
  addRigOption(sub, a->rig, false, "only its yaw (for a log without one) and time_offset (unless --time-offset) are used");
  sub->add_option("--out-dir", a->out_dir, "Output folder (created): motion.csv with its image and t columns")->required();
  addVerbosityOptions(sub, a->quiet, "No summary on standard output");
  addInputOptions(sub, a->input);
  return [a]() { return runImport(*a); };
}

} // namespace yawdepth::cli
