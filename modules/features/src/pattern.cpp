/*!
  \file pattern.cpp
  \brief PatternSpec text form, board geometry, reflectance (chessboard squares, AprilTag bitmaps
  from libapriltag).
*/
#include <yawdepth/features/pattern.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <yawdepth/error.h>

extern "C" {
#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>
#include <apriltag/tagCircle21h7.h>
#include <apriltag/tagCircle49h12.h>
#include <apriltag/tagCustom48h12.h>
#include <apriltag/tagStandard41h12.h>
#include <apriltag/tagStandard52h13.h>
}

namespace yawdepth {

namespace {

/*! \brief Shortest text of `v` that reads back to the same double (at least 12 significant digits). */
std::string num(double v) {
  for (int p = 12; p <= 17; ++p) {
    std::ostringstream s;
    s.precision(p);
    s << v;
    if (std::strtod(s.str().c_str(), nullptr) == v || p == 17)
      return s.str();
  }
  return std::to_string(v);
}

std::vector<std::string> split(const std::string &s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

std::string lower(std::string s) {
  for (char &c : s)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/*! \brief Parse a whole string as a positive integer; false otherwise. */
bool parseInt(const std::string &s, int &out) {
  if (s.empty() || s.size() > 6)
    return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c)))
      return false;
  out = std::stoi(s);
  return true;
}

/*! \brief Parse a whole string as a finite double; false otherwise. */
bool parseDouble(const std::string &s, double &out) {
  if (s.empty() || std::isspace(static_cast<unsigned char>(s.front())))
    return false;
  char *end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(out);
}

const char *kFamilies[] = {"36h11", "25h9", "16h5", "circle21h7", "circle49h12",
                           "custom48h12", "standard41h12", "standard52h13"};

/*! \brief The bitmaps of one family, from libapriltag's apriltag_to_image(), cached for the process. */
struct FamilyBitmaps {
  int ncodes = 0;
  int total_width = 0;     //!< bitmap side (cells), incl. the outer ring
  int width_at_border = 0; //!< side of the detected border square (cells) = tag_size
  std::vector<unsigned char> bits; //!< ncodes * total_width^2, 1 white, 0 black, row-major
};

FamilyBitmaps makeBitmaps(apriltag_family_t *fam) {
  FamilyBitmaps b;
  b.ncodes = static_cast<int>(fam->ncodes);
  b.width_at_border = fam->width_at_border;
  b.total_width = fam->total_width;
  const int n = b.total_width * b.total_width;
  b.bits.assign(static_cast<std::size_t>(b.ncodes) * n, 1);
  for (int id = 0; id < b.ncodes; ++id) {
    image_u8_t *im = apriltag_to_image(fam, id);
    if (!im)
      continue;
    for (int y = 0; y < std::min(im->height, b.total_width); ++y)
      for (int x = 0; x < std::min(im->width, b.total_width); ++x)
        b.bits[static_cast<std::size_t>(id) * n + static_cast<std::size_t>(y) * b.total_width + x] = im->buf[y * im->stride + x] >= 128 ? 1 : 0;
    // image_u8_destroy() is not exported by Debian's libapriltag.so (it lives in
    // libapriltag-utils); the image is two malloc'ed blocks, as image_u8_create() makes them.
    std::free(im->buf);
    std::free(im);
  }
  return b;
}

template <typename Create, typename Destroy> FamilyBitmaps withFamily(Create create, Destroy destroy) {
  apriltag_family_t *fam = create();
  if (!fam)
    throw Error("apriltag: libapriltag could not create the tag family");
  FamilyBitmaps b;
  try {
    b = makeBitmaps(fam);
  } catch (...) {
    destroy(fam);
    throw;
  }
  destroy(fam);
  return b;
}

/*! \brief Bitmaps of a family (normalised name), built once per process; thread-safe. */
const FamilyBitmaps &familyBitmaps(const std::string &family) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<FamilyBitmaps>> cache;
  // Fast path without the lock: the last family this thread used.
  thread_local std::string last_name;
  thread_local const FamilyBitmaps *last = nullptr;
  if (last && last_name == family)
    return *last;
  const std::string name = normalizeAprilTagFamily(family);
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(name);
  if (it == cache.end()) {
    FamilyBitmaps b;
    if (name == "36h11")
      b = withFamily(tag36h11_create, tag36h11_destroy);
    else if (name == "25h9")
      b = withFamily(tag25h9_create, tag25h9_destroy);
    else if (name == "16h5")
      b = withFamily(tag16h5_create, tag16h5_destroy);
    else if (name == "circle21h7")
      b = withFamily(tagCircle21h7_create, tagCircle21h7_destroy);
    else if (name == "circle49h12")
      b = withFamily(tagCircle49h12_create, tagCircle49h12_destroy);
    else if (name == "custom48h12")
      b = withFamily(tagCustom48h12_create, tagCustom48h12_destroy);
    else if (name == "standard41h12")
      b = withFamily(tagStandard41h12_create, tagStandard41h12_destroy);
    else if (name == "standard52h13")
      b = withFamily(tagStandard52h13_create, tagStandard52h13_destroy);
    else
      throw Error("apriltag: unknown family '" + family + "'");
    it = cache.emplace(name, std::make_unique<FamilyBitmaps>(std::move(b))).first;
  }
  last_name = family;
  last = it->second.get();
  return *last;
}

} // namespace

