#include "csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <yawdepth/error.h>

namespace yawdepth {
namespace io_detail {

NumberStatus parseDouble(std::string_view text, double &value)
{
  if (text.empty())
    return NumberStatus::Empty;
  if (text.size() > 1 && text[0] == '+' && (text[1] == '.' || (text[1] >= '0' && text[1] <= '9')))
    text.remove_prefix(1);
  const char *first = text.data(), *last = text.data() + text.size();
  double v = 0;
  const auto res = std::from_chars(first, last, v, std::chars_format::general);
  if (res.ec != std::errc() && res.ec != std::errc::result_out_of_range)
    return NumberStatus::NotNumber;
  if (res.ptr != last)
    return NumberStatus::NotNumber;
  if (res.ec == std::errc::result_out_of_range)
    return NumberStatus::OutOfRange;
  value = v;
  return std::isfinite(v) ? NumberStatus::Ok : NumberStatus::NotFinite;
}

NumberStatus parseInteger(std::string_view text, long &value)
{
  if (text.empty())
    return NumberStatus::Empty;
  if (text.size() > 1 && text[0] == '+' && text[1] >= '0' && text[1] <= '9')
    text.remove_prefix(1);
  const char *first = text.data(), *last = text.data() + text.size();
  long v = 0;
  const auto res = std::from_chars(first, last, v, 10);
  if (res.ec == std::errc::result_out_of_range) {
    // Only a well-formed integer is "out of range"; anything else is not an integer.
    std::size_t i = (text[0] == '-') ? 1 : 0;
    bool digits = i < text.size();
    for (; i < text.size(); ++i)
      digits = digits && text[i] >= '0' && text[i] <= '9';
    return digits ? NumberStatus::OutOfRange : NumberStatus::NotInteger;
  }
  if (res.ec != std::errc() || res.ptr != last) {
    double d = 0;
    const NumberStatus s = parseDouble(text, d);
    return (s == NumberStatus::NotNumber) ? NumberStatus::NotNumber : NumberStatus::NotInteger;
  }
  value = v;
  return NumberStatus::Ok;
}

std::string formatNumber(double v)
{
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::general, 17);
  return std::string(buf, res.ptr);
}

std::string csvField(const std::string &text)
{
  bool quote = !text.empty() && (text.front() == ' ' || text.front() == '\t' || text.back() == ' ' ||
                                 text.back() == '\t' || text.front() == '"');
  for (char c : text)
    if (c == ',' || c == '"' || c == '\n' || c == '\r')
      quote = true;
  if (!quote)
    return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"')
      out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string excerpt(std::string_view text, std::size_t max_chars)
{
  std::string out;
  static const char hex[] = "0123456789abcdef";
  std::size_t n = 0;
  for (char ch : text) {
    if (n >= max_chars) {
      out += "...";
      break;
    }
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7f) {
      out += ch;
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
    ++n;
  }
  return out;
}

void throwError(const std::string &message)
{
  std::string line = message;
  for (char &c : line)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      c = '?';
  throw Error(line);
}

// ---------------------------------------------------------------------------------------------

static bool isBlank(char c) { return c == ' ' || c == '\t'; }

static std::string_view trim(std::string_view s)
{
  while (!s.empty() && isBlank(s.front()))
    s.remove_prefix(1);
  while (!s.empty() && isBlank(s.back()))
    s.remove_suffix(1);
  return s;
}

CsvReader::CsvReader(const std::string &path, const InputLimits &limits) : path_(path)
{
  input_ = std::make_unique<TextInput>(path, limits);
  std::string_view text;
  bool found = false;
  bool first = true;
  while (nextLine(text)) {
    if (first && text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF")
      text.remove_prefix(3); // UTF-8 byte order mark
    first = false;
    if (!trim(text).empty()) {
      found = true;
      break;
    }
  }
  if (!found)
    failFile("empty file (a header row is required)");
  header_line_ = line_;
  if (text.find('\r') != std::string_view::npos)
    fail("carriage return inside the header: the file has old-Mac (CR-only) line ends; convert them to LF");
  split(text, names_);
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (names_[i].empty())
      continue; // an unnamed column (e.g. a trailing comma) is ignored like any unknown column
    for (std::size_t j = 0; j < i; ++j)
      if (names_[j] == names_[i])
        fail("duplicated column '" + excerpt(names_[i]) + "' in the header");
  }
}

bool CsvReader::nextLine(std::string_view &text)
{
  if (!input_->getline(text_))
    return false;
  line_ = input_->lineNumber();
  text = text_;
  if (!text.empty() && text.back() == '\r')
    text.remove_suffix(1);
  return true;
}

void CsvReader::split(std::string_view text, std::vector<std::string> &out) const
{
  out.clear();
  std::size_t i = 0;
  for (;;) {
    // one field starting at i
    std::size_t start = i;
    while (start < text.size() && isBlank(text[start]))
      ++start;
    if (start < text.size() && text[start] == '"') {
      std::string value;
      std::size_t k = start + 1;
      bool closed = false;
      while (k < text.size()) {
        if (text[k] == '"') {
          if (k + 1 < text.size() && text[k + 1] == '"') {
            value += '"';
            k += 2;
            continue;
          }
          closed = true;
          ++k;
          break;
        }
        value += text[k++];
      }
      if (!closed)
        fail("unterminated quoted field in column " + std::to_string(out.size() + 1));
      while (k < text.size() && isBlank(text[k]))
        ++k;
      if (k < text.size() && text[k] != ',')
        fail("text after a closing quote in column " + std::to_string(out.size() + 1));
      out.push_back(std::move(value));
      if (k >= text.size())
        return;
      i = k + 1;
    } else {
      std::size_t comma = text.find(',', start);
      std::string_view f = text.substr(start, comma == std::string_view::npos ? std::string_view::npos
                                                                                  : comma - start);
      out.emplace_back(trim(f));
      if (comma == std::string_view::npos)
        return;
      i = comma + 1;
    }
  }
}

std::optional<std::size_t> CsvReader::column(const std::string &name) const
{
  for (std::size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name)
      return i;
  return std::nullopt;
}

std::size_t CsvReader::requireColumn(const std::string &name) const
{
  const auto c = column(name);
  if (!c)
    failAt(header_line_, "missing column '" + name + "' in the header");
  return *c;
}

bool CsvReader::next()
{
  std::string_view text;
  while (nextLine(text)) {
    if (trim(text).empty())
      continue;
    split(text, fields_);
    if (fields_.size() != names_.size())
      fail("row has " + std::to_string(fields_.size()) + " field" + (fields_.size() == 1 ? "" : "s") +
           ", the header has " + std::to_string(names_.size()));
    return true;
  }
  fields_.clear();
  return false;
}

double CsvReader::number(std::size_t col) const
{
  double v = 0;
  const std::string &f = fields_[col];
  switch (parseDouble(f, v)) {
  case NumberStatus::Ok:
    return v;
  case NumberStatus::Empty:
    fail("column '" + names_[col] + "' is empty");
  case NumberStatus::NotFinite:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is not a finite number");
  case NumberStatus::OutOfRange:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is out of range");
  default:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is not a number");
  }
}

double CsvReader::numberOrNaN(std::size_t col) const
{
  double v = 0;
  const std::string &f = fields_[col];
  switch (parseDouble(f, v)) {
  case NumberStatus::Ok:
  case NumberStatus::NotFinite:
    return v;
  case NumberStatus::Empty:
    return std::numeric_limits<double>::quiet_NaN();
  case NumberStatus::OutOfRange:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is out of range");
  default:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is not a number");
  }
}

long CsvReader::integer(std::size_t col, bool allow_negative) const
{
  long v = 0;
  const std::string &f = fields_[col];
  switch (parseInteger(f, v)) {
  case NumberStatus::Ok:
    if (v < 0 && !allow_negative)
      fail("column '" + names_[col] + "': " + std::to_string(v) + " is negative");
    return v;
  case NumberStatus::Empty:
    fail("column '" + names_[col] + "' is empty");
  case NumberStatus::OutOfRange:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is out of range");
  case NumberStatus::NotInteger:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is not an integer");
  default:
    fail("column '" + names_[col] + "': '" + excerpt(f) + "' is not a number");
  }
}

void CsvReader::fail(const std::string &reason) const { failAt(line_, reason); }

void CsvReader::failAt(std::size_t line, const std::string &reason) const
{
  throwError(path_ + ":" + std::to_string(line) + ": " + reason);
}

void CsvReader::failFile(const std::string &reason) const { throwError(path_ + ": " + reason); }

} // namespace io_detail
} // namespace yawdepth
