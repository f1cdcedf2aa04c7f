#include <yawdepth/report/board_report.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

#include "figure_support.h"

namespace yawdepth {

using report_detail::text;

Eigen::Vector3d BoardMetrics::stats(const std::vector<BlockLength> &v)
{
  if (v.empty())
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double lo = v.front().length, hi = lo, sum = 0;
  for (const BlockLength &b : v) {
    lo = std::min(lo, b.length);
    hi = std::max(hi, b.length);
    sum += b.length;
  }
  return Eigen::Vector3d(lo, hi, sum / static_cast<double>(v.size()));
}

namespace {

const MotionSample &sampleOf(const std::vector<MotionSample> &motion, long frame)
{
  const long row = rowOfFrame(motion, frame);
  if (row < 0)
    throw Error("report: frame " + std::to_string(frame) + " is not in the motion log");
  return motion[static_cast<std::size_t>(row)];
}

/* Neighbour pairs of the pattern: (horizontal, vertical). */
void neighbours(const PatternSpec &p, std::vector<std::pair<long, long>> &h, std::vector<std::pair<long, long>> &v,
                const std::map<long, BoardPoint> &pts)
{
  if (p.kind == PatternSpec::Kind::Chessboard) {
    for (int r = 0; r < p.rows; ++r)
      for (int c = 0; c < p.cols; ++c) {
        const long id = static_cast<long>(r) * p.cols + c;
        if (c + 1 < p.cols)
          h.emplace_back(id, id + 1);
        if (r + 1 < p.rows)
          v.emplace_back(id, id + p.cols);
      }
    return;
  }
  // AprilTag: the four edges of every tag seen (corner ids 5t+1..5t+4, consecutive corners).
  std::map<long, int> tags;
  for (const auto &kv : pts)
    if (kv.first % 5 != 0)
      ++tags[kv.first / 5];
  for (const auto &kv : tags) {
    const long b = 5 * kv.first;
    h.emplace_back(b + 1, b + 2);
    v.emplace_back(b + 2, b + 3);
    h.emplace_back(b + 4, b + 3);
    v.emplace_back(b + 1, b + 4);
  }
}

std::string mm(double metres, int decimals = 2)
{
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, metres * 1000.0);
  return buf;
}

/* The valid measured points of the board in the world frame, by id (AprilTag centres are not on
   the block grid: left out). */
std::map<long, BoardPoint> boardPointsInWorld(const PatternSpec &pattern, const YawRig &rig,
                                              const std::vector<MotionSample> &motion,
                                              const std::vector<std::pair<long, PointEstimate>> &rows)
{
  std::map<long, BoardPoint> pts;
  for (const auto &[id, e] : rows) {
    if (!e.ok())
      continue;
    if (pattern.kind == PatternSpec::Kind::AprilTag && id % 5 == 0)
      continue; // tag centres are not on the block grid
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    fromVisp(wMc(rig, sampleOf(motion, e.frame)), R, t);
    BoardPoint p;
    p.id = id;
    p.frame = e.frame;
    p.c_P = e.c_P;
    p.w_P = R * e.c_P + t;
    pts[id] = p;
  }
  return pts;
}

/* The blocks of the pairs whose two points were measured, with their lengths, into `out`. */
void blockLengths(const std::vector<std::pair<long, long>> &pairs, const std::map<long, BoardPoint> &pts,
                  std::vector<BlockLength> &out)
{
  for (const auto &[a, b] : pairs) {
    const auto ia = pts.find(a), ib = pts.find(b);
    if (ia != pts.end() && ib != pts.end())
      out.push_back({a, b, (ia->second.w_P - ib->second.w_P).norm()});
  }
}

/* The plane through m.points (centroid, direction of least spread), each point's distance to it
   and the points' depth range. */
void fitBoardPlane(BoardMetrics &m)
{
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const BoardPoint &p : m.points)
    c += p.w_P;
  c /= static_cast<double>(m.points.size());
  Eigen::MatrixXd A(m.points.size(), 3);
  for (std::size_t i = 0; i < m.points.size(); ++i)
    A.row(static_cast<Eigen::Index>(i)) = (m.points[i].w_P - c).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinV);
  m.plane_normal = svd.matrixV().col(2).normalized();
  m.plane_point = c;
  m.min_depth = std::numeric_limits<double>::infinity();
  m.max_depth = -std::numeric_limits<double>::infinity();
  for (const BoardPoint &p : m.points) {
    const double d = m.plane_normal.dot(p.w_P - c);
    m.plane_distance.push_back(d);
    m.max_plane_distance = std::max(m.max_plane_distance, std::abs(d));
    m.min_depth = std::min(m.min_depth, p.c_P.z());
    m.max_depth = std::max(m.max_depth, p.c_P.z());
  }
}