std::string normalizeAprilTagFamily(const std::string &name) {
  std::string f = lower(name);
  if (f.rfind("tag", 0) == 0)
    f = f.substr(3);
  for (const char *k : kFamilies)
    if (f == k)
      return f;
  std::string list;
  for (const char *k : kFamilies)
    list += std::string(list.empty() ? "" : ", ") + k;
  throw Error("pattern: unknown AprilTag family '" + name + "' (known: " + list + ")");
}

AprilTagFamilyInfo aprilTagFamilyInfo(const std::string &family) {
  const FamilyBitmaps &b = familyBitmaps(family);
  AprilTagFamilyInfo info;
  info.ncodes = b.ncodes;
  info.total_width = b.total_width;
  info.width_at_border = b.width_at_border;
  return info;
}

PatternSpec PatternSpec::parse(const std::string &text) {
  const std::string usage = "pattern '" + text +
                            "': expected chessboard:COLSxROWS:SQUARE or apriltag:FAMILY:SIZE "
                            "(e.g. chessboard:5x4:0.02, apriltag:36h11:0.05)";
  const std::vector<std::string> parts = split(text, ':');
  if (parts.size() != 3)
    throw Error(usage);
  const std::string kind = lower(parts[0]);
  PatternSpec p;
  if (kind == "chessboard") {
    p.kind = Kind::Chessboard;
    std::string dims = lower(parts[1]);
    const std::size_t x = dims.find('x');
    if (x == std::string::npos || !parseInt(dims.substr(0, x), p.cols) || !parseInt(dims.substr(x + 1), p.rows))
      throw Error(usage);
    if (p.cols < 3 || p.rows < 3)
      throw Error("pattern '" + text + "': a chessboard needs at least 3x3 inner corners");
    if (p.cols > 1000 || p.rows > 1000)
      throw Error("pattern '" + text + "': too many inner corners (at most 1000x1000)");
    if (!parseDouble(parts[2], p.square))
      throw Error(usage);
    if (!(p.square > 0))
      throw Error("pattern '" + text + "': the square size must be > 0 (metres)");
  } else if (kind == "apriltag") {
    p.kind = Kind::AprilTag;
    p.family = normalizeAprilTagFamily(parts[1]);
    if (!parseDouble(parts[2], p.tag_size))
      throw Error(usage);
    if (!(p.tag_size > 0))
      throw Error("pattern '" + text + "': the tag size must be > 0 (metres)");
  } else {
    throw Error(usage);
  }
  return p;
}

std::string PatternSpec::toString() const {
  if (kind == Kind::Chessboard)
    return "chessboard:" + std::to_string(cols) + "x" + std::to_string(rows) + ":" + num(square);
  return "apriltag:" + family + ":" + num(tag_size);
}

namespace {

/*! \brief The default or given margin (m). */
double boardMargin(const BoardLayout &b) {
  if (b.margin > 0)
    return b.margin;
  if (b.pattern.kind == PatternSpec::Kind::Chessboard)
    return b.pattern.square;
  // AprilTag: the bitmap's ring outside the border square plus one cell (1/4 tag for 36h11).
  const FamilyBitmaps &f = familyBitmaps(b.pattern.family);
  const double cell = b.pattern.tag_size / f.width_at_border;
  return cell * (0.5 * (f.total_width - f.width_at_border) + 1.0);
}

void checkLayout(const BoardLayout &b) {
  if (b.pattern.kind == PatternSpec::Kind::Chessboard) {
    if (b.pattern.cols < 1 || b.pattern.rows < 1 || !(b.pattern.square > 0))
      throw Error("board: invalid chessboard " + b.pattern.toString());
    if (!(b.outer_square >= 0 && b.outer_square <= b.pattern.square))
      throw Error("board: the outer squares' width must be 0 (full) to one square");
  } else {
    if (!(b.pattern.tag_size > 0) || b.tags_x < 1 || b.tags_y < 1 || !(b.gap >= 0) || b.first_tag_id < 0)
      throw Error("board: invalid AprilTag layout (tag size > 0, tags_x, tags_y >= 1, gap >= 0, first id >= 0)");
    const FamilyBitmaps &f = familyBitmaps(b.pattern.family);
    if (static_cast<long>(b.first_tag_id) + static_cast<long>(b.tags_x) * b.tags_y > f.ncodes)
      throw Error("board: tag ids " + std::to_string(b.first_tag_id) + ".." +
                  std::to_string(static_cast<long>(b.first_tag_id) + static_cast<long>(b.tags_x) * b.tags_y - 1) +
                  " exceed family " + b.pattern.family + " (" + std::to_string(f.ncodes) + " codes)");
  }
  if (!(b.margin >= 0) || !std::isfinite(b.margin))
    throw Error("board: the margin must be >= 0");
}

} // namespace

