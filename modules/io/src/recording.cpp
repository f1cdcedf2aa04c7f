/*!
  \file recording.cpp
  \brief Recordings as users have them: TUM, EuRoC and ViSP pose files, timestamped images, and the
  time alignment of the two (yawdepth/io/recording.h).
*/
#include "csv.h"
#include "yaml_support.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sys/stat.h>
#include <yaml-cpp/yaml.h>
#include <yawdepth/error.h>
#include <yawdepth/io/recording.h>

namespace yawdepth {

namespace fs = std::filesystem;
using io_detail::CsvReader;
using io_detail::excerpt;
using io_detail::formatNumber;
using io_detail::NumberStatus;
using io_detail::parseDouble;
using io_detail::parseInteger;
using io_detail::throwError;
using io_detail::where;
using io_detail::finiteNumber;

namespace recording_detail {

/* A vpPoseVector file is a few lines. */
constexpr std::size_t kMaxPoseFileBytes = 1 << 20;

std::string trimmed(const std::string &s)
{
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos)
    return std::string();
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string lower(std::string s)
{
  for (char &c : s)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/* Whitespace-separated fields of a line. */
std::vector<std::string> splitBlanks(const std::string &line)
{
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t'))
      ++i;
    if (i >= line.size())
      break;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t')
      ++j;
    out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

/* A CSV column's name without a leading '#' and a trailing unit in brackets: "#timestamp [ns]" -> "timestamp". */
std::string baseName(const std::string &name)
{
  std::string s = name;
  while (!s.empty() && (s.front() == '#' || s.front() == ' '))
    s.erase(0, 1);
  const auto b = s.find('[');
  if (b != std::string::npos)
    s.erase(b);
  return trimmed(s);
}

/* Integer nanoseconds to seconds, split so that the fractional part keeps its digits. */
double nanosecondsToSeconds(long ns)
{
  const long whole = ns / 1000000000L, rest = ns % 1000000000L;
  return static_cast<double>(whole) + static_cast<double>(rest) * 1e-9;
}

/* Natural order: digit runs compared as numbers ("img2" before "img10"), then the plain text. */
bool naturalLess(const std::string &a, const std::string &b)
{
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool db = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (da && db) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie])))
        ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je])))
        ++je;
      std::string na = a.substr(i, ie - i), nb = b.substr(j, je - j);
      na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
      nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
      if (na.size() != nb.size())
        return na.size() < nb.size();
      if (na != nb)
        return na < nb;
      i = ie;
      j = je;
      continue;
    }
    if (a[i] != b[j])
      return a[i] < b[j];
    ++i;
    ++j;
  }
  if ((a.size() - i) != (b.size() - j))
    return a.size() - i < b.size() - j;
  return a < b;
}

bool isPipe(const std::string &path)
{
  struct stat st{};
  return ::stat(path.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

bool isFolder(const std::string &path)
{
  std::error_code ec;
  return fs::is_directory(path, ec);
}

/* The files of `folder` whose extension (lower case) is one of `extensions`, in natural name order. */
std::vector<fs::path> filesWithExtensions(const std::string &folder, const std::vector<std::string> &extensions)
{
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code ec2;
    if (!it->is_regular_file(ec2))
      continue;
    const std::string ext = lower(it->path().extension().string());
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end())
      files.push_back(it->path());
  }
  if (ec)
    throwError(folder + ": cannot list the folder (" + ec.message() + ")");
  std::sort(files.begin(), files.end(),
            [](const fs::path &a, const fs::path &b) { return naturalLess(a.filename().string(), b.filename().string()); });
  return files;
}

const std::vector<std::string> kImageExtensions = {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".pnm",
                                                   ".bmp", ".tif", ".tiff"};

/* The first lines of a file that carry content (blank lines skipped), at most `n`. */
std::vector<std::string> firstLines(const std::string &path, std::size_t n, const InputLimits &limits)
{
  TextInput in(path, limits);
  std::vector<std::string> lines;
  std::string line;
  bool first = true;
  while (lines.size() < n && in.getline(line)) {
    if (first && line.size() >= 3 && line.compare(0, 3, "\xEF\xBB\xBF") == 0)
      line.erase(0, 3);
    first = false;
    const std::string t = trimmed(line);
    if (!t.empty())
      lines.push_back(t);
  }
  return lines;
}

