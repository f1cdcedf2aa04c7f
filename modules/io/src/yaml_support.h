#pragma once
/*!
  \file yaml_support.h
  \brief Private helpers of the io module for YAML files (rig files, ViSP pose files): where a node
  is, and a node as a finite number, in one-line messages. Not installed.
*/
#include "csv.h"

#include <string>
#include <yaml-cpp/yaml.h>

namespace yawdepth {
namespace io_detail {

/*! \brief "path:line: " for a node's mark, or "path: " when it has none. */
inline std::string where(const std::string &path, const YAML::Mark &mark)
{
  if (mark.is_null() || mark.line < 0)
    return path + ": ";
  return path + ":" + std::to_string(mark.line + 1) + ": ";
}

/*! \brief A scalar node as a finite number; throws naming the file, line and `what` otherwise. */
inline double finiteNumber(const std::string &path, const YAML::Node &node, const std::string &what)
{
  if (!node.IsScalar())
    throwError(where(path, node.Mark()) + what + " must be a number");
  double v = 0;
  const std::string &text = node.Scalar();
  switch (parseDouble(text, v)) {
  case NumberStatus::Ok:
    return v;
  case NumberStatus::Empty:
    throwError(where(path, node.Mark()) + what + " is empty");
  case NumberStatus::NotFinite:
    throwError(where(path, node.Mark()) + what + ": '" + excerpt(text) + "' is not a finite number");
  case NumberStatus::OutOfRange:
    throwError(where(path, node.Mark()) + what + ": '" + excerpt(text) + "' is out of range");
  default:
    throwError(where(path, node.Mark()) + what + ": '" + excerpt(text) + "' is not a number");
  }
}

} // namespace io_detail
} // namespace yawdepth
