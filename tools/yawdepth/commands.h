#pragma once
// Subcommands of the `yawdepth` tool. Each `add*` registers its options on `app` and returns the
// subcommand; `run*` is called when that subcommand was given and returns the exit status.
// Errors are thrown as yawdepth::Error and reported by main() as one line on stderr.
#include <CLI/CLI.hpp>
#include <functional>

namespace yawdepth::cli {

using Runner = std::function<int()>;

Runner addEstimate(CLI::App &app);
Runner addErrorAnalysis(CLI::App &app);
Runner addSimulate(CLI::App &app);
Runner addMeasure(CLI::App &app);
Runner addCalibrateCamera(CLI::App &app);
Runner addCalibrateRig(CLI::App &app);

/*! \brief CLI11 validator: a finite number (rejects nan and inf). */
extern const CLI::Validator Finite;
/*! \brief CLI11 validator: a finite number >= 0. */
extern const CLI::Validator FiniteNonNegative;

} // namespace yawdepth::cli