/* The column names of a CSV header line (split at commas, trimmed). */
std::vector<std::string> headerNames(const std::string &line)
{
  std::vector<std::string> names;
  std::size_t start = 0;
  for (;;) {
    const auto comma = line.find(',', start);
    names.push_back(trimmed(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos)
      break;
    start = comma + 1;
  }
  return names;
}

bool isNumber(const std::string &text)
{
  double v = 0;
  return parseDouble(text, v) == NumberStatus::Ok;
}

/* TUM: `timestamp tx ty tz qx qy qz qw` per line. */
MotionLog readTum(const std::string &path, double yaw, const InputLimits &limits)
{
  TextInput in(path, limits);
  MotionLog log;
  log.timestamped = true;
  log.yaw_column = false;
  std::string line;
  bool first = true;
  static const char *const kNames[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  while (in.getline(line)) {
    if (first && line.size() >= 3 && line.compare(0, 3, "\xEF\xBB\xBF") == 0)
      line.erase(0, 3);
    first = false;
    const std::string t = trimmed(line);
    if (t.empty() || t[0] == '#')
      continue;
    const std::string at = path + ":" + std::to_string(in.lineNumber()) + ": ";
    const auto fail = [&](const std::string &why) { throwError(at + why); };
    const std::vector<std::string> f = splitBlanks(t);
    if (f.size() != 8)
      fail("expected 8 fields 'timestamp tx ty tz qx qy qz qw' (TUM), found " + std::to_string(f.size()));
    double v[8];
    for (int i = 0; i < 8; ++i) {
      switch (parseDouble(f[static_cast<std::size_t>(i)], v[i])) {
      case NumberStatus::Ok:
        break;
      case NumberStatus::NotFinite:
        throwError(at + kNames[i] + ": '" + excerpt(f[static_cast<std::size_t>(i)]) + "' is not a finite number");
      default:
        throwError(at + kNames[i] + ": '" + excerpt(f[static_cast<std::size_t>(i)]) + "' is not a number");
      }
    }
    io_detail::checkTimeIncreasing(v[0], log.times.empty() ? std::nullopt : std::optional<double>(log.times.back()),
                                   fail);
    MotionSample s;
    s.frame = static_cast<long>(log.samples.size());
    s.six_dof = true;
    s.x = v[1];
    s.y = v[2];
    s.z = v[3];
    s.theta_u = io_detail::thetaUOfQuaternion(v[4], v[5], v[6], v[7], fail);
    s.yaw = yaw;
    log.times.push_back(v[0]);
    log.samples.push_back(s);
  }
  if (log.samples.empty())
    throwError(path + ": no poses (a TUM trajectory has lines 'timestamp tx ty tz qx qy qz qw')");
  return log;
}

/* EuRoC / ASL CSV: #timestamp [ns], p_*_x/y/z [m], q_*_w/x/y/z []. */
MotionLog readEuroc(const std::string &path, double yaw, const InputLimits &limits)
{
  CsvReader csv(path, limits);
  const std::vector<std::string> &names = csv.names();
  std::vector<std::string> base(names.size());
  std::transform(names.begin(), names.end(), base.begin(), baseName);
  const auto find = [&](const std::string &name) -> std::optional<std::size_t> {
    for (std::size_t i = 0; i < base.size(); ++i)
      if (base[i] == name)
        return i;
    return std::nullopt;
  };
  const auto c_time = find("timestamp");
  if (!c_time)
    csv.failAt(csv.headerLine(), "missing column '#timestamp [ns]' in the header (EuRoC)");
  // The first position p_<frames>_x with its _y, _z; the first quaternion q_<frames>_w with _x, _y, _z.
  std::optional<std::size_t> c_p[3], c_q[4];
  for (std::size_t i = 0; i < base.size() && !c_p[0]; ++i) {
    const std::string &b = base[i];
    if (b.size() > 4 && b.compare(0, 2, "p_") == 0 && b.compare(b.size() - 2, 2, "_x") == 0) {
      const std::string stem = b.substr(0, b.size() - 1);
      if (find(stem + "y") && find(stem + "z")) {
        c_p[0] = i;
        c_p[1] = find(stem + "y");
        c_p[2] = find(stem + "z");
      }
    }
  }
  for (std::size_t i = 0; i < base.size() && !c_q[0]; ++i) {
    const std::string &b = base[i];
    if (b.size() > 4 && b.compare(0, 2, "q_") == 0 && b.compare(b.size() - 2, 2, "_w") == 0) {
      const std::string stem = b.substr(0, b.size() - 1);
      if (find(stem + "x") && find(stem + "y") && find(stem + "z")) {
        c_q[0] = i;
        c_q[1] = find(stem + "x");
        c_q[2] = find(stem + "y");
        c_q[3] = find(stem + "z");
      }
    }
  }
  if (!c_p[0])
    csv.failAt(csv.headerLine(), "missing position columns 'p_RS_R_x [m]', 'p_RS_R_y [m]', 'p_RS_R_z [m]' (EuRoC)");
  if (!c_q[0])
    csv.failAt(csv.headerLine(), "missing quaternion columns 'q_RS_w []', 'q_RS_x []', 'q_RS_y []', 'q_RS_z []' (EuRoC)");
  MotionLog log;
  log.timestamped = true;
  log.yaw_column = false;
  const auto fail = [&](const std::string &why) { csv.fail(why); };
  while (csv.next()) {
    const double t = nanosecondsToSeconds(csv.integer(*c_time));
    io_detail::checkTimeIncreasing(t, log.times.empty() ? std::nullopt : std::optional<double>(log.times.back()),
                                   fail);
    MotionSample s;
    s.frame = static_cast<long>(log.samples.size());
    s.six_dof = true;
    s.x = csv.number(*c_p[0]);
    s.y = csv.number(*c_p[1]);
    s.z = csv.number(*c_p[2]);
    s.theta_u = io_detail::thetaUOfQuaternion(csv.number(*c_q[1]), csv.number(*c_q[2]), csv.number(*c_q[3]),
                                              csv.number(*c_q[0]), fail);
    s.yaw = yaw;
    log.times.push_back(t);
    log.samples.push_back(s);
  }
  if (log.samples.empty())
    csv.failFile("no data rows after the header");
  return log;
}

/* The paths of ViSP pose files: the files given, or the .yaml/.yml files of one folder. */
std::vector<std::string> poseFiles(const std::vector<std::string> &paths)
{
  if (paths.size() == 1 && isFolder(paths[0])) {
    std::vector<std::string> files;
    for (const fs::path &p : filesWithExtensions(paths[0], {".yaml", ".yml"}))
      files.push_back(p.string());
    if (files.empty())
      throwError(paths[0] + ": no .yaml pose files in this folder");
    return files;
  }
  std::vector<std::string> files = paths;
  std::stable_sort(files.begin(), files.end(), [](const std::string &a, const std::string &b) {
    return naturalLess(fs::path(a).filename().string(), fs::path(b).filename().string());
  });
  return files;
}

/* The time in an image's file stem: seconds with a decimal point, integer nanoseconds. */
std::optional<double> stemTime(const std::string &stem)
{
  if (stem.empty())
    return std::nullopt;
  std::size_t dots = 0;
  for (char c : stem) {
    if (c == '.')
      ++dots;
    else if (!std::isdigit(static_cast<unsigned char>(c)))
      return std::nullopt;
  }
  if (dots > 1 || stem.front() == '.' || stem.back() == '.')
    return std::nullopt;
  if (dots == 1) {
    double v = 0;
    if (parseDouble(stem, v) != NumberStatus::Ok)
      return std::nullopt;
    return v;
  }
  long ns = 0;
  if (parseInteger(stem, ns) != NumberStatus::Ok)
    return std::nullopt;
  return nanosecondsToSeconds(ns);
}

/* Sorted by time; two images with one time are an error. */
void sortByTime(ImageList &list, const std::string &what)
{
  std::vector<std::size_t> order(list.paths.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return list.times[a] < list.times[b]; });
  ImageList sorted;
  for (std::size_t i : order) {
    if (!sorted.times.empty() && !(list.times[i] > sorted.times.back()))
      throwError(what + ": two images at time " + formatNumber(list.times[i]) + " s (" +
                 fs::path(sorted.paths.back()).filename().string() + ", " + fs::path(list.paths[i]).filename().string() +
                 ")");
    sorted.paths.push_back(list.paths[i]);
    sorted.times.push_back(list.times[i]);
  }
  list = std::move(sorted);
}

ImageList imagesOfFolder(const std::string &folder, bool timed)
{
  ImageList list;
  for (const fs::path &p : filesWithExtensions(folder, kImageExtensions)) {
    if (timed) {
      const auto t = stemTime(p.stem().string());
      if (!t)
        throwError(p.string() + ": the image name is not a timestamp (expected seconds such as 1305031102.175304.png, "
                                "or integer nanoseconds such as 1403636579763555584.png)");
      list.times.push_back(*t);
    }
    list.paths.push_back(p.string());
  }
  if (list.paths.empty())
    throwError(folder + ": no images in this folder (.png, .jpg, .pgm, .ppm, .bmp, .tif)");
  if (timed)
    sortByTime(list, folder);
  return list;
}

/* A list entry's image: relative to the list's folder, or (EuRoC) to data/ beside it. */
std::string listImage(const std::string &list_path, const std::string &name, std::size_t line, bool euroc)
{
  const fs::path folder = fs::path(list_path).parent_path();
  const fs::path direct = fs::path(name).is_absolute() ? fs::path(name) : folder / name;
  std::error_code ec;
  if (fs::is_regular_file(direct, ec))
    return direct.string();
  if (euroc && !fs::path(name).is_absolute()) {
    const fs::path data = folder / "data" / name;
    if (fs::is_regular_file(data, ec))
      return data.string();
  }
  throwError(list_path + ":" + std::to_string(line) + ": " + excerpt(name, 120) + ": no such image file (looked in " +
             (folder.empty() ? std::string(".") : folder.string()) + (euroc ? " and its data/ folder)" : ")"));
}

ImageList imagesOfList(const std::string &path, const InputLimits &limits)
{
  const std::vector<std::string> head = firstLines(path, 1, limits);
  if (head.empty())
    throwError(path + ": empty image list");
  const bool euroc = head[0].find(',') != std::string::npos;
  ImageList list;
  if (euroc) {
    CsvReader csv(path, limits);
    std::optional<std::size_t> c_time, c_file;
    for (std::size_t i = 0; i < csv.names().size(); ++i) {
      const std::string b = baseName(csv.names()[i]);
      if (b == "timestamp" && !c_time)
        c_time = i;
      if (b == "filename" && !c_file)
        c_file = i;
    }
    if (!c_time || !c_file)
      csv.failAt(csv.headerLine(), "an image list in CSV form needs the columns '#timestamp [ns]' and 'filename' (EuRoC)");
    while (csv.next()) {
      const double t = nanosecondsToSeconds(csv.integer(*c_time));
      io_detail::checkTimeIncreasing(t, list.times.empty() ? std::nullopt : std::optional<double>(list.times.back()),
                                     [&](const std::string &why) { csv.fail(why); });
      list.paths.push_back(listImage(path, csv.field(*c_file), csv.line(), true));
      list.times.push_back(t);
    }
  } else {
    TextInput in(path, limits);
    std::string line;
    while (in.getline(line)) {
      const std::string t = trimmed(line);
      if (t.empty() || t[0] == '#')
        continue;
      const std::string at = path + ":" + std::to_string(in.lineNumber()) + ": ";
      const std::vector<std::string> f = splitBlanks(t);
      if (f.size() != 2)
        throwError(at + "expected 'timestamp filename' (TUM's rgb.txt), found " + std::to_string(f.size()) + " fields");
      double v = 0;
      if (parseDouble(f[0], v) != NumberStatus::Ok)
        throwError(at + "timestamp '" + excerpt(f[0]) + "' is not a finite number");
      io_detail::checkTimeIncreasing(v, list.times.empty() ? std::nullopt : std::optional<double>(list.times.back()),
                                     [&](const std::string &why) { throwError(at + why); });
      list.paths.push_back(listImage(path, f[1], in.lineNumber(), false));
      list.times.push_back(v);
    }
  }
  if (list.paths.empty())
    throwError(path + ": no images in this list");
  return list;
}

double medianRate(const std::vector<double> &times)
{
  if (times.size() < 2)
    return 0.0;
  std::vector<double> d(times.size() - 1);
  for (std::size_t i = 1; i < times.size(); ++i)
    d[i - 1] = times[i] - times[i - 1];
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  const double m = d[d.size() / 2];
  return m > 0 ? 1.0 / m : 0.0;
}

std::string span(double a, double b)
{
  return "[" + formatNumber(a) + ", " + formatNumber(b) + "] s";
}

std::string fixed(double v, int digits)
{
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

} // namespace recording_detail

using namespace recording_detail;

const char *toString(MotionFormat f)
{
  switch (f) {
  case MotionFormat::Auto:
    return "auto";
  case MotionFormat::Yawdepth:
    return "yawdepth";
  case MotionFormat::Tum:
    return "tum";
  case MotionFormat::Euroc:
    return "euroc";
  case MotionFormat::Visp:
    return "visp";
  }
  return "auto";
}

MotionFormat motionFormatFromString(const std::string &word)
{
  for (MotionFormat f : {MotionFormat::Auto, MotionFormat::Yawdepth, MotionFormat::Tum, MotionFormat::Euroc,
                         MotionFormat::Visp})
    if (word == toString(f))
      return f;
  throwError("unknown motion format '" + excerpt(word) + "' (auto, yawdepth, tum, euroc, visp)");
}

MotionFormat detectMotionFormat(const std::string &path, const InputLimits &limits)
{
  if (isFolder(path))
    return MotionFormat::Visp;
  checkInputFile(path);
  if (isPipe(path))
    return MotionFormat::Yawdepth; // read once only: the format must be given for another one
  for (const std::string &line : firstLines(path, 64, limits)) {
    if (line[0] == '#') {
      if (line.find(',') != std::string::npos && baseName(headerNames(line)[0]) == "timestamp")
        return MotionFormat::Euroc;
      continue; // a TUM comment
    }
    if (line.rfind("%YAML", 0) == 0 || line.rfind("rows:", 0) == 0)
      return MotionFormat::Visp;
    if (line.find(',') != std::string::npos) {
      const std::vector<std::string> names = headerNames(line);
      bool has_frame = false, has_timestamp = false;
      for (const std::string &n : names) {
        has_frame = has_frame || n == "frame" || n == "t";
        has_timestamp = has_timestamp || baseName(n) == "timestamp";
      }
      if (!has_frame && has_timestamp)
        return MotionFormat::Euroc;
      return MotionFormat::Yawdepth;
    }
    const std::vector<std::string> f = splitBlanks(line);
    if (f.size() == 8 && std::all_of(f.begin(), f.end(), isNumber))
      return MotionFormat::Tum;
    return MotionFormat::Yawdepth;
  }
  return MotionFormat::Yawdepth; // the reader names what is missing
}

vpPoseVector readVispPoseFile(const std::string &path)
{
  const std::string text = readTextFile(path, kMaxPoseFileBytes);
  if (text.find('\0') != std::string::npos)
    throwError(path + ": not a YAML file (it holds a NUL byte)");
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root || !root.IsMap())
      throwError(path + ": not a vpPoseVector file (expected 'rows: 6', 'cols: 1', 'data:' with 6 values)");
    const YAML::Node rows = root["rows"], cols = root["cols"], data = root["data"];
    if (!rows || !cols || !data)
      throwError(path + ": missing key '" + std::string(!rows ? "rows" : !cols ? "cols" : "data") +
                 "' (a vpPoseVector file has rows: 6, cols: 1, data: [[tx], [ty], [tz], [tux], [tuy], [tuz]])");
    if (finiteNumber(path, rows, "'rows'") != 6 || finiteNumber(path, cols, "'cols'") != 1)
      throwError(where(path, rows.Mark()) + "a vpPoseVector is 6x1 ('rows: 6', 'cols: 1')");
    if (!data.IsSequence() || data.size() != 6)
      throwError(where(path, data.Mark()) + "'data' must hold 6 rows (tx, ty, tz, tux, tuy, tuz)");
    double v[6];
    for (std::size_t i = 0; i < 6; ++i) {
      YAML::Node e = data[i];
      if (e.IsSequence()) {
        if (e.size() != 1)
          throwError(where(path, e.Mark()) + "'data' row " + std::to_string(i + 1) + " must hold one value");
        e = e[0];
      }
      v[i] = finiteNumber(path, e, "'data' row " + std::to_string(i + 1));
    }
    if (!(Eigen::Vector3d(v[3], v[4], v[5]).norm() <= 4 * M_PI))
      throwError(where(path, data.Mark()) + "the rotation (tux, tuy, tuz) has a norm above 4 pi: not theta-u in radians");
    return vpPoseVector(v[0], v[1], v[2], v[3], v[4], v[5]);
  } catch (const YAML::Exception &e) {
    throwError(where(path, e.mark) + "not valid YAML (" + e.msg + ")");
  }
}

