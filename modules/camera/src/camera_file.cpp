/*!
  \file camera_file.cpp
  \brief Camera files: ViSP XML through vpXmlParserCamera, OpenCV YAML/XML through cv::FileStorage.
*/
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/core/files.h>
#include "quiet_visp.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <Eigen/LU>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <iostream>
#include <mutex>
#include <opencv2/core.hpp>
#include <charconv>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>
#include <visp3/core/vpXmlParserCamera.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

/*! \brief One-line version of a message (newlines and tabs become spaces, trimmed). */
std::string oneLine(const std::string &s) {
  std::string r;
  r.reserve(s.size());
  bool space = false;
  for (char c : s) {
    if (c == '\n' || c == '\r' || c == '\t' || c == ' ') {
      space = !r.empty();
      continue;
    }
    if (space)
      r += ' ';
    space = false;
    r += c;
  }
  return r;
}

std::string trim(const std::string &s) {
  const char *ws = " \t\r\n";
  const auto b = s.find_first_not_of(ws);
  if (b == std::string::npos)
    return "";
  const auto e = s.find_last_not_of(ws);
  return s.substr(b, e - b + 1);
}

/*! \brief Whole file as text; throws yawdepth::Error when missing, a directory or unreadable. */
std::string readWholeFile(const std::string &path) {
  std::error_code ec;
  if (path.empty())
    throw Error("camera file: empty path");
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st))
    throw Error(path + ": camera file not found");
  if (std::filesystem::is_directory(st))
    throw Error(path + ": is a directory, not a camera file");
  // A regular file or a pipe, at most 16 MiB (a camera file is a few kB): not a device that never ends.
  std::string text = yawdepth::readTextFile(path, std::size_t(16) << 20);
  if (text.size() >= 3 && static_cast<unsigned char>(text[0]) == 0xEF &&
      static_cast<unsigned char>(text[1]) == 0xBB && static_cast<unsigned char>(text[2]) == 0xBF)
    text.erase(0, 3); // UTF-8 byte order mark
  return text;
}

/*! \brief True when `text` has the tag `<name` followed by `>`, `/` or white space. */
std::size_t findTag(const std::string &text, const std::string &name, std::size_t from = 0) {
  const std::string open = "<" + name;
  for (std::size_t p = text.find(open, from); p != std::string::npos; p = text.find(open, p + 1)) {
    const std::size_t after = p + open.size();
    if (after >= text.size())
      return std::string::npos;
    const char c = text[after];
    if (c == '>' || c == '/' || c == ' ' || c == '\t' || c == '\n' || c == '\r')
      return p;
  }
  return std::string::npos;
}

/*! \brief The text with XML comments blanked out. */
std::string stripXmlComments(const std::string &text) {
  std::string r = text;
  for (std::size_t p = r.find("<!--"); p != std::string::npos; p = r.find("<!--", p)) {
    std::size_t e = r.find("-->", p + 4);
    e = (e == std::string::npos) ? r.size() : e + 3;
    std::fill(r.begin() + static_cast<std::ptrdiff_t>(p), r.begin() + static_cast<std::ptrdiff_t>(e), ' ');
    p = e;
  }
  return r;
}

std::string decodeXmlEntities(const std::string &s) {
  static const std::pair<const char *, char> entities[] = {
      {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}, {"&amp;", '&'}};
  std::string r;
  for (std::size_t i = 0; i < s.size();) {
    bool done = false;
    if (s[i] == '&')
      for (const auto &e : entities) {
        const std::size_t n = std::char_traits<char>::length(e.first);
        if (s.compare(i, n, e.first) == 0) {
          r += e.second;
          i += n;
          done = true;
          break;
        }
      }
    if (!done)
      r += s[i++];
  }
  return r;
}

/*!
  \brief Names of the `<camera>` entries of a ViSP XML file, in file order (light text scan; the
  real parsing is vpXmlParserCamera's). A camera without `<name>` has an empty name.
*/
std::vector<std::string> vispCameraNames(const std::string &raw) {
  const std::string text = stripXmlComments(raw);
  std::vector<std::string> names;
  for (std::size_t p = findTag(text, "camera"); p != std::string::npos;) {
    const std::size_t gt = text.find('>', p);
    if (gt == std::string::npos)
      break;
    if (text[gt - 1] == '/') { // <camera/>
      names.emplace_back();
      p = findTag(text, "camera", gt);
      continue;
    }
    std::size_t end = text.find("</camera>", gt);
    if (end == std::string::npos)
      end = text.size();
    const std::string body = text.substr(gt + 1, end - gt - 1);
    std::string name;
    const std::size_t n = findTag(body, "name");
    if (n != std::string::npos) {
      const std::size_t ngt = body.find('>', n);
      if (ngt != std::string::npos && body[ngt - 1] != '/') {
        const std::size_t nend = body.find("</name>", ngt);
        name = body.substr(ngt + 1, (nend == std::string::npos ? body.size() : nend) - ngt - 1);
        const std::string cdata = "<![CDATA[";
        if (name.compare(0, cdata.size(), cdata) == 0 && name.size() >= cdata.size() + 3)
          name = name.substr(cdata.size(), name.size() - cdata.size() - 3);
        else
          name = decodeXmlEntities(name);
      }
    }
    names.push_back(name);
    p = findTag(text, "camera", end);
  }
  return names;
}

std::string joinNames(const std::vector<std::string> &names) {
  std::string r;
  for (const auto &n : names)
    r += (r.empty() ? "" : ", ") + (n.empty() ? std::string("<unnamed>") : n);
  return r;
}


/*! \brief One vpXmlParserCamera::parse call, silenced; false when ViSP reports an error. */
bool vispParse(const std::string &path, const std::string &name,
               vpCameraParameters::vpCameraParametersProjType model, vpCameraParameters &cam, unsigned &w,
               unsigned &h) {
  const detail::QuietVisp quiet; // parse() prints "Found camera with name ..."
  vpXmlParserCamera parser;
  vpCameraParameters c;
  if (parser.parse(c, path, name, model, 0, 0) != vpXmlParserCamera::SEQUENCE_OK)
    return false;
  if (c.get_projModel() != model)
    return false;
  cam = c;
  w = parser.getWidth();
  h = parser.getHeight();
  return true;
}

