#pragma once
// Subcommands of the `yawdepth` tool. Each `add*` registers its options on `app` and returns the
// subcommand; `run*` is called when that subcommand was given and returns the exit status.
// Errors are thrown as yawdepth::Error and reported by main() as one line on stderr.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>
#include <opencv2/core.hpp>
#include <yawdepth/core/files.h>
#include <yawdepth/features/detector.h>

namespace yawdepth::cli {

using Runner = std::function<int()>;

Runner addEstimate(CLI::App &app);
Runner addErrorAnalysis(CLI::App &app);
Runner addSimulate(CLI::App &app);
Runner addMeasure(CLI::App &app);
Runner addTrack(CLI::App &app);
Runner addCalibrateCamera(CLI::App &app);
Runner addCalibrateRig(CLI::App &app);

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

/*! \brief The --debug-dir pictures of `images`: DIR/NNNN_STEM.png (NNNN the image's position);
    empty when `dir` is empty. Throws yawdepth::Error for an existing path that is not a folder. */
std::vector<std::string> debugFiles(const std::string &dir, const std::vector<std::string> &images);
/*! \brief drawDetection() of `image` written as a PNG to `path` (its folder created), atomically. */
void writeDebugImage(const std::string &path, const cv::Mat &image, const FrameDetection &detection);

/*! \brief CLI11 validator: a finite number (rejects nan and inf). */
extern const CLI::Validator Finite;
/*! \brief CLI11 validator: a finite number >= 0. */
extern const CLI::Validator FiniteNonNegative;

} // namespace yawdepth::cli
