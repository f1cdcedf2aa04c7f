#pragma once
/*!
  \file error.h
  \brief The one exception type yawdepth throws.
*/
#include <stdexcept>
#include <string>

namespace yawdepth {

/*!
  \brief Error raised for bad input (unreadable or malformed files, invalid parameters).

  The message is one line, starts with the offending file or parameter when there is one,
  and is meant to be shown to the user as it is. The library never prints and never exits.
*/
class Error : public std::runtime_error {
public:
  /*! \param what The one-line message. */
  explicit Error(const std::string &what) : std::runtime_error(what) {}
};

} // namespace yawdepth
