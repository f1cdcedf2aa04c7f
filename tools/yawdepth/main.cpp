// The `yawdepth` command line: subcommands wiring the library's modules.
#include <opencv2/imgcodecs.hpp>
#include <filesystem>
#include "command_line.h"
#include "commands.h"
#include "progress.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <vector>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <yawdepth/bag/bag.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth::cli {

static std::string finiteCheck(const std::string &text, bool non_negative)
{
  try {
    std::size_t pos = 0;
    const double v = std::stod(text, &pos);
    if (pos != text.size())
      return "'" + text + "' is not a number";
    if (!std::isfinite(v))
      return "'" + text + "' is not a finite number";
    if (non_negative && v < 0)
      return "'" + text + "' must not be negative";
  } catch (const std::exception &) {
    return "'" + text + "' is not a number";
  }
  return {};
}

void addInputOptions(CLI::App *sub, InputOptions &options)
{
  sub->add_option("--max-input-mb", options.max_input_mb,
                  "Largest motion log or tracks CSV read (MiB; lines at most 1 MiB). Inputs are read as streams: a "
                  "regular file or a pipe (a FIFO with no writer waits for one, as cat does), not a device")
      ->check(CLI::Range(1.0, 1048576.0))
      ->capture_default_str();
}

void addMotionOptions(CLI::App *sub, MotionOptions &options, const std::string &what)
{
  sub->add_option("--motion", options.motion,
                  what + ". Any of: a yawdepth CSV (frame-based, or timestamped with a column t), a TUM trajectory "
                         "(timestamp tx ty tz qx qy qz qw), an EuRoC CSV, or ViSP vpPoseVector YAML files (several, "
                         "or a folder; paired with --images in name order)")
      ->required();
  sub->add_option("--motion-format", options.format, "The motion file's format (auto: by its content)")
      ->check(CLI::IsMember({"auto", "yawdepth", "tum", "euroc", "visp"}))
      ->capture_default_str();
  sub->add_option("--images", options.images,
                  "The images of a timestamped motion log, with their times: a folder named by timestamps "
                  "(1305031102.175304.png in s, 1403636579763555584.png in ns), TUM's rgb.txt or EuRoC's data.csv; "
                  "with ViSP pose files, a folder or list paired in order");
  options.time_offset_option =
      sub->add_option("--time-offset", options.time_offset,
                      "The image at camera time t was taken at motion time t + S (s; default: the rig file's "
                      "time_offset, else 0)")
          ->check(Finite);
  sub->add_option("--max-pose-gap", options.max_pose_gap,
                  "An image between two poses further apart than this is skipped, never extrapolated (s)")
      ->check(CLI::PositiveNumber & Finite)
      ->capture_default_str();
}

MotionInput MotionOptions::input() const
{
  MotionInput in;
  in.motion = motion;
  in.format = motionFormatFromString(format);
  in.images = images;
  if (time_offset_option && time_offset_option->count() > 0)
    in.time_offset = time_offset;
  in.max_pose_gap = max_pose_gap;
  return in;
}

std::vector<NamedPath> MotionOptions::inputs() const
{
  std::vector<NamedPath> out;
  for (const std::string &m : motion)
    out.push_back({"--motion", m});
  if (!images.empty())
    out.push_back({"--images", images});
  return out;
}

LoadedMotion loadCommandMotion(const std::string &command, const MotionOptions &options, const RigFile *rig,
                               const InputLimits &limits, bool quiet)
{
  LoadedMotion m = loadMotion(options.input(), rig ? rig->yaw : std::nullopt,
                              rig ? rig->time_offset : std::nullopt, limits);
  stage(command, options.name() + " read: " + std::to_string(m.log.samples.size()) + " rows");
  for (const std::string &w : motionWarnings(m.log, options.name()))
    warn(command, w);
  if (m.alignment && !quiet) {
    const TimeAlignment &a = *m.alignment;
    std::cerr << "yawdepth " << command << ": " << options.name() << " (" << toString(m.format) << ") with "
              << options.images << ": " << a.summary() << "; time offset " << m.time_offset << " s\n";
    if (2 * a.matched < a.images)
      std::cerr << "yawdepth " << command << ": warning: only " << a.matched << " of " << a.images
                << " images have a pose: check the clocks and --time-offset\n";
  }
  return m;
}

RigFile readCommandRig(const std::string &command, const std::string &path)
{
  RigFile rig = readRigFile(path);
  for (const std::string &w : rigWarnings(rig, path))
    warn(command, w);
  return rig;
}

static std::string oneLine(std::string what);

namespace {
std::vector<std::string> &pendingWarnings()
{
  static std::vector<std::string> pending;
  return pending;
}
} // namespace

