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
#include <iostream>
#include <mutex>
#include <opencv2/core.hpp>
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

CameraModel loadOpenCv(const std::string &path, const std::string &text, bool yaml) {
  std::string content = text;
  if (yaml && trim(text).rfind("%YAML", 0) != 0)
    content = "%YAML:1.0\n---\n" + text; // OpenCV 4 insists on the YAML header
  precheckOpenCv(path, content, yaml);
  std::vector<double> K, D;
  int kr = 0, kc = 0, dr = 0, dc = 0;
  unsigned w = 0, h = 0;
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
  const double fx = K[0], skew = K[1], u0 = K[2], fy = K[4], v0 = K[5];
  if (std::abs(K[3]) > 0 || std::abs(K[6]) > 0 || std::abs(K[7]) > 0 || std::abs(K[8] - 1) > 1e-12)
    throw Error(path + ": camera_matrix last row must be [0 0 1] and K(1,0) must be 0");
  if (std::abs(skew) > 1e-9 * std::max(1.0, std::abs(fx)))
    throw Error(path + ": camera_matrix has a non-zero skew, which is not supported");
  if (!D.empty() && dr != 1 && dc != 1)
    throw Error(path + ": distortion_coefficients must be a 1xN or Nx1 matrix");
  try {
    return CameraModel::brown(fx, fy, u0, v0, D, w, h);
  } catch (const Error &e) {
    throw Error(path + ": " + e.what());
  }
}

enum class Format { ViSPXml, OpenCvXml, OpenCvYaml, Unknown };

Format detectFormat(const std::string &text) {
  const std::string t = trim(text);
  const std::string nc = stripXmlComments(t);
  if (t.rfind("%YAML", 0) == 0)
    return Format::OpenCvYaml;
  if (t.rfind('<', 0) == 0) {
    if (findTag(nc, "opencv_storage") != std::string::npos)
      return Format::OpenCvXml;
    if (findTag(nc, "root") != std::string::npos && findTag(nc, "camera") != std::string::npos)
      return Format::ViSPXml;
    return Format::Unknown;
  }
  if (t.rfind("camera_matrix:", 0) == 0 || t.find("\ncamera_matrix:") != std::string::npos)
    return Format::OpenCvYaml;
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
  // Every pixel of a grid over the image (its border included) must undistort, and the ray
  // from the principal point to it must be monotonic: the distorted radius grows with the
  // undistorted one, with a positive Jacobian determinant all along.
  constexpr int kNu = 17, kNv = 13, kSteps = 64;
  for (int j = 0; j < kNv; ++j) {
    for (int i = 0; i < kNu; ++i) {
      const Eigen::Vector2d uv(-0.5 + (w) * i / (kNu - 1), -0.5 + (h) * j / (kNv - 1));
      const Eigen::Vector2d md((uv.x() - c.u0()) / c.kx(), (uv.y() - c.v0()) / c.ky());
      Eigen::Vector2d m;
      if (!c.undistort(uv, m) || !m.allFinite())
        fail("the distortion cannot be inverted at pixel (" + num(uv.x()) + ", " + num(uv.y()) + ")");
      const double rd = md.norm(), ru = m.norm();
      if (rd > 1e-3 && (ru > 10 * rd || ru < 0.1 * rd))
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
    case Format::Unknown:
      break;
    }
    throw Error(path + ": not a camera file (expected a ViSP camera XML <root><camera>, or an OpenCV "
                       "YAML/XML with camera_matrix)");
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
  // ViSP's kud model is Brown with k1 = kud, so every model has an exact OpenCV form.
  std::vector<double> d;
  if (camera.distortion() != CameraModel::Distortion::None) {
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

} // namespace yawdepth
