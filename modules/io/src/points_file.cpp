#include "csv.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

using io_detail::CsvReader;
using io_detail::excerpt;
using io_detail::formatNumber;
using io_detail::throwError;

namespace {

const char *const kPointsHeader = "id,frame,x,y,z,xc,yc,zc,sigma_zc,status\n";

void appendRow(std::string &out, const PointRow &row)
{
  const PointEstimate &e = row.estimate;
  out += std::to_string(row.id);
  out += ',';
  out += std::to_string(e.frame);
  const double values[7] = {e.v_P.x(), e.v_P.y(), e.v_P.z(), e.c_P.x(), e.c_P.y(), e.c_P.z(), e.sigmaZ()};
  for (double v : values) {
    out += ',';
    if (e.ok())
      out += formatNumber(v);
  }
  out += ',';
  out += toString(e.status);
  out += '\n';
}

std::string pointsText(const std::vector<PointRow> &rows)
{
  std::string out = kPointsHeader;
  for (const PointRow &r : rows)
    appendRow(out, r);
  return out;
}

} // namespace

void writePointsCsv(std::ostream &out, const std::vector<PointRow> &rows)
{
  const std::string text = pointsText(rows);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.flush();
  if (!out)
    throwError("cannot write the points (standard output or the stream given)");
}

void writePointsCsv(const std::string &path, const std::vector<PointRow> &rows)
{
  writeFileAtomically(path, pointsText(rows));
}

std::vector<PointRow> readPointsCsv(const std::string &path, const InputLimits &limits)
{
  CsvReader csv(path, limits);
  const std::size_t c_id = csv.requireColumn("id");
  const std::size_t c_frame = csv.requireColumn("frame");
  const char *const names[7] = {"x", "y", "z", "xc", "yc", "zc", "sigma_zc"};
  std::size_t cols[7];
  for (int i = 0; i < 7; ++i)
    cols[i] = csv.requireColumn(names[i]);
  const std::size_t c_status = csv.requireColumn("status");

  std::vector<PointRow> rows;
  while (csv.next()) {
    PointRow r;
    r.id = csv.integer(c_id, true);
    r.estimate.frame = csv.integer(c_frame, true);
    double v[7];
    for (int i = 0; i < 7; ++i)
      v[i] = csv.numberOrNaN(cols[i]);
    r.estimate.v_P = Eigen::Vector3d(v[0], v[1], v[2]);
    r.estimate.c_P = Eigen::Vector3d(v[3], v[4], v[5]);
    r.estimate.c_cov = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
    r.estimate.c_cov(2, 2) = v[6] * v[6];
    try {
      r.estimate.status = statusFromString(csv.field(c_status));
    } catch (const Error &) {
      csv.fail("column 'status': unknown status '" + excerpt(csv.field(c_status)) + "'");
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

} // namespace yawdepth