/* Chessboard: the nominal board (the layout's corners by id) fitted to the measured corners: the
   board's pose, scale and fit RMS (m.has_board_pose when at least 3 corners match). */
void fitNominalBoard(const PatternSpec &pattern, BoardMetrics &m)
{
  if (pattern.kind != PatternSpec::Kind::Chessboard || m.points.size() < 3)
    return;
  BoardLayout layout;
  layout.pattern = pattern;
  const auto features = layout.features();
  const std::map<long, Eigen::Vector3d> board(features.begin(), features.end());
  Eigen::Matrix3Xd nominal(3, m.points.size()), measured(3, m.points.size());
  Eigen::Index n = 0;
  for (const BoardPoint &q : m.points) {
    const auto it = board.find(q.id);
    if (it == board.end())
      continue;
    nominal.col(n) = it->second;
    measured.col(n++) = q.w_P;
  }
  nominal.conservativeResize(3, n);
  measured.conservativeResize(3, n);
  if (n < 3)
    return;
  const Eigen::Matrix4d T = Eigen::umeyama(nominal, measured, false);
  const Eigen::Matrix4d S = Eigen::umeyama(nominal, measured, true);
  m.w_R_o = T.topLeftCorner<3, 3>();
  m.w_t_o = T.topRightCorner<3, 1>();
  m.board_scale = S.topLeftCorner<3, 3>().col(0).norm();
  const Eigen::Matrix3Xd fitted = (m.w_R_o * nominal).colwise() + m.w_t_o;
  m.board_fit_rms = std::sqrt((fitted - measured).colwise().squaredNorm().mean());
  m.has_board_pose = m.w_R_o.allFinite() && m.w_t_o.allFinite() && std::isfinite(m.board_scale);
}

} // namespace

BoardMetrics boardMetrics(const PatternSpec &pattern, const YawRig &rig, const std::vector<MotionSample> &motion,
                          const std::vector<std::pair<long, PointEstimate>> &rows)
{
  BoardMetrics m;
  m.nominal = pattern.kind == PatternSpec::Kind::Chessboard ? pattern.square : pattern.tag_size;
  const std::map<long, BoardPoint> pts = boardPointsInWorld(pattern, rig, motion, rows);
  if (pts.size() < 3)
    throw Error("report: fewer than 3 valid points of the board were measured");
  for (const auto &kv : pts)
    m.points.push_back(kv.second);

  std::vector<std::pair<long, long>> h, v;
  neighbours(pattern, h, v, pts);
  blockLengths(h, pts, m.horizontal);
  blockLengths(v, pts, m.vertical);
  fitBoardPlane(m);
  fitNominalBoard(pattern, m);
  return m;
}

double BoardMetrics::quantile(double q) const
{
  std::vector<double> v;
  for (const auto *set : {&horizontal, &vertical})
    for (const BlockLength &b : *set)
      v.push_back(b.length);
  if (v.empty())
    return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const double x = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(x));
  const std::size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (x - static_cast<double>(i)) * (v[j] - v[i]);
}