void warn(const std::string &command, const std::string &text)
{
  pendingWarnings().push_back("yawdepth " + command + ": warning: " + oneLine(text));
}

std::vector<std::string> debugFiles(const std::string &dir, const std::vector<std::string> &images)
{
  std::vector<std::string> out;
  if (dir.empty())
    return out;
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    throw Error("--debug-dir " + dir + ": exists and is not a folder");
  for (std::size_t i = 0; i < images.size(); ++i) {
    char num[32];
    std::snprintf(num, sizeof num, "%04zu_", i);
    std::string stem = std::filesystem::path(images[i]).stem().string();
    if (stem.empty() || stem == "." || stem == "..")
      stem = "image";
    out.push_back((std::filesystem::path(dir) / (num + stem + ".png")).string());
  }
  return out;
}

void writeDebugImage(const std::string &path, const cv::Mat &image, const FrameDetection &detection)
{
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec)
    throw Error("--debug-dir: cannot create " + std::filesystem::path(path).parent_path().string() + ": " + ec.message());
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", drawDetection(image, detection), png))
    throw Error(path + ": cannot encode the picture");
  writeFileAtomically(path, std::string(png.begin(), png.end()));
}

const CLI::Validator Finite([](std::string &s) { return finiteCheck(s, false); }, "FINITE");
const CLI::Validator FiniteNonNegative([](std::string &s) { return finiteCheck(s, true); }, "NON-NEGATIVE");

/* Messages from other libraries can span lines; the contract is one line on stderr. */
static std::string oneLine(std::string what)
{
  for (char &c : what)
    if (c == '\n' || c == '\r' || c == '\t')
      c = ' ';
  while (!what.empty() && what.back() == ' ')
    what.pop_back();
  return what;
}

using Command = std::pair<CLI::App *, Runner>;

/* Every subcommand registered on `app`, with its runner. */
static std::vector<Command> addCommands(CLI::App &app)
{
  std::vector<Command> commands;
  auto add = [&](Runner (*adder)(CLI::App &)) {
    const std::size_t before = app.get_subcommands({}).size();
    Runner r = adder(app);
    CLI::App *sub = app.get_subcommands({}).at(before);
    addConfigOptions(sub); // every command reads a settings file
    commands.emplace_back(sub, std::move(r));
  };
  add(addEstimate);
  add(addMeasure);
  add(addTrack);
  add(addErrorAnalysis);
  add(addSimulate);
  add(addCalibrateCamera);
  add(addCalibrateRig);
  add(addImport);
  add(addImportBag);
  return commands;
}

/* The commands' names, for messages: "estimate, measure, ...". */
static std::string commandNames(const std::vector<Command> &commands)
{
  std::string names;
  for (const auto &c : commands)
    names += (names.empty() ? "" : ", ") + c.first->get_name();
  return names;
}

/* An unknown command named (instead of CLI11's generic "A subcommand is required"): false, after the
   message on stderr, when `word` (the first argument, not an option) is no command's name. */
static bool knownCommand(const std::vector<Command> &commands, const char *word)
{
  for (const auto &c : commands)
    if (c.first->get_name() == word)
      return true;
  std::cerr << "yawdepth: error: unknown command '" << oneLine(word) << "' (expected one of "
            << commandNames(commands) << ") (see yawdepth --help)\n";
  return false;
}

/* Run the parsed subcommand `sub`: its status, or 1 with one line on stderr for an error (standard
   output is an output too: a full disk or /dev/full is an error, not a success). */
