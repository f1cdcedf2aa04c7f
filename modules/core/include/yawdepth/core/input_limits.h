#pragma once
/*!
  \file input_limits.h
  \brief Bounds on a text input: the readers of yawdepth::io (and the command line) read a file as a
  stream, a line at a time, and stop with a one-line error at a line or a file larger than these.
*/
#include <cstddef>

namespace yawdepth {

/*! \brief Bounds on a text input (bytes). */
struct InputLimits {
  std::size_t max_bytes = std::size_t(256) << 20;     //!< Whole file: 256 MiB by default.
  std::size_t max_line_bytes = std::size_t(1) << 20; //!< One line: 1 MiB.
};

} // namespace yawdepth