CameraModel loadVispXml(const std::string &path, const std::string &text, const std::string &camera_name) {
  const std::vector<std::string> names = vispCameraNames(text);
  if (names.empty())
    throw Error(path + ": no <camera> entry in this ViSP camera file");

  std::string name; // exactly as written in the file (vpXmlParserCamera compares verbatim)
  if (camera_name.empty()) {
    if (names.size() > 1)
      throw Error("several cameras in " + path + "; pick one with --camera-name (" + joinNames(names) + ")");
    name = names.front();
  } else {
    std::vector<std::string> matches;
    for (const auto &n : names)
      if (n == camera_name || trim(n) == trim(camera_name))
        matches.push_back(n);
    if (matches.empty())
      throw Error(path + ": no camera named '" + camera_name + "' (cameras: " + joinNames(names) + ")");
    name = matches.front();
    for (const auto &n : matches)
      if (n == camera_name)
        name = n;
  }
  if (std::count(names.begin(), names.end(), name) > 1)
    throw Error(path + ": several cameras named '" + name + "'");

  vpCameraParameters cam;
  unsigned w = 0, h = 0;
  bool ok = false;
  try {
    ok = vispParse(path, name, vpCameraParameters::perspectiveProjWithDistortion, cam, w, h) ||
         vispParse(path, name, vpCameraParameters::perspectiveProjWithoutDistortion, cam, w, h);
  } catch (const std::exception &e) {
    throw Error(path + ": ViSP could not read the camera file: " + oneLine(e.what()));
  } catch (...) {
    throw Error(path + ": ViSP could not read the camera file");
  }
  if (!ok)
    throw Error(path + ": vpXmlParserCamera rejected camera '" + name +
                "' (malformed XML, unexpected element, or no complete perspectiveProjWithDistortion / "
                "perspectiveProjWithoutDistortion model)");
  try {
    return CameraModel(cam, w, h);
  } catch (const Error &e) {
    throw Error(path + ": " + e.what());
  }
}

/*! \brief Largest number of rows or columns of a matrix in a camera file (at most 3x3 or 1x8). */
constexpr int kMaxMatrixSide = 16;

/*! \brief Numbers of an OpenCV matrix node (map `!!opencv-matrix`), a sequence, or a scalar. */
std::vector<double> readNumbers(const cv::FileNode &node, const std::string &path, const std::string &key,
                                int &rows, int &cols) {
  std::vector<double> v;
  if (node.isMap()) {
    // Checked before OpenCV sizes the matrix from `rows` and `cols`: a corrupt size (a stray
    // byte before the number) made cv::FileNode >> cv::Mat ask for 48 GB (found by fuzzing).
    const cv::FileNode rn = node["rows"], cn = node["cols"];
    if (!rn.isInt() || !cn.isInt())
      throw Error(path + ": " + key + " is not a matrix (no integer rows and cols)");
    const int nr = static_cast<int>(rn), nc = static_cast<int>(cn);
    if (nr < 0 || nc < 0 || nr > kMaxMatrixSide || nc > kMaxMatrixSide)
      throw Error(path + ": " + key + " has a bad size " + std::to_string(nr) + "x" + std::to_string(nc));
    cv::Mat m;
    node >> m;
    if (m.empty()) {
      rows = cols = 0;
      return v;
    }
    if (m.channels() != 1)
      throw Error(path + ": " + key + " must be a single-channel matrix");
    cv::Mat md;
    m.convertTo(md, CV_64F);
    rows = md.rows;
    cols = md.cols;
    for (int r = 0; r < md.rows; ++r)
      for (int c = 0; c < md.cols; ++c)
        v.push_back(md.at<double>(r, c));
  } else if (node.isSeq()) {
    for (const cv::FileNode e : node) {
      if (!e.isInt() && !e.isReal())
        throw Error(path + ": " + key + " must hold numbers only");
      v.push_back(static_cast<double>(e));
    }
    rows = 1;
    cols = static_cast<int>(v.size());
  } else if (node.isInt() || node.isReal()) {
    v.push_back(static_cast<double>(node));
    rows = cols = 1;
  } else {
    throw Error(path + ": " + key + " is not a matrix");
  }
  for (double x : v)
    if (!std::isfinite(x))
      throw Error(path + ": " + key + " holds a non-finite value");
  return v;
}

unsigned readImageSize(const cv::FileNode &node, const std::string &path, const std::string &key) {
  if (node.empty() || node.isNone())
    return 0;
  if (!node.isInt())
    throw Error(path + ": " + key + " must be an integer");
  const int v = static_cast<int>(node);
  if (v < 0)
    throw Error(path + ": " + key + " = " + std::to_string(v) + " must be >= 0");
  return static_cast<unsigned>(v);
}

/*! \brief Deepest nesting accepted in a camera file (a real one nests 2 or 3 levels). */
constexpr int kMaxNesting = 16;

/*!
  \brief Throws yawdepth::Error for what OpenCV 4.6's cv::FileStorage cannot take safely (found by
  fuzzing; its parsers are third-party code, so the input is checked here first):
  - YAML whose top level is not a block map starting in the first column, or with a second
    document ('---' or '...' after the first key): after a first document that ends before the end
    of the file, a line starting with '-' sends the parser into an endless loop;
  - nesting deeper than kMaxNesting (flow collections `[` `{`, block sequences `- - -` on one line,
    XML elements): the parsers recurse once per level without a limit and overflow the stack.
*/
void precheckOpenCv(const std::string &path, const std::string &content, bool yaml) {
  const auto tooDeep = [&] {
    return Error(path + ": nested more than " + std::to_string(kMaxNesting) + " levels deep; not a camera file");
  };
  if (!yaml) {
    const std::string t = stripXmlComments(content);
    int depth = 0;
    for (std::size_t p = t.find('<'); p != std::string::npos; p = t.find('<', p + 1)) {
      const std::size_t gt = t.find('>', p);
      if (gt == std::string::npos)
        break;
      if (p + 1 < t.size() && t[p + 1] == '/')
        depth = std::max(0, depth - 1);
      else if (p + 1 < t.size() && t[p + 1] != '?' && t[p + 1] != '!' && t[gt - 1] != '/' && ++depth > kMaxNesting)
        throw tooDeep();
    }
    return;
  }
  std::istringstream in(content);
  std::string line;
  bool first_item = false;
  int flow_depth = 0;
  while (std::getline(in, line)) {
    const std::size_t b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#')
      continue;
    if (!first_item) {
      if (line[b] == '%' || line.compare(b, 3, "---") == 0)
        continue; // directives and the document start, before the first key
      if (b != 0 || !(std::isalnum(static_cast<unsigned char>(line[0])) || line[0] == '_'))
        throw Error(path + ": not a camera file (its top level must be a map of keys starting in the first "
                           "column, e.g. 'camera_matrix: ...')");
      first_item = true;
    } else if (b == 0 && (line.compare(0, 3, "---") == 0 || line.compare(0, 3, "...") == 0)) {
      throw Error(path + ": a camera file holds one YAML document ('" + line.substr(0, 3) +
                  "' after its first key)");
    }
    int dashes = 0; // block sequences opened on this line: "- - - x"
    for (std::size_t i = b; i < line.size() && line[i] == '-' && (i + 1 == line.size() || line[i + 1] == ' ');
         i = line.find_first_not_of(' ', i + 1))
      if (++dashes > kMaxNesting)
        throw tooDeep();
    for (const char c : line) {
      if ((c == '[' || c == '{') && ++flow_depth > kMaxNesting)
        throw tooDeep();
      if ((c == ']' || c == '}') && flow_depth > 0)
        --flow_depth;
    }
  }
}

