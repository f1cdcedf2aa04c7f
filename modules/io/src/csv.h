#pragma once
/*!
  \file csv.h
  \brief Private helpers of the io module: strict CSV reading, number parsing and formatting,
  one-line error messages. Not installed.
*/
#include <cstddef>
#include <functional>
#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <memory>
#include <vector>
#include <yawdepth/core/files.h>

namespace yawdepth {
namespace io_detail {

/*! \brief Outcome of parsing a number from a text field. */
enum class NumberStatus { Ok, Empty, NotNumber, NotFinite, NotInteger, OutOfRange };

/*!
  \brief Parse a double from the whole of `text` (locale-independent; one optional leading '+').
  NaN and infinities parse but are reported as NotFinite (the value is still stored).
*/
NumberStatus parseDouble(std::string_view text, double &value);
/*! \brief Parse an integer (optional sign, decimal digits only) from the whole of `text`. */
NumberStatus parseInteger(std::string_view text, long &value);

/*! \brief `v` with 17 significant digits, as printf's "%.17g" in the C locale. */
std::string formatNumber(double v);

/*! \brief A field for a CSV file: quoted (RFC 4180) when it holds a comma, quote, or edge spaces. */
std::string csvField(const std::string &text);

/*!
  \brief A short printable rendering of user text for an error message: control and non-ASCII
  bytes escaped as \\xNN, long text cut.
*/
std::string excerpt(std::string_view text, std::size_t max_chars = 40);

/*! \brief Throw yawdepth::Error with `message` forced onto one line (control characters replaced). */
[[noreturn]] void throwError(const std::string &message);

/*!
  \brief A strict CSV reader, streaming within InputLimits (core/files.h: a regular file or a pipe
  only): header row required (after an optional UTF-8 BOM), CRLF or LF line endings, fields trimmed
  of spaces and tabs, blank lines skipped, every data row with exactly as many fields as the header.
*/
class CsvReader {
public:
  /*! \brief Open and read `path` and its header; throws on a missing, unreadable or empty file,
      or a duplicated column name. */
  explicit CsvReader(const std::string &path, const InputLimits &limits = InputLimits());

  /*! \brief The file's path, as given. */
  const std::string &path() const { return path_; }
  /*! \brief Line number of the header row (1-based). */
  std::size_t headerLine() const { return header_line_; }
  /*! \brief The header's column names, in file order. */
  const std::vector<std::string> &names() const { return names_; }
  /*! \brief Index of column `name`, if the header has it. */
  std::optional<std::size_t> column(const std::string &name) const;
  /*! \brief Index of column `name`; throws "<file>:<header line>: missing column 'name'". */
  std::size_t requireColumn(const std::string &name) const;

  /*! \brief Advance to the next data row; false at the end of the file. */
  bool next();
  /*! \brief Line number of the current row (1-based). */
  std::size_t line() const { return line_; }
  /*! \brief Raw (trimmed, unquoted) text of field `col` in the current row. */
  const std::string &field(std::size_t col) const { return fields_[col]; }
  /*! \brief Field `col` as a finite double; throws otherwise. */
  double number(std::size_t col) const;
  /*! \brief Field `col` as a double, empty meaning NaN; NaN and infinities accepted. */
  double numberOrNaN(std::size_t col) const;
  /*! \brief Field `col` as an integer; negative values rejected unless `allow_negative`. */
  long integer(std::size_t col, bool allow_negative = false) const;

  /*! \brief Throw "<file>:<current line>: reason". */
  [[noreturn]] void fail(const std::string &reason) const;
  /*! \brief Throw "<file>:<line>: reason". */
  [[noreturn]] void failAt(std::size_t line, const std::string &reason) const;
  /*! \brief Throw "<file>: reason". */
  [[noreturn]] void failFile(const std::string &reason) const;

private:
  bool nextLine(std::string_view &text);
  void split(std::string_view text, std::vector<std::string> &out) const;

  std::string path_;
  std::unique_ptr<TextInput> input_;
  std::string text_; // the current line
  std::size_t line_ = 0;
  std::size_t header_line_ = 0;
  std::vector<std::string> names_;
  std::vector<std::string> fields_;
};

/*! \brief How far from 1 a quaternion's norm may be (rounding of printed digits) before it is refused. */
constexpr double kQuaternionNormTolerance = 1e-3;

/*!
  \brief The rotation vector (theta-u) of a Hamilton quaternion (qx, qy, qz, qw), normalised; calls
  `fail` (which throws) for a norm of 0 or one more than kQuaternionNormTolerance from 1.
*/
Eigen::Vector3d thetaUOfQuaternion(double qx, double qy, double qz, double qw,
                                   const std::function<void(const std::string &)> &fail);
/*! \brief Calls `fail` (which throws) unless `t` is after `previous` (when there is one). */
void checkTimeIncreasing(double t, std::optional<double> previous,
                         const std::function<void(const std::string &)> &fail);

} // namespace io_detail
} // namespace yawdepth
