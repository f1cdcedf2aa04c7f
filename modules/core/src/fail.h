#pragma once
// Private to the core module: throw yawdepth::Error with the message forced onto one line
// (control characters of user text, such as a path, replaced by '?').
#include <string>
#include <yawdepth/error.h>

namespace yawdepth::core_detail {

[[noreturn]] inline void fail(const std::string &message)
{
  std::string line = message;
  for (char &c : line)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      c = '?';
  throw Error(line);
}

} // namespace yawdepth::core_detail
