#pragma once
// Progress and verbosity of the `yawdepth` command line: one owner for what goes to stderr besides
// results, warnings and errors.
#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <yawdepth/pipeline/pipeline.h>

namespace yawdepth::cli {

/*! \brief The process's verbosity, set once by main() from the command's --quiet and --verbose. */
struct Verbosity {
  bool quiet = false;   //!< --quiet: no summaries, no progress (warnings and errors stay)
  bool verbose = false; //!< --verbose: each stage's time on stderr as well
};
/*! \brief The verbosity of this run (one command per process). */
Verbosity &verbosity();

/*!
  \brief With --verbose, `yawdepth COMMAND: STAGE (S s)` on stderr: the seconds since the previous
  stage (or the start). Nothing otherwise.
*/
void stage(const std::string &command, const std::string &text);

/*!
  \brief A single updating progress line on stderr, only when stderr is a terminal and not --quiet:
  a caller capturing stderr gets one line per problem, never a progress bar. Shown from 1 s into the
  work (a short run prints nothing), rewritten at most 5 times a second, ended by a newline when the
  object goes. Refine's solver stages use the same line (refineCallback()).
*/
class ProgressLine {
public:
  ProgressLine();
  ~ProgressLine();
  ProgressLine(const ProgressLine &) = delete;
  ProgressLine &operator=(const ProgressLine &) = delete;

  /*! \brief `WHAT: DONE/TOTAL UNIT` (e.g. `simulate: 12/40 images`; `WHAT: DONE UNIT` when TOTAL is 0,
      unknown), rate-limited; the last one (DONE == TOTAL) always once a line is shown. */
  void count(const std::string &what, std::size_t done, std::size_t total, const std::string &unit);
  /*! \brief Ends the line (a newline if one was shown) before other messages; nothing more is shown. */
  void finish();
  /*! \brief Refine's stages as they come (from 2 s into the solve; a new stage at once). Empty when inactive. */
  std::function<void(const RefineProgress &)> refineCallback();

private:
  void show(const std::string &text);
  bool active_;
  bool printed_ = false;
  std::chrono::steady_clock::time_point start_, last_;
  int refine_stage_ = -1;
};

} // namespace yawdepth::cli