double BoardMetrics::fractionWithin(double tolerance) const
{
  std::size_t n = 0, in = 0;
  for (const auto *set : {&horizontal, &vertical})
    for (const BlockLength &b : *set) {
      ++n;
      in += std::abs(b.length - nominal) <= tolerance ? 1 : 0;
    }
  return n ? static_cast<double>(in) / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

std::string formatBoardMetrics(const BoardMetrics &m)
{
  std::ostringstream o;
  const Eigen::Vector3d hs = BoardMetrics::stats(m.horizontal), vs = BoardMetrics::stats(m.vertical);
  double rms = 0;
  for (double d : m.plane_distance)
    rms += d * d;
  rms = std::sqrt(rms / static_cast<double>(std::max<std::size_t>(1, m.plane_distance.size())));
  auto worst = [&m](const std::vector<BlockLength> &v) {
    double w = 0;
    for (const BlockLength &b : v)
      w = std::max(w, std::abs(b.length - m.nominal));
    return w;
  };
  o << "points measured:            " << m.points.size() << "\n";
  o << "horizontal block lengths:   " << mm(hs(0)) << " .. " << mm(hs(1)) << " mm, mean " << mm(hs(2))
    << " mm, worst error " << mm(worst(m.horizontal)) << " mm (" << m.horizontal.size() << " blocks, nominal "
    << mm(m.nominal) << " mm)\n";
  o << "vertical block lengths:     " << mm(vs(0)) << " .. " << mm(vs(1)) << " mm, mean " << mm(vs(2))
    << " mm, worst error " << mm(worst(m.vertical)) << " mm (" << m.vertical.size() << " blocks)\n";
  o << "distance to fitted plane:   largest " << mm(m.max_plane_distance) << " mm, RMS " << mm(rms) << " mm\n";
  o << "depth zc:                   " << mm(m.min_depth, 1) << " .. " << mm(m.max_depth, 1) << " mm\n";
  if (!m.horizontal.empty() || !m.vertical.empty()) {
    char line[200];
    std::snprintf(line, sizeof line, "all block lengths:          median %.3f mm, 5..95 %% %.3f .. %.3f mm, %.0f %% within 0.3 mm\n",
                  1e3 * m.quantile(0.5), 1e3 * m.quantile(0.05), 1e3 * m.quantile(0.95), 100.0 * m.fractionWithin(3e-4));
    o << line;
  }
  if (m.has_board_pose) {
    const Eigen::AngleAxisd aa(m.w_R_o);
    const Eigen::Vector3d tu = aa.angle() * aa.axis();
    char line[300];
    std::snprintf(line, sizeof line,
                  "board pose in the world:    t = (%.2f, %.2f, %.2f) mm, theta-u = (%.5f, %.5f, %.5f) rad (wMo: origin at "
                  "corner 0, x along a row), fit RMS %.3f mm, scale %.5f\n",
                  1e3 * m.w_t_o.x(), 1e3 * m.w_t_o.y(), 1e3 * m.w_t_o.z(), tu.x(), tu.y(), tu.z(), 1e3 * m.board_fit_rms,
                  m.board_scale);
    o << line;
  }
  return o.str();
}

namespace {

cv::Scalar errorColour(double err, double scale)
{
  // green (small) -> orange -> red (>= scale)
  const double t = std::clamp(std::abs(err) / scale, 0.0, 1.0);
  return cv::Scalar(40, 200 * (1 - t) + 40 * t, 60 + 180 * t);
}


/* blocks.csv: one row per block, its length and error against the nominal. */
std::string blocksTable(const BoardMetrics &m)
{
  std::ostringstream blocks;
  blocks << "direction,id_a,id_b,length,error\n";
  char buf[160];
  for (const auto *set : {&m.horizontal, &m.vertical})
    for (const BlockLength &b : *set) {
      std::snprintf(buf, sizeof buf, "%s,%ld,%ld,%.12g,%.12g\n", set == &m.horizontal ? "horizontal" : "vertical",
                    b.id_a, b.id_b, b.length, b.length - m.nominal);
      blocks << buf;
    }
  return blocks.str();
}

/* plane.csv: one row per point, in the world and the camera, and its distance to the plane. */
std::string planeTable(const BoardMetrics &m)
{
  std::ostringstream plane;
  plane << "id,frame,x,y,z,xc,yc,zc,plane_distance\n";
  char buf[160];
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    const BoardPoint &p = m.points[i];
    std::snprintf(buf, sizeof buf, "%ld,%ld,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", p.id, p.frame, p.w_P.x(),
                  p.w_P.y(), p.w_P.z(), p.c_P.x(), p.c_P.y(), p.c_P.z(), m.plane_distance[i]);
    plane << buf;
  }
  return plane.str();
}

/* The points' coordinates in the fitted plane, from its point: x along the board's rows (the sum
   of the horizontal blocks, else the world's x, projected on the plane), y = normal x x. */
std::vector<Eigen::Vector2d> inPlaneCoordinates(const BoardMetrics &m)
{
  Eigen::Vector3d ex = Eigen::Vector3d::UnitX();
  {
    std::map<long, Eigen::Vector3d> P;
    for (const BoardPoint &p : m.points)
      P[p.id] = p.w_P;
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    for (const BlockLength &b : m.horizontal)
      acc += P[b.id_b] - P[b.id_a];
    if (acc.norm() > 0)
      ex = acc;
  }
  ex = (ex - m.plane_normal * m.plane_normal.dot(ex)).normalized();
  const Eigen::Vector3d ey = m.plane_normal.cross(ex).normalized();
  std::vector<Eigen::Vector2d> q;
  for (const BoardPoint &p : m.points) {
    const Eigen::Vector3d r = p.w_P - m.plane_point;
    q.emplace_back(r.dot(ex), r.dot(ey));
  }
  return q;
}

/* Panel 1: the points in the fitted plane (q, board-horizontal to the right), the blocks coloured
   by their error (full red at err_scale) and labelled with their lengths. */
void drawPointsPanel(cv::Mat &img, const BoardMetrics &m, const std::vector<Eigen::Vector2d> &q, double err_scale)
{
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const Eigen::Vector2d &a : q) {
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(a);
  }
  const cv::Rect p1(30, 60, 620, 560);
  cv::rectangle(img, p1, cv::Scalar(200, 200, 200));
  text(img, "points in the fitted plane, block lengths (mm)", cv::Point(p1.x + 10, p1.y + 20));
  const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-6});
  const double scale = 0.8 * std::min(p1.width, p1.height - 40) / span;
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  // The panel's centre in whole pixels (integer halves, as intended).
  const int centre_x = p1.x + p1.width / 2;
  const int centre_y = p1.y + 20 + (p1.height - 20) / 2;
  auto toPx = [&](const Eigen::Vector2d &a) {
    return cv::Point(static_cast<int>(centre_x + scale * (a.x() - mid.x())),
                     static_cast<int>(centre_y + scale * (a.y() - mid.y())));
  };
  std::map<long, cv::Point> px;
  for (std::size_t i = 0; i < m.points.size(); ++i)
    px[m.points[i].id] = toPx(q[i]);
  for (const auto *set : {&m.horizontal, &m.vertical})
    for (const BlockLength &b : *set) {
      const cv::Point a = px[b.id_a], c = px[b.id_b];
      cv::line(img, a, c, errorColour(b.length - m.nominal, err_scale), 3, cv::LINE_AA);
      const cv::Point mpt = (a + c) / 2;
      text(img, mm(b.length), mpt + cv::Point(set == &m.horizontal ? -18 : 4, set == &m.horizontal ? -6 : 4), 0.38);
    }
  for (const auto &kv : px) {
    cv::circle(img, kv.second, 4, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
    text(img, std::to_string(kv.first), kv.second + cv::Point(5, 14), 0.33, cv::Scalar(120, 120, 120));
  }
  text(img, "colour: |length - " + mm(m.nominal) + " mm|, green 0 .. red " + mm(err_scale) + " mm",
       cv::Point(p1.x + 10, p1.y + p1.height - 10), 0.4);
}