/*!
  \brief The pinhole part of a 3x3 camera matrix (row-major): zero skew, K(1,0) = 0, last row
  [0 0 1]; throws yawdepth::Error naming `path` and `key` otherwise.
*/
void pinholeOf(const std::string &path, const std::string &key, const std::vector<double> &K, double &fx,
               double &fy, double &u0, double &v0) {
  fx = K[0];
  fy = K[4];
  u0 = K[2];
  v0 = K[5];
  if (std::abs(K[3]) > 0 || std::abs(K[6]) > 0 || std::abs(K[7]) > 0 || std::abs(K[8] - 1) > 1e-12)
    throw Error(path + ": " + key + " last row must be [0 0 1] and K(1,0) must be 0");
  if (std::abs(K[1]) > 1e-9 * std::max(1.0, std::abs(fx)))
    throw Error(path + ": " + key + " has a non-zero skew, which is not supported");
}

/*! \brief A CameraModel factory's error, prefixed with the file (and the key, when given). */
template <class Make> CameraModel makeCamera(const std::string &path, const std::string &key, Make make) {
  try {
    return make();
  } catch (const Error &e) {
    std::string what = e.what();
    if (what.rfind("camera: ", 0) == 0)
      what.erase(0, 8);
    throw Error(path + ": " + (key.empty() ? std::string() : key + ": ") + what);
  }
}

/*! \brief The fisheye model's names in a camera file's `distortion_model` (ROS, Kalibr, OpenCV). */
bool isFisheyeName(const std::string &m) { return m == "equidistant" || m == "fisheye"; }

CameraModel loadOpenCv(const std::string &path, const std::string &text, bool yaml) {
  std::string content = text;
  if (yaml && trim(text).rfind("%YAML", 0) != 0)
    content = "%YAML:1.0\n---\n" + text; // OpenCV 4 insists on the YAML header
  precheckOpenCv(path, content, yaml);
  std::vector<double> K, D;
  int kr = 0, kc = 0, dr = 0, dc = 0;
  unsigned w = 0, h = 0;
  std::string model;
  try {
    cv::FileStorage fs(content, cv::FileStorage::READ | cv::FileStorage::MEMORY |
                                    (yaml ? cv::FileStorage::FORMAT_YAML : cv::FileStorage::FORMAT_XML));
    if (!fs.isOpened())
      throw Error(path + ": OpenCV cannot parse this camera file");
    const cv::FileNode root = fs.root();
    if (!root.isMap())
      throw Error(path + ": not a camera file (expected camera_matrix, distortion_coefficients, ...)");
    const cv::FileNode kn = fs["camera_matrix"];
    if (kn.empty() || kn.isNone())
      throw Error(path + ": missing camera_matrix");
    K = readNumbers(kn, path, "camera_matrix", kr, kc);
    const cv::FileNode dn = fs["distortion_coefficients"];
    if (!dn.empty() && !dn.isNone())
      D = readNumbers(dn, path, "distortion_coefficients", dr, dc);
    w = readImageSize(fs["image_width"], path, "image_width");
    h = readImageSize(fs["image_height"], path, "image_height");
    const cv::FileNode mn = fs["distortion_model"];
    if (!mn.empty() && !mn.isNone()) {
      if (!mn.isString())
        throw Error(path + ": distortion_model must be a word (plumb_bob, rational_polynomial or equidistant)");
      model = trim(static_cast<std::string>(mn));
    }
  } catch (const Error &) {
    throw;
  } catch (const cv::Exception &e) {
    throw Error(path + ": OpenCV cannot read this camera file: " + oneLine(e.err) +
                (e.func.empty() ? std::string() : " (" + oneLine(e.func).substr(0, 120) + ")"));
  } catch (const std::exception &e) {
    throw Error(path + ": cannot read this camera file: " + oneLine(e.what()));
  }

  if (K.size() != 9 || !((kr == 3 && kc == 3) || kr == 1 || kc == 1))
    throw Error(path + ": camera_matrix must be 3x3 (got " + std::to_string(kr) + "x" + std::to_string(kc) + ")");
  double fx = 0, fy = 0, u0 = 0, v0 = 0;
  pinholeOf(path, "camera_matrix", K, fx, fy, u0, v0);
  if (!D.empty() && dr != 1 && dc != 1)
    throw Error(path + ": distortion_coefficients must be a 1xN or Nx1 matrix");
  if (isFisheyeName(model)) {
    if (D.size() != 4)
      throw Error(path + ": distortion_coefficients must hold 4 values (k1 k2 k3 k4) for distortion_model " +
                  model + " (got " + std::to_string(D.size()) + ")");
    return makeCamera(path, "", [&] { return CameraModel::kannalaBrandt(fx, fy, u0, v0, D, w, h); });
  }
  if (!model.empty() && model != "plumb_bob" && model != "rational_polynomial")
    throw Error(path + ": distortion_model '" + oneLine(model).substr(0, 64) +
                "' is not supported (known: plumb_bob, rational_polynomial, equidistant)");
  return makeCamera(path, "", [&] { return CameraModel::brown(fx, fy, u0, v0, D, w, h); });
}

// ---- ROS camera_info and Kalibr camchain YAML ----
// Read with cv::FileStorage's YAML parser node by node (never `node >> cv::Mat`, whose messages are
// OpenCV's internals), so that the camera module needs no other YAML library: a servo-only user
// of the installed package must not need yaml-cpp (tests/consumer_servo).

bool present(const cv::FileNode &n) { return !n.empty() && !n.isNone(); }

/*! \brief What a node is, for a message: its text when it is a string, else its kind. */
std::string shown(const cv::FileNode &n) {
  if (n.isString()) {
    const std::string t = oneLine(static_cast<std::string>(n));
    return "'" + (t.size() > 40 ? t.substr(0, 40) + "..." : t) + "'";
  }
  if (n.isMap())
    return "a map";
  if (n.isSeq())
    return "a sequence";
  if (n.isNone())
    return "empty";
  return "not a number";
}

