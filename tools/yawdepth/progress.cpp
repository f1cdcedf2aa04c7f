#include "progress.h"

#include <cstdio>
#include <iostream>
#include <unistd.h>

namespace yawdepth::cli {

namespace {
using Clock = std::chrono::steady_clock;
const Clock::time_point g_start = Clock::now(); // the process's start, for --verbose's times
double secondsBetween(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }
} // namespace

Verbosity &verbosity()
{
  static Verbosity v;
  return v;
}

void stage(const std::string &command, const std::string &text)
{
  const Clock::time_point start = g_start;
  static Clock::time_point previous = start;
  const Clock::time_point now = Clock::now();
  if (verbosity().verbose && !verbosity().quiet) {
    char seconds[64];
    std::snprintf(seconds, sizeof seconds, "%.3f s; %.3f s in all", secondsBetween(previous, now),
                  secondsBetween(start, now));
    std::cerr << "yawdepth " << command << ": " << text << " (" << seconds << ")\n";
  }
  previous = now;
}

ProgressLine::ProgressLine()
    : active_(!verbosity().quiet && isatty(STDERR_FILENO)), start_(Clock::now()), last_(start_)
{
}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::finish()
{
  if (printed_)
    std::fputc('\n', stderr);
  printed_ = false;
  active_ = false;
}

void ProgressLine::show(const std::string &text)
{
  // The padding clears what a longer previous line left.
  std::fprintf(stderr, "\r%s%10s", text.c_str(), "");
  std::fflush(stderr);
  printed_ = true;
  last_ = Clock::now();
}

void ProgressLine::count(const std::string &what, std::size_t done, std::size_t total, const std::string &unit)
{
  if (!active_)
    return;
  const Clock::time_point now = Clock::now();
  const bool last = done == total && printed_; // the final count, once a line is up
  if (!last && (secondsBetween(start_, now) < 1.0 || secondsBetween(last_, now) < 0.2))
    return;
  show(what + ": " + std::to_string(done) + (total > 0 ? "/" + std::to_string(total) : std::string()) + " " + unit);
}

std::function<void(const RefineProgress &)> ProgressLine::refineCallback()
{
  if (!active_)
    return {};
  return [this](const RefineProgress &p) {
    const int stage_index = static_cast<int>(p.stage);
    // A solve under 2 s prints nothing; a new stage is shown at once, the same one at most once a second.
    if (p.seconds < 2.0 || (stage_index == refine_stage_ && secondsBetween(last_, Clock::now()) < 1.0))
      return;
    refine_stage_ = stage_index;
    const char *name = p.stage == RefineProgress::Stage::RobustSolve  ? "robust solve"
                       : p.stage == RefineProgress::Stage::FinalSolve ? "final solve"
                                                                      : "covariances";
    char text[160];
    if (p.stage == RefineProgress::Stage::Covariance)
      std::snprintf(text, sizeof text, "refine: %d points x %d frames, %s ... (%.0f s)", p.points, p.frames, name,
                    p.seconds);
    else
      std::snprintf(text, sizeof text, "refine: %d points x %d frames, %s, iteration %d, cost %.6g (%.0f s)",
                    p.points, p.frames, name, p.iteration, p.cost, p.seconds);
    show(text);
  };
}

} // namespace yawdepth::cli