/* Panel 2: distance of each point to the plane (mm), a bar per point by id. */
void drawPlaneDistancePanel(cv::Mat &img, const BoardMetrics &m)
{
  const cv::Rect p2(680, 60, 490, 270);
  cv::rectangle(img, p2, cv::Scalar(200, 200, 200));
  text(img, "distance to the fitted plane (mm), by id", cv::Point(p2.x + 10, p2.y + 20));
  const double dmax = std::max(m.max_plane_distance, 1e-5);
  const int zero_y = p2.y + 30 + (p2.height - 50) / 2;
  cv::line(img, cv::Point(p2.x + 40, zero_y), cv::Point(p2.x + p2.width - 10, zero_y), cv::Scalar(120, 120, 120));
  text(img, "+" + mm(dmax), cv::Point(p2.x + 2, p2.y + 40), 0.35);
  text(img, "-" + mm(dmax), cv::Point(p2.x + 2, p2.y + p2.height - 18), 0.35);
  const int n = static_cast<int>(m.points.size());
  const double bw = static_cast<double>(p2.width - 60) / std::max(1, n);
  for (int i = 0; i < n; ++i) {
    const double h = m.plane_distance[static_cast<std::size_t>(i)] / dmax * (p2.height - 60) / 2;
    const int x0 = static_cast<int>(p2.x + 45 + i * bw);
    cv::rectangle(img, cv::Point(x0, zero_y), cv::Point(static_cast<int>(x0 + 0.7 * bw), static_cast<int>(zero_y - h)),
                  cv::Scalar(180, 120, 40), cv::FILLED);
  }
  text(img, "largest " + mm(m.max_plane_distance) + " mm", cv::Point(p2.x + 10, p2.y + p2.height - 4), 0.4);
}