static int runCommand(const CLI::App &sub, const Runner &run)
{
  try {
    const int status = run();
    stage(sub.get_name(), "done");
    errno = 0;
    std::cout.flush();
    if (!std::cout || std::fflush(stdout) != 0 || std::ferror(stdout)) {
      const int err = errno;
      std::cerr << "yawdepth " << sub.get_name() << ": error: cannot write to standard output"
                << (err ? std::string(" (") + std::strerror(err) + ")" : std::string()) << "\n";
      return 1;
    }
    if (status == 0)
      for (const std::string &w : pendingWarnings())
        std::cerr << w << "\n";
    return status;
  } catch (const yawdepth::Error &e) {
    std::cerr << "yawdepth " << sub.get_name() << ": error: " << oneLine(e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc &) {
    std::cerr << "yawdepth " << sub.get_name() << ": error: out of memory\n";
    return 1;
  } catch (const std::exception &e) {
    std::cerr << "yawdepth " << sub.get_name() << ": error: " << oneLine(e.what()) << "\n";
    return 1;
  }
}

/* The usage error's one line (status 2): `yawdepth CMD: error: REASON (see yawdepth CMD --help)`. */
static int usageError(const std::string &command, const std::string &reason)
{
  const std::string who = command.empty() ? "yawdepth" : "yawdepth " + command;
  std::cerr << who << ": error: " << oneLine(reason) << " (see " << who << " --help)\n";
  return 2;
}

/* The command's --quiet and --verbose into verbosity() (one command per process). */
static void setVerbosity(const CLI::App &sub)
{
  const CLI::Option *quiet = sub.get_option_no_throw("--quiet"), *verbose = sub.get_option_no_throw("--verbose");
  verbosity().quiet = quiet != nullptr && quiet->count() > 0;
  verbosity().verbose = verbose != nullptr && verbose->count() > 0;
}

/* Before CLI11 parses `args` (the words after the command `sub`): an unknown option is reported
   before any missing one; --config's settings are added; renamed options warned about. Returns the
   usage error's status, or 0 to go on. */
static int prepareArguments(CLI::App &app, const CLI::App &sub, std::vector<std::string> &args,
                            ConfigApplied &config)
{
  const std::string unknown = unknownOption(sub, args);
  if (!unknown.empty())
    return usageError(sub.get_name(), unknown);
  try {
    config = applyConfigFile(app, sub, args);
  } catch (const ConfigFileError &e) {
    return usageError(sub.get_name(), e.message);
  }
  warnRenamedOptions(sub, args);
  return 0;
}

/* A parse error's reason, naming the settings file when the option it is about came from there. */
static std::string parseReason(const CLI::ParseError &e, const ConfigApplied &config)
{
  std::string reason = e.what();
  // The option named as a word: --out is not --outliers, --camera not --camera-name.
  auto named = [&](const std::string &name) {
    for (std::size_t at = reason.find(name); at != std::string::npos; at = reason.find(name, at + 1)) {
      const std::size_t end = at + name.size();
      if (end == reason.size() || !(std::isalnum(static_cast<unsigned char>(reason[end])) || reason[end] == '-'))
        return true;
    }
    return false;
  };
  for (const std::string &name : config.options)
    if (named(name))
      return reason + " (set in " + config.file + ")";
  return reason;
}

} // namespace yawdepth::cli

int main(int argc, char **argv)
{
  using namespace yawdepth::cli;
  CLI::App app{"yawdepth: 3D points from the motion of a yawing monocular camera (depth from "
               "odometry and image motion, on ViSP).",
               "yawdepth"};
  app.require_subcommand(1);
  std::string version = "yawdepth 0.1.0\nbag formats read:";
  const std::vector<yawdepth::BagFormat> formats = yawdepth::readableBagFormats();
  for (yawdepth::BagFormat f : formats)
    version += std::string(" ") + yawdepth::toString(f);
  if (formats.empty())
    version += " none";
  app.set_version_flag("--version", version);
  const std::vector<Command> commands = addCommands(app);
  if (argc == 3 && std::string(argv[1]) == "--completion" && std::string(argv[2]) == "bash") {
    std::cout << bashCompletion(app); // hidden: the build writes the installed completion with it
    return 0;
  }
  if (argc == 1)
    return usageError("", "no command given (one of " + commandNames(commands) + ")");
  if (argv[1][0] != '-' && !knownCommand(commands, argv[1]))
    return 2;

  const CLI::App *chosen = nullptr;
  for (const auto &c : commands)
    if (argc > 1 && c.first->get_name() == argv[1])
      chosen = c.first;
  std::vector<std::string> args(argv + 1, argv + argc);
  ConfigApplied config;
  if (chosen != nullptr) {
    std::vector<std::string> rest(args.begin() + 1, args.end());
    if (const int status = prepareArguments(app, *chosen, rest, config))
      return status;
    rest.insert(rest.begin(), args.front());
    args = std::move(rest);
  } else if (const std::string unknown = unknownOption(app, args); !unknown.empty())
    return usageError("", unknown);
  const std::string command = chosen ? chosen->get_name() : std::string();
  try {
    std::reverse(args.begin(), args.end()); // CLI11 takes the words last first
    app.parse(args);
  } catch (const CLI::CallForHelp &e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp &e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion &e) {
    return app.exit(e);
  } catch (const CLI::ParseError &e) {
    return usageError(command, parseReason(e, config));
  }

  // An interrupted run leaves no temporary file behind (the outputs are written atomically).
  yawdepth::removeTemporaryFilesOnSignals();
  for (const auto &[sub, run] : commands) {
    if (!sub->parsed())
      continue;
    if (sub->count("--print-config") > 0) {
      try {
        std::cout << effectiveConfig(*sub);
      } catch (const ConfigFileError &e) {
        return usageError(sub->get_name(), e.message);
      }
      return 0;
    }
    setVerbosity(*sub);
    return runCommand(*sub, run);
  }
  return 2;
}
