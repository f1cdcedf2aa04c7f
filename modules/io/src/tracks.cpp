#include "csv.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

using io_detail::CsvReader;
using io_detail::formatNumber;
using io_detail::throwError;

std::vector<Track> readTracksCsv(const std::string &path, const InputLimits &limits)
{
  CsvReader csv(path, limits);
  const std::size_t c_frame = csv.requireColumn("frame");
  const std::size_t c_id = csv.requireColumn("id");
  const std::size_t c_u = csv.requireColumn("u");
  const std::size_t c_v = csv.requireColumn("v");

  struct Obs {
    Observation o;
    std::size_t line;
  };
  std::map<long, std::vector<Obs>> by_id;
  bool any = false;
  while (csv.next()) {
    Obs ob;
    ob.o.frame = csv.integer(c_frame);
    const long id = csv.integer(c_id);
    ob.o.u = csv.number(c_u);
    ob.o.v = csv.number(c_v);
    ob.line = csv.line();
    by_id[id].push_back(ob);
    any = true;
  }
  if (!any)
    csv.failFile("no data rows after the header");

  std::vector<Track> tracks;
  tracks.reserve(by_id.size());
  for (auto &[id, obs] : by_id) {
    std::stable_sort(obs.begin(), obs.end(), [](const Obs &a, const Obs &b) { return a.o.frame < b.o.frame; });
    Track t;
    t.id = id;
    t.observations.reserve(obs.size());
    for (std::size_t i = 0; i < obs.size(); ++i) {
      if (i > 0 && obs[i].o.frame == obs[i - 1].o.frame) {
        const std::size_t a = std::min(obs[i].line, obs[i - 1].line), b = std::max(obs[i].line, obs[i - 1].line);
        csv.failAt(b, "feature " + std::to_string(id) + " is observed twice in frame " +
                          std::to_string(obs[i].o.frame) + " (first at line " + std::to_string(a) + ")");
      }
      t.observations.push_back(obs[i].o);
    }
    tracks.push_back(std::move(t));
  }
  return tracks;
}

void checkTracksAgainstMotion(const std::vector<Track> &tracks, const MotionLog &motion,
                              const std::string &tracks_path)
{
  for (const Track &t : tracks)
    for (const Observation &o : t.observations)
      if (!motion.find(o.frame))
        throwError(tracks_path + ": feature " + std::to_string(t.id) + " is observed in frame " +
                   std::to_string(o.frame) + ", which the motion log does not have");
}

void writeTracksCsv(const std::string &path, const std::vector<Track> &tracks)
{
  struct Row {
    long frame, id;
    double u, v;
  };
  std::vector<Row> rows;
  for (const Track &t : tracks)
    for (const Observation &o : t.observations) {
      if (!std::isfinite(o.u) || !std::isfinite(o.v))
        throwError(path + ": feature " + std::to_string(t.id) + " has a non-finite pixel in frame " +
                   std::to_string(o.frame));
      rows.push_back({o.frame, t.id, o.u, o.v});
    }
  std::stable_sort(rows.begin(), rows.end(),
                   [](const Row &a, const Row &b) { return std::tie(a.frame, a.id) < std::tie(b.frame, b.id); });
  std::string out = "frame,id,u,v\n";
  for (const Row &r : rows) {
    out += std::to_string(r.frame);
    out += ',';
    out += std::to_string(r.id);
    out += ',';
    out += formatNumber(r.u);
    out += ',';
    out += formatNumber(r.v);
    out += '\n';
  }
  writeFileAtomically(path, out);
}

} // namespace yawdepth