/* Panel 3: seen from above: board-horizontal (q's x) against camera depth. */
void drawFromAbovePanel(cv::Mat &img, const BoardMetrics &m, const std::vector<Eigen::Vector2d> &q)
{
  const cv::Rect p3(680, 350, 490, 270);
  cv::rectangle(img, p3, cv::Scalar(200, 200, 200));
  text(img, "from above: along the board (mm) vs depth zc (mm)", cv::Point(p3.x + 10, p3.y + 20));
  double x_lo = 1e9, x_hi = -1e9;
  for (const auto &a : q) {
    x_lo = std::min(x_lo, a.x());
    x_hi = std::max(x_hi, a.x());
  }
  // Depth at no more than 4x the scale of the board axis, so that millimetre noise is not drawn as a curve.
  const double xr = std::max(x_hi - x_lo, 1e-4), zr = std::max({m.max_depth - m.min_depth, 0.25 * xr, 1e-4});
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    const int x = static_cast<int>(p3.x + 30 + (q[i].x() - x_lo) / xr * (p3.width - 60));
    const int y = static_cast<int>(p3.y + 40 + (m.points[i].c_P.z() - m.min_depth) / zr * (p3.height - 70));
    cv::circle(img, cv::Point(x, y), 4, cv::Scalar(40, 40, 200), cv::FILLED, cv::LINE_AA);
  }
  text(img, "zc " + mm(m.min_depth, 1) + " (top) .. " + mm(m.max_depth, 1) + " mm", cv::Point(p3.x + 10, p3.y + p3.height - 6),
       0.4);
}

/* The figure: 1200 x 640, the title and three panels. */
cv::Mat boardFigure(const BoardMetrics &m, const std::string &title)
{
  cv::Mat img(640, 1200, CV_8UC3, cv::Scalar(255, 255, 255));
  text(img, title, cv::Point(20, 30), 0.7, cv::Scalar(0, 0, 0), 2);
  const double err_scale = std::max(1e-4, 0.02 * m.nominal); // 2 % of the block is full red
  const std::vector<Eigen::Vector2d> q = inPlaneCoordinates(m);
  drawPointsPanel(img, m, q, err_scale);
  drawPlaneDistancePanel(img, m);
  drawFromAbovePanel(img, m, q);
  return img;
}

} // namespace

void writeBoardReport(const std::string &dir, const BoardMetrics &m, const std::string &title)
{
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw Error(dir + ": cannot create the report folder: " + ec.message());
  const std::filesystem::path d(dir);
  // The four files are committed together, after the figure is drawn: all or nothing.
  AtomicFiles files;
  files.add((d / "report.txt").string(), title + "\n\n" + formatBoardMetrics(m));
  files.add((d / "blocks.csv").string(), blocksTable(m));
  files.add((d / "plane.csv").string(), planeTable(m));
  const std::string png = (d / "figure.png").string();
  files.add(png, report_detail::encodePng(boardFigure(m, title), png));
  files.commit();
}

std::vector<std::string> boardReportFiles(const std::string &dir)
{
  const std::filesystem::path d(dir);
  return {(d / "report.txt").string(), (d / "blocks.csv").string(), (d / "plane.csv").string(),
          (d / "figure.png").string()};
}

} // namespace yawdepth