std::string numText(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

/*! \brief A finite number; throws naming the file and key otherwise. */
double yamlNumber(const std::string &path, const cv::FileNode &n, const std::string &key) {
  if (!n.isInt() && !n.isReal())
    throw Error(path + ": " + key + " = " + shown(n) + " is not a number");
  const double v = n.isInt() ? static_cast<double>(static_cast<int>(n)) : static_cast<double>(n);
  if (!std::isfinite(v))
    throw Error(path + ": " + key + " = " + (std::isnan(v) ? std::string("nan") : numText(v)) + " is not finite");
  return v;
}

/*! \brief The finite numbers of a sequence (any length). */
std::vector<double> yamlNumbers(const std::string &path, const cv::FileNode &n, const std::string &key) {
  if (!n.isSeq())
    throw Error(path + ": " + key + " must be a sequence of numbers [a, b, ...] (it is " + shown(n) + ")");
  std::vector<double> v;
  for (std::size_t i = 0; i < n.size(); ++i)
    v.push_back(yamlNumber(path, n[static_cast<int>(i)], key + "[" + std::to_string(i) + "]"));
  return v;
}

/*! \brief A non-negative integer of at most 2^20 (an image side, a matrix size; the plausibility
    check refuses image sides over 65535 with its own message). */
unsigned yamlSize(const std::string &path, const cv::FileNode &n, const std::string &key) {
  if (!n.isInt())
    throw Error(path + ": " + key + " = " + (n.isReal() ? numText(static_cast<double>(n)) : shown(n)) +
                " must be an integer");
  const int v = static_cast<int>(n);
  if (v < 0 || v > (1 << 20))
    throw Error(path + ": " + key + " = " + std::to_string(v) + " must be 0 to 1048576");
  return static_cast<unsigned>(v);
}

std::string yamlWord(const std::string &path, const cv::FileNode &n, const std::string &key) {
  if (!n.isString())
    throw Error(path + ": " + key + " must be a word (it is " + shown(n) + ")");
  return trim(static_cast<std::string>(n));
}

/*!
  \brief A ROS camera_info matrix `{rows: R, cols: C, data: [R*C numbers]}` (`cols` < 0: any
  number of columns; `cols_out` receives it). A plain sequence is taken as the data of a 1 x N
  matrix when `rows` is 1.
*/
std::vector<double> rosMatrix(const std::string &path, const cv::FileNode &n, const std::string &key, int rows,
                              int cols, int *cols_out = nullptr) {
  if (rows == 1 && n.isSeq()) {
    std::vector<double> v = yamlNumbers(path, n, key);
    if (cols >= 0 && static_cast<int>(v.size()) != cols)
      throw Error(path + ": " + key + " must hold " + std::to_string(cols) + " numbers (got " +
                  std::to_string(v.size()) + ")");
    if (cols_out)
      *cols_out = static_cast<int>(v.size());
    return v;
  }
  const std::string shape = "{rows: " + std::to_string(rows) + ", cols: " + (cols >= 0 ? std::to_string(cols) : "N") +
                            ", data: [...]}";
  if (!n.isMap())
    throw Error(path + ": " + key + " must be a matrix " + shape + " (it is " + shown(n) + ")");
  for (const char *sub : {"rows", "cols", "data"})
    if (!present(n[sub]))
      throw Error(path + ": " + key + " has no " + sub + " (expected " + shape + ")");
  const unsigned r = yamlSize(path, n["rows"], key + ".rows");
  const unsigned c = yamlSize(path, n["cols"], key + ".cols");
  if (static_cast<int>(r) != rows || (cols >= 0 && static_cast<int>(c) != cols) || c > 64)
    throw Error(path + ": " + key + " is " + std::to_string(r) + "x" + std::to_string(c) + "; expected " +
                std::to_string(rows) + "x" + (cols >= 0 ? std::to_string(cols) : "N"));
  std::vector<double> v = yamlNumbers(path, n["data"], key + ".data");
  if (v.size() != static_cast<std::size_t>(r) * c)
    throw Error(path + ": " + key + ".data holds " + std::to_string(v.size()) + " numbers; rows x cols is " +
                std::to_string(r * c));
  if (cols_out)
    *cols_out = static_cast<int>(c);
  return v;
}

/*!
  \brief The text with YAML's compact block sequences indented under their key: PyYAML (Kalibr)
  writes `T_cn_cnm1:` and its `- [...]` rows at the same indentation, which is valid YAML that
  OpenCV's parser does not take. Each such sequence, with the lines of its items, is moved two
  spaces right; nothing else changes.
*/
std::string indentCompactSequences(const std::string &text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  const auto indentOf = [](const std::string &l) { return l.find_first_not_of(' '); };
  const auto isItem = [](const std::string &l, std::size_t at) {
    return at < l.size() && l[at] == '-' && (at + 1 == l.size() || l[at + 1] == ' ' || l[at + 1] == '\r');
  };
  for (std::size_t i = 0; i < lines.size(); ++i) {
    // A key whose value is on the following lines: `key:` (and maybe a comment).
    std::string l = lines[i];
    const std::size_t hash = l.find(" #");
    if (hash != std::string::npos)
      l.erase(hash);
    l = l.substr(0, l.find_last_not_of(" \t\r") + 1);
    const std::size_t k = indentOf(l);
    if (k == std::string::npos || l.back() != ':' || l[k] == '-' || l[k] == '#')
      continue;
    std::size_t j = i + 1;
    while (j < lines.size() && (indentOf(lines[j]) == std::string::npos || lines[j][indentOf(lines[j])] == '#'))
      ++j;
    if (j == lines.size() || indentOf(lines[j]) != k || !isItem(lines[j], k))
      continue;
    for (; j < lines.size(); ++j) {
      const std::size_t a = indentOf(lines[j]);
      if (a != std::string::npos && (a < k || (a == k && !isItem(lines[j], k))))
        break;
      if (a != std::string::npos)
        lines[j].insert(0, 2, ' ');
    }
  }
  std::string out;
  for (const auto &line : lines)
    out += line + "\n";
  return out;
}

/*!
  \brief Opens a YAML camera file of another dialect than OpenCV's with cv::FileStorage (after the
  checks of precheckOpenCv()) and returns its root, a map without a duplicated top-level key.
*/
cv::FileNode yamlRoot(const std::string &path, const std::string &raw, const std::string &what, cv::FileStorage &fs) {
  const std::string text = indentCompactSequences(raw);
  std::string content = text;
  if (trim(text).rfind("%YAML", 0) != 0)
    content = "%YAML:1.0\n---\n" + text; // OpenCV 4 insists on the YAML header
  precheckOpenCv(path, content, true);     // one document, keys in the first column, bounded nesting
  try {
    fs.open(content, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception &e) {
    throw Error(path + ": not valid YAML (" + oneLine(e.err) + ")");
  }
  if (!fs.isOpened())
    throw Error(path + ": not valid YAML");
  const cv::FileNode root = fs.root();
  if (!root.isMap())
    throw Error(path + ": not a " + what + " (its top level is not a map of keys)");
  std::vector<std::string> seen;
  for (const cv::FileNode kv : root) {
    const std::string key = kv.name();
    if (std::find(seen.begin(), seen.end(), key) != seen.end())
      throw Error(path + ": key " + key + " is given twice");
    seen.push_back(key);
  }
  return root;
}

/*!
  \brief OpenCV-order distortion coefficients (ROS plumb_bob / rational_polynomial): 0, 4, 5 or 8
  values, or more with zeros beyond the eighth (OpenCV's thin-prism and tilt terms, which ROS
  sometimes writes as 14 values), as OpenCV and ROS's image_geometry take them.
*/
std::vector<double> opencvOrderCoefficients(const std::string &path, const std::string &key,
                                            const std::string &model, std::vector<double> d) {
  if (d.size() > 8) {
    if (d.size() > 14)
      throw Error(path + ": " + key + " holds " + std::to_string(d.size()) + " coefficients for " + model +
                  " (expected 5, or 8 for rational_polynomial)");
    for (std::size_t i = 8; i < d.size(); ++i)
      if (d[i] != 0)
        throw Error(path + ": " + key + " coefficient " + std::to_string(i + 1) + " = " + numText(d[i]) +
                    " is not supported (OpenCV's thin-prism and tilt terms beyond k6 must be 0)");
    d.resize(8);
  }
  if (d.size() != 0 && d.size() != 4 && d.size() != 5 && d.size() != 8)
    throw Error(path + ": " + key + " holds " + std::to_string(d.size()) + " coefficients for " + model +
                " (expected 5: k1 k2 p1 p2 k3, or 8 for rational_polynomial: k1 k2 p1 p2 k3 k4 k5 k6)");
  return d;
}

const char *const kRosModels = "plumb_bob, rational_polynomial, equidistant";

CameraModel loadRosCameraInfo(const std::string &path, const std::string &text, const std::string &camera_name) {
  cv::FileStorage fs;
  const cv::FileNode root = yamlRoot(path, text, "ROS camera_info file", fs);
  for (const char *key : {"image_width", "image_height", "camera_matrix", "distortion_coefficients"})
    if (!present(root[key]))
      throw Error(path + ": missing " + key + " (ROS camera_info file)");
  const unsigned w = yamlSize(path, root["image_width"], "image_width");
  const unsigned h = yamlSize(path, root["image_height"], "image_height");
  if (!camera_name.empty()) {
    const cv::FileNode n = root["camera_name"];
    const std::string name = n.isString() ? trim(static_cast<std::string>(n)) : std::string();
    if (name != trim(camera_name))
      throw Error(path + ": camera_name is " + (name.empty() ? std::string("not given") : "'" + name + "'") +
                  ", not '" + camera_name + "' (a ROS camera_info file holds one camera; --camera-name may be left out)");
  }
  const std::vector<double> K = rosMatrix(path, root["camera_matrix"], "camera_matrix", 3, 3);
  double fx = 0, fy = 0, u0 = 0, v0 = 0;
  pinholeOf(path, "camera_matrix", K, fx, fy, u0, v0);
  // ROS's own parser assumes plumb_bob when the key is missing.
  const std::string model = present(root["distortion_model"])
                                ? yamlWord(path, root["distortion_model"], "distortion_model")
                                : std::string("plumb_bob");
  int n = 0;
  std::vector<double> D = rosMatrix(path, root["distortion_coefficients"], "distortion_coefficients", 1, -1, &n);
  // Read and checked, not used: a monocular pipeline on image_raw uses camera_matrix and the
  // distortion; the rectified camera (rectification_matrix, projection_matrix) is for stereo.
  if (present(root["rectification_matrix"]))
    rosMatrix(path, root["rectification_matrix"], "rectification_matrix", 3, 3);
  if (present(root["projection_matrix"]))
    rosMatrix(path, root["projection_matrix"], "projection_matrix", 3, 4);
  if (model == "equidistant") {
    if (D.size() != 4)
      throw Error(path + ": distortion_coefficients holds " + std::to_string(D.size()) +
                  " coefficients for equidistant (expected 4: k1 k2 k3 k4)");
    return makeCamera(path, "", [&] { return CameraModel::kannalaBrandt(fx, fy, u0, v0, D, w, h); });
  }
  if (model != "plumb_bob" && model != "rational_polynomial")
    throw Error(path + ": distortion_model '" + oneLine(model).substr(0, 64) + "' is not supported (known: " +
                kRosModels + ")");
  D = opencvOrderCoefficients(path, "distortion_coefficients", model, D);
  return makeCamera(path, "", [&] { return CameraModel::brown(fx, fy, u0, v0, D, w, h); });
}

/*! \brief True for a Kalibr camera key: cam0, cam1, ... */
bool isKalibrCameraKey(const std::string &k) {
  return k.size() > 3 && k.compare(0, 3, "cam") == 0 &&
         std::all_of(k.begin() + 3, k.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; });
}

CameraModel loadKalibr(const std::string &path, const std::string &text, const std::string &camera_name) {
  cv::FileStorage fs;
  const cv::FileNode root = yamlRoot(path, text, "Kalibr camchain file", fs);
  std::vector<std::string> names;
  for (const cv::FileNode kv : root)
    if (isKalibrCameraKey(kv.name()))
      names.push_back(kv.name());
  if (names.empty())
    throw Error(path + ": no cam0, cam1, ... key (Kalibr camchain file)");
  const std::string cam = camera_name.empty() ? std::string("cam0") : trim(camera_name);
  if (std::find(names.begin(), names.end(), cam) == names.end())
    throw Error(path + ": no camera " + cam + (camera_name.empty() ? " (the default); pick one with --camera-name" : "") +
                " (cameras: " + joinNames(names) + ")");
  const cv::FileNode c = root[cam];
  if (!c.isMap())
    throw Error(path + ": " + cam + " must be a map (camera_model, intrinsics, ...)");
  for (const char *key : {"camera_model", "intrinsics", "distortion_model", "resolution"})
    if (!present(c[key]))
      throw Error(path + ": missing " + cam + "." + key + " (Kalibr camchain file)");
  const std::string camera_model = yamlWord(path, c["camera_model"], cam + ".camera_model");
  if (camera_model != "pinhole")
    throw Error(path + ": " + cam + ".camera_model '" + oneLine(camera_model).substr(0, 64) +
                "' is not supported (only pinhole, with distortion_model radtan, equidistant or none)");
  const std::vector<double> in = yamlNumbers(path, c["intrinsics"], cam + ".intrinsics");
  if (in.size() != 4)
    throw Error(path + ": " + cam + ".intrinsics holds " + std::to_string(in.size()) +
                " numbers (expected 4: fu fv pu pv)");
  const cv::FileNode res = c["resolution"];
  if (!res.isSeq() || res.size() != 2)
    throw Error(path + ": " + cam + ".resolution must be [width, height]");
  const unsigned w = yamlSize(path, res[0], cam + ".resolution[0]");
  const unsigned h = yamlSize(path, res[1], cam + ".resolution[1]");
  const std::string model = yamlWord(path, c["distortion_model"], cam + ".distortion_model");
  const std::string key = cam + ".distortion_coeffs";
  std::vector<double> d;
  if (present(c["distortion_coeffs"]))
    d = yamlNumbers(path, c["distortion_coeffs"], key);
  if (model == "radtan" || model == "equidistant") {
    if (!present(c["distortion_coeffs"]))
      throw Error(path + ": missing " + key + " (Kalibr camchain file)");
    if (d.size() != 4)
      throw Error(path + ": " + key + " holds " + std::to_string(d.size()) + " coefficients for " + model +
                  " (expected 4: " + (model == "radtan" ? "k1 k2 r1 r2" : "k1 k2 k3 k4") + ")");
  } else if (model == "none") {
    if (std::any_of(d.begin(), d.end(), [](double x) { return x != 0; }))
      throw Error(path + ": " + key + " must be empty or zero for distortion_model none");
    d.clear();
  } else {
    throw Error(path + ": " + cam + ".distortion_model '" + oneLine(model).substr(0, 64) +
                "' is not supported (known: radtan, equidistant, none)");
  }
  if (model == "equidistant")
    return makeCamera(path, cam, [&] { return CameraModel::kannalaBrandt(in[0], in[1], in[2], in[3], d, w, h); });
  // radtan k1 k2 r1 r2 is OpenCV's k1 k2 p1 p2.
  return makeCamera(path, cam, [&] { return CameraModel::brown(in[0], in[1], in[2], in[3], d, w, h); });
}

/*! \brief A reader of the other YAML dialects, with OpenCV's exceptions as one-line errors. */
template <class Load> CameraModel readYamlDialect(const std::string &path, Load load) {
  try {
    return load();
  } catch (const Error &) {
    throw;
  } catch (const cv::Exception &e) {
    throw Error(path + ": OpenCV cannot read this camera file: " + oneLine(e.err));
  }
}

enum class Format { ViSPXml, OpenCvXml, OpenCvYaml, RosYaml, KalibrYaml, Unknown };

/*! \brief Offset of the line `key:` (the key in the first column), or npos. */
std::size_t topLevelKey(const std::string &t, const std::string &key) {
  for (std::size_t p = t.find(key); p != std::string::npos; p = t.find(key, p + 1)) {
    if (p != 0 && t[p - 1] != '\n')
      continue;
    const std::size_t c = t.find_first_not_of(" \t", p + key.size());
    if (c != std::string::npos && t[c] == ':')
      return p;
  }
  return std::string::npos;
}

/*!
  \brief Whether the value of the top-level `camera_matrix:` at `p` is a plain YAML map (ROS's
  `{rows, cols, data}`) rather than an OpenCV `!!opencv-matrix` or a sequence.
*/
bool cameraMatrixIsPlainMap(const std::string &t, std::size_t p) {
  const std::size_t colon = t.find(':', p);
  std::size_t eol = t.find('\n', colon);
  std::string rest = t.substr(colon + 1, (eol == std::string::npos ? t.size() : eol) - colon - 1);
  const std::size_t hash = rest.find(" #");
  if (hash != std::string::npos)
    rest.erase(hash);
  rest = trim(rest);
  if (!rest.empty())
    return rest[0] == '{';
  // The value starts on a following line: a map when its first line is `key: ...`.
  while (eol != std::string::npos) {
    const std::size_t b = eol + 1;
    eol = t.find('\n', b);
    const std::string line = trim(t.substr(b, (eol == std::string::npos ? t.size() : eol) - b));
    if (line.empty() || line[0] == '#')
      continue;
    return line[0] != '-' && line[0] != '[' && line[0] != '!' && line.find(':') != std::string::npos;
  }
  return false;
}

/*! \brief Whether a top-level key is a Kalibr camera (cam0, cam1, ...). */
bool hasKalibrCamera(const std::string &t) {
  for (std::size_t p = t.find("cam"); p != std::string::npos; p = t.find("cam", p + 1)) {
    if (p != 0 && t[p - 1] != '\n')
      continue;
    std::size_t q = p + 3;
    while (q < t.size() && std::isdigit(static_cast<unsigned char>(t[q])))
      ++q;
    if (q == p + 3)
      continue;
    q = t.find_first_not_of(" \t", q);
    if (q != std::string::npos && t[q] == ':')
      return true;
  }
  return false;
}

Format detectFormat(const std::string &text) {
  const std::string t = trim(text);
  const std::string nc = stripXmlComments(t);
  if (t.rfind('<', 0) == 0) {
    if (findTag(nc, "opencv_storage") != std::string::npos)
      return Format::OpenCvXml;
    if (findTag(nc, "root") != std::string::npos && findTag(nc, "camera") != std::string::npos)
      return Format::ViSPXml;
    return Format::Unknown;
  }
  // YAML: ROS camera_info when camera_matrix is a plain {rows, cols, data} map (OpenCV's reader
  // wants an !!opencv-matrix there), Kalibr when cam0, cam1, ... are top-level keys.
  const std::size_t km = topLevelKey(t, "camera_matrix");
  if (km != std::string::npos)
    return cameraMatrixIsPlainMap(t, km) ? Format::RosYaml : Format::OpenCvYaml;
  if (hasKalibrCamera(t))
    return Format::KalibrYaml;
  if (t.rfind("%YAML", 0) == 0)
    return Format::OpenCvYaml;
  if (topLevelKey(t, "camera_name") != std::string::npos || topLevelKey(t, "distortion_model") != std::string::npos)
    return Format::RosYaml; // without camera_matrix: its reader names what is missing
  return Format::Unknown;
}

/*!
  \brief Throws yawdepth::Error for a camera that parses but cannot be a real one: focal lengths
  outside 1e-3..1e6 px or with an aspect ratio beyond 10, an image side over 65535 px, a principal
  point more than half an image outside the image, or (image size known) a distortion that is not
  invertible over the image (not monotonic along a ray from the centre, Newton's inverse failing)
  or that maps the image to a field more than 10x wider or narrower than the pinhole would.
*/
void checkPlausible(const std::string &path, const CameraModel &c) {
  checkCameraPlausible(c, path);
}

} // namespace