MotionLog readMotionFile(const std::vector<std::string> &paths, MotionFormat format, std::optional<double> fixed_yaw,
                         const InputLimits &limits)
{
  if (paths.empty())
    throwError("no motion file given");
  if (format == MotionFormat::Auto)
    format = paths.size() > 1 ? MotionFormat::Visp : detectMotionFormat(paths[0], limits);
  if (format != MotionFormat::Visp && paths.size() > 1)
    throwError(paths[1] + ": several motion files are read only as ViSP pose files (--motion-format visp)");
  if (fixed_yaw && !std::isfinite(*fixed_yaw))
    throwError(paths[0] + ": the fixed yaw is not a finite number");
  const double yaw = fixed_yaw.value_or(0.0);
  switch (format) {
  case MotionFormat::Tum:
    return readTum(paths[0], yaw, limits);
  case MotionFormat::Euroc:
    return readEuroc(paths[0], yaw, limits);
  case MotionFormat::Visp: {
    MotionLog log;
    log.yaw_column = false;
    for (const std::string &p : poseFiles(paths)) {
      MotionSample s = MotionSample::fromPose(static_cast<long>(log.samples.size()), vpHomogeneousMatrix(readVispPoseFile(p)), yaw);
      log.samples.push_back(s);
    }
    return log;
  }
  case MotionFormat::Auto:
  case MotionFormat::Yawdepth:
    break;
  }
  return readMotionCsv(paths[0], fixed_yaw, limits);
}

