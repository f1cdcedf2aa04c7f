#pragma once
// What main() does with a command line before and after CLI11 parses it: the unknown options
// (reported before any missing one, with a suggestion), the renamed ones, --config's settings,
// --print-config, and the bash completion generated from the same option table.
#include <CLI/CLI.hpp>
#include <set>
#include <string>
#include <vector>

namespace yawdepth::cli {

/*!
  \brief The first option among `args` (the words after the command) that `sub` does not have, as
  `unknown option '--x' (did you mean --y?)` (the suggestion only when one of the command's own
  options is close); empty when every option is known. Numbers (-0.5) are values, not options;
  nothing after `--` is looked at.
*/
std::string unknownOption(const CLI::App &sub, const std::vector<std::string> &args);

/*! \brief A warning (warn()) for each renamed option's old name used in `args`. */
void warnRenamedOptions(const CLI::App &sub, const std::vector<std::string> &args);

/*! \brief A settings file that cannot be used: the message names the file and the key or line. */
struct ConfigFileError {
  std::string message;
};

/*! \brief What applyConfigFile() took from the file. */
struct ConfigApplied {
  std::string file;               //!< the --config file (empty: none given)
  std::set<std::string> options;  //!< the options set from it (--name)
};

/*!
  \brief --config FILE among `args`: the file's settings for `sub` (top-level keys and its
  [COMMAND] section) appended to `args` for every option the command line does not give (the
  command line overrides the file). Top-level keys of another command's options are skipped, so one
  file serves them all; a key no command has, a key of [COMMAND] that `sub` lacks, a section that is
  no command, or an unreadable file throws ConfigFileError. `app` is the whole command line.
*/
ConfigApplied applyConfigFile(CLI::App &app, const CLI::App &sub, std::vector<std::string> &args);

/*! \brief --print-config: `sub`'s effective settings as a --config file (TOML). */
std::string effectiveConfig(const CLI::App &sub);

/*! \brief The bash completion script of `app`'s commands and options (`yawdepth --completion bash`). */
std::string bashCompletion(CLI::App &app);

} // namespace yawdepth::cli