void checkCameraPlausible(const CameraModel &c, const std::string &what) {
  auto fail = [&](const std::string &why) { throw Error(what + ": implausible camera: " + why); };
  auto num = [](double v) {
    std::ostringstream ss;
    ss.precision(6);
    ss << v;
    return ss.str();
  };
  for (const double f : {c.kx(), c.ky()})
    if (!(f >= 1e-3 && f <= 1e6))
      fail("focal length " + num(f) + " px (expected 1e-3 to 1e6)");
  if (c.kx() > 10 * c.ky() || c.ky() > 10 * c.kx())
    fail("focal lengths " + num(c.kx()) + " and " + num(c.ky()) + " px differ by more than 10x");
  constexpr unsigned kMaxSide = 65535;
  if (c.width() > kMaxSide || c.height() > kMaxSide)
    fail("image size " + std::to_string(c.width()) + "x" + std::to_string(c.height()) + " (at most 65535 a side)");
  const double w = c.width(), h = c.height();
  if (c.width() > 0 && c.height() > 0) {
    if (!(c.u0() >= -0.5 * w && c.u0() <= 1.5 * w && c.v0() >= -0.5 * h && c.v0() <= 1.5 * h))
      fail("principal point (" + num(c.u0()) + ", " + num(c.v0()) + ") far outside the " + std::to_string(c.width()) +
           "x" + std::to_string(c.height()) + " image");
  } else if (!(std::abs(c.u0()) <= kMaxSide && std::abs(c.v0()) <= kMaxSide)) {
    fail("principal point (" + num(c.u0()) + ", " + num(c.v0()) + ") beyond 65535 px");
  }
  if (c.distortion() == CameraModel::Distortion::None || c.width() == 0 || c.height() == 0)
    return;
  const bool fisheye = c.distortion() == CameraModel::Distortion::KannalaBrandt;
  constexpr double kPi = 3.14159265358979323846;
  // Fisheye: theta_d(theta) must increase from the centre to the image's farthest pixel (a
  // corner), or up to 90 degrees when the image reaches beyond (a field over 180 degrees, or
  // corners outside the lens's image circle). The pixels beyond 90 degrees are no failure of the
  // model: no normalised point holds their rays, so they do not undistort and are not used.
  double fisheye_rd90 = std::numeric_limits<double>::infinity(); // distorted radius at 90 degrees
  if (fisheye) {
    const std::vector<double> &k = c.kannalaBrandtCoefficients();
    const auto thetaD = [&](double t) {
      const double t2 = t * t;
      return t * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
    };
    double rd_max = 0;
    Eigen::Vector2d far_px(0, 0);
    for (const double u : {-0.5, w - 0.5})
      for (const double v : {-0.5, h - 0.5}) {
        const double rd = std::hypot((u - c.u0()) / c.kx(), (v - c.v0()) / c.ky());
        if (rd > rd_max) {
          rd_max = rd;
          far_px = Eigen::Vector2d(u, v);
        }
      }
    if (c.maxRayAngle() < kPi / 2 && thetaD(c.maxRayAngle()) <= rd_max)
      fail("the fisheye distortion is not monotonic between the image centre and pixel (" + num(far_px.x()) +
           ", " + num(far_px.y()) + "): theta_d(theta) stops increasing at " + num(c.maxRayAngle() * 180 / kPi) +
           " degrees from the optical axis, inside the image");
    fisheye_rd90 = thetaD(kPi / 2);
  }
  // Every pixel of a grid over the image (its border included) must undistort, and the ray
  // from the principal point to it must be monotonic: the distorted radius grows with the
  // undistorted one, with a positive Jacobian determinant all along. (Fisheye: the pixels within
  // 90 degrees of the axis; the field rule below for those within 80 degrees, since a pinhole's
  // field grows without bound toward 90.)
  constexpr int kNu = 17, kNv = 13, kSteps = 64;
  constexpr double kFisheyeFieldRuleAngle = 80 * kPi / 180;
  for (int j = 0; j < kNv; ++j) {
    for (int i = 0; i < kNu; ++i) {
      const Eigen::Vector2d uv(-0.5 + (w) * i / (kNu - 1), -0.5 + (h) * j / (kNv - 1));
      const Eigen::Vector2d md((uv.x() - c.u0()) / c.kx(), (uv.y() - c.v0()) / c.ky());
      if (fisheye && md.norm() >= fisheye_rd90)
        continue; // a ray at 90 degrees or more
      Eigen::Vector2d m;
      if (!c.undistort(uv, m) || !m.allFinite())
        fail("the distortion cannot be inverted at pixel (" + num(uv.x()) + ", " + num(uv.y()) + ")");
      const double rd = md.norm(), ru = m.norm();
      const bool field_rule = !fisheye || std::atan(ru) <= kFisheyeFieldRuleAngle;
      if (field_rule && rd > 1e-3 && (ru > 10 * rd || ru < 0.1 * rd))
        fail("the distortion maps pixel (" + num(uv.x()) + ", " + num(uv.y()) + ") " + num(ru / rd) +
             "x as far from the centre as the pinhole would (expected 0.1 to 10)");
      const Eigen::Vector2d dir = rd > 1e-12 ? Eigen::Vector2d(md / rd) : Eigen::Vector2d(1, 0);
      double last = 0;
      for (int k = 1; k <= kSteps; ++k) {
        Eigen::Matrix2d J;
        const Eigen::Vector2d d = c.distortNormalized(m * (double(k) / kSteps), &J);
        const double r = d.dot(dir);
        if (!(J.determinant() > 0) || (rd > 1e-3 && !(r > last)))
          fail("the distortion is not monotonic between the image centre and pixel (" + num(uv.x()) + ", " +
               num(uv.y()) + ")");
        last = r;
      }
    }
  }
}

