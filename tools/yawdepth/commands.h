#pragma once
// Subcommands of the `yawdepth` tool. Each `add*` registers its options on `app` and returns the
// subcommand; `run*` is called when that subcommand was given and returns the exit status.
// Errors are thrown as yawdepth::Error and reported by main() as one line on stderr.
#include <CLI/CLI.hpp>
#include <functional>
#include <yawdepth/core/files.h>

namespace yawdepth::cli {

using Runner = std::function<int()>;

Runner addEstimate(CLI::App &app);
Runner addErrorAnalysis(CLI::App &app);
Runner addSimulate(CLI::App &app);
Runner addMeasure(CLI::App &app);
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

/*! \brief CLI11 validator: a finite number (rejects nan and inf). */
extern const CLI::Validator Finite;
/*! \brief CLI11 validator: a finite number >= 0. */
extern const CLI::Validator FiniteNonNegative;

} // namespace yawdepth::cli