ImageList readImageList(const std::string &path, bool timed, const InputLimits &limits)
{
  if (path.empty())
    throwError("--images: empty path");
  std::error_code ec;
  if (!fs::exists(path, ec))
    throwError(path + ": no such folder or image list");
  if (isFolder(path))
    return imagesOfFolder(path, timed);
  return imagesOfList(path, limits);
}

void TimeAlignmentOptions::validate() const
{
  if (!std::isfinite(time_offset))
    throwError("time offset " + formatNumber(time_offset) + " s is not a finite number");
  if (!(max_pose_gap > 0) || !std::isfinite(max_pose_gap))
    throwError("maximum pose gap " + formatNumber(max_pose_gap) + " s must be a finite number > 0");
}

std::string TimeAlignment::summary() const
{
  std::string s = std::to_string(images) + " images";
  if (image_rate_hz > 0)
    s += " (" + fixed(image_rate_hz, 1) + " Hz)";
  s += ", " + std::to_string(matched) + " matched";
  const std::size_t skipped = before + after + in_gap;
  if (skipped) {
    s += ", " + std::to_string(skipped) + " skipped (";
    std::string parts;
    if (before)
      parts += std::to_string(before) + " before the poses";
    if (after)
      parts += (parts.empty() ? "" : ", ") + std::to_string(after) + " after them";
    if (in_gap)
      parts += (parts.empty() ? "" : ", ") + std::to_string(in_gap) + " in pose gaps";
    s += parts + ")";
  }
  s += "; poses";
  if (motion_rate_hz > 0)
    s += " at " + fixed(motion_rate_hz, 1) + " Hz";
  s += " over " + fixed(motion_last - motion_first, 3) + " s";
  return s;
}

