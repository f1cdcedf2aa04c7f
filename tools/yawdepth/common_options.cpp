// The options every command registers the same way (one helper each): --quiet/--verbose,
// --config/--print-config, --tags, --rig, and the record of renamed options.
#include "commands.h"

namespace yawdepth::cli {

namespace {
std::vector<RenamedOption> &renamedRegistry()
{
  static std::vector<RenamedOption> renamed;
  return renamed;
}
} // namespace

void addVerbosityOptions(CLI::App *sub, bool &quiet, const std::string &quiet_help)
{
  CLI::Option *q = sub->add_flag("--quiet", quiet, quiet_help + " (warnings and errors are still printed)");
  sub->add_flag("--verbose", "Also each stage's time on stderr (reading, detection, estimation, writing)")
      ->excludes(q);
}

void addConfigOptions(CLI::App *sub)
{
  const std::string help = "Read settings from a TOML or INI FILE: KEY = VALUE lines (an option's long name "
                           "without the dashes), at the top (any command) or in a [" +
                           sub->get_name() + "] section; the command line overrides the file";
  sub->add_option("--config", help)
      ->type_name("FILE")
      ->configurable(false);
  sub->add_flag("--print-config", "Write the effective settings (the file's and the command line's) as a "
                                  "--config file to standard output and exit without running")
      ->configurable(false);
}

CLI::Option *addTagsOption(CLI::App *sub, std::string &tags)
{
  tags = kDefaultTags;
  return sub->add_option("--tags", tags,
                         "AprilTag grid: COLSxROWS tags (default 1x1: one tag, as apriltag:FAMILY:SIZE names it; give "
                         "the grid of a printed multi-tag board)")
      ->type_name("COLSxROWS");
}

CLI::Option *addCameraOptions(CLI::App *sub, std::string &camera, std::string &camera_name, bool required,
                              const std::string &note)
{
  CLI::Option *o = sub->add_option("--camera", camera,
                                   "Camera file: ViSP XML or OpenCV YAML/XML (docs/formats.md, \"Camera file\")" +
                                       (note.empty() ? std::string() : "; " + note))
                       ->type_name("FILE");
  if (required)
    o->required();
  sub->add_option("--camera-name", camera_name,
                  "Camera name in a ViSP XML file (optional when it holds one), or cam0, cam1, ... in a Kalibr "
                  "camchain (default cam0)");
  return o;
}

CLI::Option *addRigOption(CLI::App *sub, std::string &rig, bool required, const std::string &optional_because)
{
  std::string help = "Rig file (YAML): camera_offset (or camera_pose), yaw_offset, yaw_axis, time_offset";
  if (!required)
    help += "; optional: " + optional_because;
  CLI::Option *o = sub->add_option("--rig", rig, help)->type_name("FILE");
  if (required)
    o->required();
  return o;
}

CLI::Option *renamedFrom(const CLI::App *sub, CLI::Option *opt, const std::string &old_name)
{
  renamedRegistry().push_back({sub->get_name(), old_name, "--" + opt->get_lnames().front()});
  return opt;
}

const std::vector<RenamedOption> &renamedOptions() { return renamedRegistry(); }

} // namespace yawdepth::cli
