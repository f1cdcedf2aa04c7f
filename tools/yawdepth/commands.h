#pragma once
// Subcommands of the `yawdepth` tool. Each `add*` registers its options on `app` and returns the
// subcommand; `run*` is called when that subcommand was given and returns the exit status.
// Errors are thrown as yawdepth::Error and reported by main() as one line on stderr.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>
#include <opencv2/core.hpp>
#include <yawdepth/bag/import.h>
#include <yawdepth/core/files.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/io/recording.h>

namespace yawdepth::cli {

using Runner = std::function<int()>;

Runner addEstimate(CLI::App &app);
Runner addErrorAnalysis(CLI::App &app);
Runner addSimulate(CLI::App &app);
Runner addMeasure(CLI::App &app);
Runner addTrack(CLI::App &app);
Runner addCalibrateCamera(CLI::App &app);
Runner addCalibrateRig(CLI::App &app);
Runner addImport(CLI::App &app);
Runner addImportBag(CLI::App &app);

/*! \brief The bounds on CSV inputs (motion log, tracks), set by --max-input-mb. */
struct InputOptions {
  double max_input_mb = 256; //!< Largest CSV input read (MiB).
  /*! \brief As InputLimits (lines stay at 1 MiB). */
  InputLimits limits() const
  {
    InputLimits l;
    l.max_bytes = static_cast<std::size_t>(max_input_mb * 1048576.0);
    return l;
  }
};
/*! \brief Add --max-input-mb to `sub`. */
void addInputOptions(CLI::App *sub, InputOptions &options);

/*!
  \brief `--motion` (one file; ViSP pose files: several, or a folder), `--motion-format`, `--images`,
  `--time-offset`, `--max-pose-gap`: every command that reads a motion log takes them
  (yawdepth/io/recording.h: loadMotion()).
*/
struct MotionOptions {
  std::vector<std::string> motion;   //!< --motion
  std::string format = "auto";       //!< --motion-format
  std::string images;                //!< --images
  double time_offset = 0.0;          //!< --time-offset (s)
  double max_pose_gap = 0.2;         //!< --max-pose-gap (s)
  CLI::Option *time_offset_option = nullptr;
  /*! \brief As loadMotion() takes them. */
  MotionInput input() const;
  /*! \brief The files read (for the output clash checks): the motion files and --images' list. */
  std::vector<NamedPath> inputs() const;
  /*! \brief The motion file's name, for messages (the first one). */
  const std::string &name() const { return motion.front(); }
};
/*! \brief Add the motion options to `sub`; `what` describes --motion. */
void addMotionOptions(CLI::App *sub, MotionOptions &options, const std::string &what);
/*!
  \brief loadMotion() for a command; the time alignment's summary (and a warning when fewer than half
  the images got a pose) on stderr unless `quiet`. The rig file gives the fixed yaw and the default
  time offset.
*/
LoadedMotion loadCommandMotion(const std::string &command, const MotionOptions &options, const RigFile *rig,
                               const InputLimits &limits, bool quiet);

/*!
  \brief The bag options of `import-bag` and `measure --bag` (docs/formats.md, "import-bag"): the
  topics, `--tf WORLD:BODY`, the camera frame, the pan joint, the window. `--time-offset` and
  `--max-pose-gap` are the command's own (MotionOptions for measure).
*/
struct BagOptions {
  BagImportOptions import; //!< all but bag, out_dir, time_offset, max_pose_gap
  std::string tf;          //!< --tf WORLD:BODY
  std::vector<double> joint_axis, joint_origin; //!< --joint-axis X,Y,Z, --joint-origin X,Y,Z (empty: the defaults)
  /*! \brief importBag()'s options for `bag` into `out_dir`, --tf split at its colon. */
  BagImportOptions options(const std::string &bag, const std::string &out_dir, double time_offset,
                           double max_pose_gap) const;
};
/*! \brief Add the bag options to `sub` (not the bag itself). */
void addBagOptions(CLI::App *sub, BagOptions &options);
/*! \brief importBag() for a command: its warnings warned; the summary on `summary` unless null. */
BagImportResult importCommandBag(const std::string &command, const BagImportOptions &options, std::ostream *summary);

/*! \brief A warning for stderr, `yawdepth COMMAND: warning: TEXT`, printed when the command succeeds
    (a failure prints its one error line only); never silenced by --quiet. */
void warn(const std::string &command, const std::string &text);
/*! \brief readRigFile() for a command, its rigWarnings() warned. */
RigFile readCommandRig(const std::string &command, const std::string &path);

/*! \brief The --debug-dir pictures of `images`: DIR/NNNN_STEM.png (NNNN the image's position);
    empty when `dir` is empty. Throws yawdepth::Error for an existing path that is not a folder. */
std::vector<std::string> debugFiles(const std::string &dir, const std::vector<std::string> &images);
/*! \brief drawDetection() of `image` written as a PNG to `path` (its folder created), atomically. */
void writeDebugImage(const std::string &path, const cv::Mat &image, const FrameDetection &detection);

/*!
  \brief --quiet and --verbose on `sub` (every command has both; they exclude each other). `quiet` is the
  command's own flag; main() sets verbosity() from them after parsing (progress.h).
  `quiet_help` says what --quiet silences in this command (never warnings or errors).
*/
void addVerbosityOptions(CLI::App *sub, bool &quiet, const std::string &quiet_help);
/*! \brief --config FILE and --print-config on `sub` (every command): main() reads them (command_line.h). */
void addConfigOptions(CLI::App *sub);
/*! \brief The default of --tags in every command that takes it: a single tag, what apriltag:FAMILY:SIZE names. */
inline const char *const kDefaultTags = "1x1";
/*! \brief --tags COLSxROWS (AprilTag grid), the same name, default and help in every command. */
CLI::Option *addTagsOption(CLI::App *sub, std::string &tags);
/*!
  \brief --camera FILE and --camera-name NAME (the camera read from a file), the same names and help in
  every command; `note` adds what the camera is for in this command. Returns --camera.
*/
CLI::Option *addCameraOptions(CLI::App *sub, std::string &camera, std::string &camera_name, bool required,
                              const std::string &note = "");
/*!
  \brief --rig FILE. `required` wherever the rig changes the numbers written; `optional_because` (when
  not required) says in the help what happens without it.
*/
CLI::Option *addRigOption(CLI::App *sub, std::string &rig, bool required, const std::string &optional_because = "");
/*!
  \brief An option renamed: `opt` was created with both names (the new first); using `old_name` warns
  `OLD is spelled NEW now` (main() checks the command line against renamedOptions()).
*/
CLI::Option *renamedFrom(const CLI::App *sub, CLI::Option *opt, const std::string &old_name);
/*! \brief Every renamed option: (command, old name, new name). */
struct RenamedOption {
  std::string command, old_name, new_name;
};
const std::vector<RenamedOption> &renamedOptions();

/*! \brief CLI11 validator: a finite number (rejects nan and inf). */
extern const CLI::Validator Finite;
/*! \brief CLI11 validator: a finite number >= 0. */
extern const CLI::Validator FiniteNonNegative;

} // namespace yawdepth::cli