CameraModel loadCameraFile(const std::string &path, const std::string &camera_name) {
  try {
    const std::string text = readWholeFile(path);
    if (trim(text).empty())
      throw Error(path + ": empty camera file");
    // Text only: OpenCV's in-memory parsers stop at a NUL byte and then dereference a null
    // pointer (found by fuzzing).
    if (text.find('\0') != std::string::npos)
      throw Error(path + ": not a camera file (it holds a NUL byte)");
    switch (detectFormat(text)) {
    case Format::ViSPXml: {
      CameraModel c = loadVispXml(path, text, camera_name);
      checkPlausible(path, c);
      return c;
    }
    case Format::OpenCvXml:
    case Format::OpenCvYaml: {
      CameraModel c = loadOpenCv(path, text, detectFormat(text) == Format::OpenCvYaml);
      checkPlausible(path, c);
      return c;
    }
    case Format::RosYaml: {
      CameraModel c = readYamlDialect(path, [&] { return loadRosCameraInfo(path, text, camera_name); });
      checkPlausible(path, c);
      return c;
    }
    case Format::KalibrYaml: {
      CameraModel c = readYamlDialect(path, [&] { return loadKalibr(path, text, camera_name); });
      checkPlausible(path, c);
      return c;
    }
    case Format::Unknown:
      break;
    }
    throw Error(path + ": not a camera file (expected a ViSP camera XML <root><camera>, an OpenCV "
                       "YAML/XML with camera_matrix, a ROS camera_info YAML or a Kalibr camchain YAML)");
  } catch (const Error &) {
    throw;
  } catch (const std::exception &e) {
    throw Error(path + ": cannot read camera file: " + oneLine(e.what()));
  } catch (...) {
    throw Error(path + ": cannot read camera file");
  }
}