std::vector<std::pair<long, Eigen::Vector3d>> BoardLayout::features() const {
  checkLayout(*this);
  std::vector<std::pair<long, Eigen::Vector3d>> out;
  if (pattern.kind == PatternSpec::Kind::Chessboard) {
    for (int r = 0; r < pattern.rows; ++r)
      for (int c = 0; c < pattern.cols; ++c)
        out.emplace_back(static_cast<long>(r) * pattern.cols + c,
                         Eigen::Vector3d(c * pattern.square, r * pattern.square, 0.0));
    return out;
  }
  const double s = pattern.tag_size, pitch = s + gap;
  for (int r = 0; r < tags_y; ++r)
    for (int c = 0; c < tags_x; ++c) {
      const int id = first_tag_id + r * tags_x + c;
      const double x0 = c * pitch, y0 = r * pitch;
      out.emplace_back(aprilTagFeatureId(id), Eigen::Vector3d(x0 + 0.5 * s, y0 + 0.5 * s, 0.0));
      // ViSP's polygon order (libapriltag's): bottom-left, bottom-right, top-right, top-left of the
      // tag's own bitmap (board Y down).
      out.emplace_back(aprilTagFeatureId(id, 0), Eigen::Vector3d(x0, y0 + s, 0.0));
      out.emplace_back(aprilTagFeatureId(id, 1), Eigen::Vector3d(x0 + s, y0 + s, 0.0));
      out.emplace_back(aprilTagFeatureId(id, 2), Eigen::Vector3d(x0 + s, y0, 0.0));
      out.emplace_back(aprilTagFeatureId(id, 3), Eigen::Vector3d(x0, y0, 0.0));
    }
  return out;
}

Eigen::Vector4d BoardLayout::extent() const {
  checkLayout(*this);
  const double m = boardMargin(*this);
  if (pattern.kind == PatternSpec::Kind::Chessboard) {
    const double s = pattern.square, o = outer_square > 0 ? outer_square : s;
    return Eigen::Vector4d(-o - m, -o - m, (pattern.cols - 1) * s + o + m, (pattern.rows - 1) * s + o + m);
  }
  const double pitch = pattern.tag_size + gap;
  return Eigen::Vector4d(-m, -m, tags_x * pitch - gap + m, tags_y * pitch - gap + m);
}

double BoardLayout::reflectance(double X, double Y) const {
  if (!std::isfinite(X) || !std::isfinite(Y))
    return -1;
  if (pattern.kind == PatternSpec::Kind::Chessboard) {
    const double s = pattern.square, o = outer_square > 0 ? outer_square : s;
    const double m = margin > 0 ? margin : s;
    const double xmax = (pattern.cols - 1) * s + o, ymax = (pattern.rows - 1) * s + o;
    if (X < -o - m || Y < -o - m || X > xmax + m || Y > ymax + m)
      return -1;
    if (X < -o || Y < -o || X >= xmax || Y >= ymax)
      return 1; // white margin
    const long i = static_cast<long>(std::floor(X / s)), j = static_cast<long>(std::floor(Y / s));
    return ((i + j) % 2 == 0) ? 0.0 : 1.0; // square (-1, -1) beyond corner 0 is black
  }
  const FamilyBitmaps &f = familyBitmaps(pattern.family);
  const double s = pattern.tag_size, pitch = s + gap;
  const double m = boardMargin(*this);
  if (X < -m || Y < -m || X > tags_x * pitch - gap + m || Y > tags_y * pitch - gap + m)
    return -1;
  const double cell = s / f.width_at_border;
  const double off = 0.5 * (f.total_width - f.width_at_border); // cells outside the border square
  const int c0 = static_cast<int>(std::floor(X / pitch)), r0 = static_cast<int>(std::floor(Y / pitch));
  // The bitmap of a tag may reach into the neighbouring pitch cell (rings outside the border).
  for (int r = r0 - 1; r <= r0 + 1; ++r) {
    if (r < 0 || r >= tags_y)
      continue;
    for (int c = c0 - 1; c <= c0 + 1; ++c) {
      if (c < 0 || c >= tags_x)
        continue;
      const double cx = (X - c * pitch) / cell + off, cy = (Y - r * pitch) / cell + off;
      if (cx < 0 || cy < 0 || cx >= f.total_width || cy >= f.total_width)
        continue;
      const int id = first_tag_id + r * tags_x + c;
      if (id >= f.ncodes)
        return 1;
      const int ix = std::min(static_cast<int>(cx), f.total_width - 1);
      const int iy = std::min(static_cast<int>(cy), f.total_width - 1);
      return f.bits[static_cast<std::size_t>(id) * f.total_width * f.total_width + static_cast<std::size_t>(iy) * f.total_width + ix];
    }
  }
  return 1;
}

} // namespace yawdepth