TimeAlignment alignMotionToImages(const MotionLog &motion, const ImageList &images, const TimeAlignmentOptions &options,
                                  const std::string &motion_path, const std::string &images_path)
{
  options.validate();
  if (!motion.timestamped || motion.times.size() != motion.samples.size() || motion.samples.empty())
    throwError(motion_path + ": not a timestamped motion log (it needs a time per pose: 't', TUM or EuRoC)");
  if (images.paths.empty() || images.times.size() != images.paths.size())
    throwError(images_path + ": no timed images");
  TimeAlignment a;
  a.images = images.paths.size();
  a.motion_first = motion.times.front();
  a.motion_last = motion.times.back();
  a.image_first = images.times.front() + options.time_offset;
  a.image_last = images.times.back() + options.time_offset;
  a.motion_rate_hz = medianRate(motion.times);
  a.image_rate_hz = medianRate(images.times);
  if (a.image_last < a.motion_first || a.image_first > a.motion_last) {
    std::string hint;
    const double mi = std::max(std::abs(a.image_first), std::abs(a.image_last));
    const double mm = std::max(std::abs(a.motion_first), std::abs(a.motion_last));
    const double ratio = std::max(mi, mm) / std::max(1e-300, std::min(mi, mm));
    if (ratio > 1e6 && ratio < 1e13)
      hint = ": the " + std::string(mi > mm ? "images'" : "poses'") + " times are about " +
             formatNumber(std::pow(10.0, std::round(std::log10(ratio)))) +
             " times larger (nanoseconds against seconds?)";
    else
      hint = ": the two clocks differ (a relative clock against an absolute one, or a wrong --time-offset?)";
    throwError(images_path + ": the images span " + span(a.image_first, a.image_last) + " and the poses of " +
               motion_path + " span " + span(a.motion_first, a.motion_last) +
               (options.time_offset != 0 ? " (time offset " + formatNumber(options.time_offset) + " s)" : "") +
               ": they do not overlap" + hint);
  }
  a.log.timestamped = false;
  a.log.yaw_column = motion.yaw_column;
  const std::vector<double> &T = motion.times;
  for (std::size_t i = 0; i < images.paths.size(); ++i) {
    const double t = images.times[i] + options.time_offset;
    if (t < T.front()) {
      ++a.before;
      continue;
    }
    if (t > T.back()) {
      ++a.after;
      continue;
    }
    const std::size_t j = static_cast<std::size_t>(std::upper_bound(T.begin(), T.end(), t) - T.begin()); // T[j-1] <= t < T[j]
    MotionSample s;
    if (T[j - 1] == t) {
      s = motion.samples[j - 1];
    } else {
      if (T[j] - T[j - 1] > options.max_pose_gap) {
        ++a.in_gap;
        continue;
      }
      s = interpolateMotion(motion.samples[j - 1], motion.samples[j], (t - T[j - 1]) / (T[j] - T[j - 1]));
    }
    s.frame = static_cast<long>(i);
    a.log.samples.push_back(s);
    a.log.images.push_back(images.paths[i]);
    a.log.times.push_back(t);
    ++a.matched;
  }
  if (a.matched == 0)
    throwError(images_path + ": no image has a pose: " + std::to_string(a.in_gap) +
               " fall in gaps of the pose log longer than " + formatNumber(options.max_pose_gap) +
               " s (--max-pose-gap)");
  return a;
}