std::string cameraYamlText(const CameraModel &camera) {
  const std::string path = "camera file";
  // ViSP's kud model is Brown with k1 = kud, so every model has an exact OpenCV form; the fisheye
  // model is cv::fisheye's, named by a distortion_model key (OpenCV's YAML has no model word).
  const bool fisheye = camera.distortion() == CameraModel::Distortion::KannalaBrandt;
  std::vector<double> d;
  if (fisheye) {
    d = camera.kannalaBrandtCoefficients();
  } else if (camera.distortion() != CameraModel::Distortion::None) {
    const std::vector<double> &k = camera.brownCoefficients();
    std::size_t n = 4;
    if (k[5] != 0 || k[6] != 0 || k[7] != 0)
      n = 8;
    else if (k[4] != 0)
      n = 5;
    d.assign(k.begin(), k.begin() + static_cast<std::ptrdiff_t>(n));
  }
  // Serialise in memory (OpenCV would log to stderr when it cannot open a path), then write.
  std::string text;
  try {
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened())
      throw Error(path + ": cannot write camera file (OpenCV FileStorage failed)");
    fs << "image_width" << static_cast<int>(camera.width());
    fs << "image_height" << static_cast<int>(camera.height());
    const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.kx(), 0, camera.u0(), 0, camera.ky(), camera.v0(), 0, 0, 1);
    fs << "camera_matrix" << K;
    if (fisheye)
      fs << "distortion_model" << "equidistant";
    if (d.empty())
      fs << "distortion_coefficients" << cv::Mat(1, 0, CV_64F);
    else
      fs << "distortion_coefficients" << cv::Mat(1, static_cast<int>(d.size()), CV_64F, d.data()).clone();
    text = fs.releaseAndGetString();
  } catch (const Error &) {
    throw;
  } catch (const cv::Exception &e) {
    throw Error(path + ": cannot write camera file: " + oneLine(e.err));
  } catch (const std::exception &e) {
    throw Error(path + ": cannot write camera file: " + oneLine(e.what()));
  }
  return text;
}

void saveCameraYaml(const std::string &path, const CameraModel &camera) {
  writeFileAtomically(path, cameraYamlText(camera));
}

namespace {

/*! \brief Shortest text that reads back as the same double, always with a '.' in its mantissa
    (YAML 1.1 readers such as PyYAML take "1e-05" or "1" for a string or an integer, and ROS 2's
    typed messages refuse an integer for a float). */
std::string floatText(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string t(buf, r.ptr);
  if (t.find('.') == std::string::npos) {
    const std::size_t e = t.find('e');
    t.insert(e == std::string::npos ? t.size() : e, ".0");
  }
  return t;
}

/*! \brief A YAML flow sequence of a row-major matrix, one row a line (as ROS camera_calibration
    writes it), continuation lines indented by `indent` spaces. */
std::string flowMatrix(const std::vector<double> &v, std::size_t cols, std::size_t indent) {
  std::string t = "[";
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i > 0)
      t += (cols > 0 && i % cols == 0) ? ",\n" + std::string(indent, ' ') : std::string(", ");
    t += floatText(v[i]);
  }
  return t + "]";
}

/*! \brief A camera name as a YAML scalar: plain when it is made of letters, digits and _ - . /,
    else double-quoted with escapes. */
std::string yamlName(const std::string &name) {
  const bool plain = !name.empty() && std::isalnum(static_cast<unsigned char>(name[0])) &&
                     std::all_of(name.begin(), name.end(), [](char c) {
                       return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' ||
                              c == '/';
                     });
  if (plain)
    return name;
  std::string t = "\"";
  for (const char c : name) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      t += '\\';
      t += c;
    } else if (u < 0x20 || u == 0x7f) {
      const char *hex = "0123456789abcdef";
      t += "\\x";
      t += hex[u >> 4];
      t += hex[u & 15];
    } else {
      t += c;
    }
  }
  return t + "\"";
}

} // namespace

std::string rosCameraInfoYamlText(const CameraModel &camera, const std::string &camera_name) {
  std::string model = "plumb_bob";
  std::vector<double> d(5, 0.0);
  switch (camera.distortion()) {
  case CameraModel::Distortion::KannalaBrandt:
    model = "equidistant";
    d = camera.kannalaBrandtCoefficients();
    break;
  case CameraModel::Distortion::None:
    break;
  case CameraModel::Distortion::Brown:
  case CameraModel::Distortion::ViSP: { // ViSP's kud is plumb_bob with k1 = kud
    const std::vector<double> &k = camera.brownCoefficients();
    const bool rational = k[5] != 0 || k[6] != 0 || k[7] != 0;
    model = rational ? "rational_polynomial" : "plumb_bob";
    d.assign(k.begin(), k.begin() + (rational ? 8 : 5));
    break;
  }
  }
  const std::vector<double> K = {camera.kx(), 0, camera.u0(), 0, camera.ky(), camera.v0(), 0, 0, 1};
  const std::vector<double> R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<double> P = {camera.kx(), 0, camera.u0(), 0, 0, camera.ky(), camera.v0(), 0, 0, 0, 1, 0};
  for (const double v : K)
    if (!std::isfinite(v))
      throw Error("ROS camera_info file: the camera has a non-finite intrinsic");
  std::ostringstream o;
  o << "image_width: " << camera.width() << "\n"
    << "image_height: " << camera.height() << "\n"
    << "camera_name: " << yamlName(camera_name.empty() ? std::string("camera") : camera_name) << "\n"
    << "camera_matrix:\n  rows: 3\n  cols: 3\n  data: " << flowMatrix(K, 3, 9) << "\n"
    << "distortion_model: " << model << "\n"
    << "distortion_coefficients:\n  rows: 1\n  cols: " << d.size() << "\n  data: " << flowMatrix(d, 0, 0) << "\n"
    << "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: " << flowMatrix(R, 3, 9) << "\n"
    << "projection_matrix:\n  rows: 3\n  cols: 4\n  data: " << flowMatrix(P, 4, 9) << "\n";
  return o.str();
}

void saveRosCameraInfoYaml(const std::string &path, const CameraModel &camera, const std::string &camera_name) {
  writeFileAtomically(path, rosCameraInfoYamlText(camera, camera_name));
}

} // namespace yawdepth