LoadedMotion loadMotion(const MotionInput &input, std::optional<double> fixed_yaw, std::optional<double> rig_time_offset,
                        const InputLimits &limits)
{
  if (input.motion.empty())
    throwError("--motion: no motion file given");
  LoadedMotion out;
  out.format = input.format;
  if (out.format == MotionFormat::Auto)
    out.format = input.motion.size() > 1 ? MotionFormat::Visp : detectMotionFormat(input.motion[0], limits);
  const std::string &motion_path = input.motion[0];
  if (out.format == MotionFormat::Visp) {
    out.log = readMotionFile(input.motion, MotionFormat::Visp, fixed_yaw, limits);
    if (!input.images.empty()) {
      const ImageList images = readImageList(input.images, false, limits);
      if (images.paths.size() != out.log.samples.size())
        throwError(input.images + ": " + std::to_string(images.paths.size()) + " images for " +
                   std::to_string(out.log.samples.size()) + " ViSP pose files (" + motion_path +
                   (input.motion.size() > 1 ? ", ..." : "") + "): they are paired in name order, one pose per image");
      out.log.images = images.paths;
    }
    return out;
  }
  out.log = readMotionFile({input.motion[0]}, out.format, fixed_yaw, limits);
  if (input.motion.size() > 1)
    throwError(input.motion[1] + ": several motion files are read only as ViSP pose files (--motion-format visp)");
  if (!out.log.timestamped) {
    if (!input.images.empty())
      throwError(input.images + ": --images gives the images' times, but " + motion_path +
                 " is frame-based (column 'frame'): its images are its 'image' column");
    return out;
  }
  if (input.images.empty())
    throwError(motion_path + ": a timestamped motion log (" + std::string(toString(out.format)) +
               ") needs --images, the images and their times (a folder named by timestamps, rgb.txt or data.csv)");
  TimeAlignmentOptions options;
  options.time_offset = input.time_offset ? *input.time_offset : rig_time_offset.value_or(0.0);
  options.max_pose_gap = input.max_pose_gap;
  out.time_offset = options.time_offset;
  out.alignment = alignMotionToImages(out.log, readImageList(input.images, true, limits), options, motion_path,
                                      input.images);
  out.log = out.alignment->log;
  return out;
}

} // namespace yawdepth
