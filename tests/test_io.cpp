// Tests of the public file formats (docs/formats.md): readers, writers, atomic writes.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>
#include <yawdepth/error.h>
#include <yawdepth/core/files.h>
#include <yawdepth/io/files.h>

#include "file_support.h"

using namespace yawdepth;
using namespace yawdepth::test;
namespace fs = std::filesystem;

namespace {

const std::string kData = std::string(YAWDEPTH_TEST_DATA_DIR) + "/io/";

/* Checks that reading fails with a one-line message "<path>:<line>: ..." mentioning `words`. */
void requireError(const std::string &message, const std::string &prefix, const std::string &words)
{
  INFO("message: " << message);
  CHECK(message.find('\n') == std::string::npos);
  CHECK(message.find('\r') == std::string::npos);
  CHECK(message.rfind(prefix, 0) == 0);
  CHECK(message.find(words) != std::string::npos);
}

/* Checks that read(path) fails as requireError says, the prefix being the path and then `where`. */
template <class Read>
void requireReadError(const std::string &path, const std::string &where, const std::string &words, const Read &read)
{
  requireError(errorOf([&] { read(path); }), path + where, words);
}

// The readers, each as a function of the path alone.
const auto readMotion = [](const std::string &p) { readMotionCsv(p); };
const auto readTracks = [](const std::string &p) { readTracksCsv(p); };
const auto readRig = [](const std::string &p) { readRigFile(p); };
const auto readPoints = [](const std::string &p) { readPointsCsv(p); };

void requireMotionError(const TempDir &dir, const std::string &content, const std::string &where,
                        const std::string &words, std::optional<double> fixed_yaw = std::nullopt)
{
  requireReadError(dir.write("bad_motion.csv", content), where, words,
                   [&](const std::string &p) { readMotionCsv(p, fixed_yaw); });
}

void requireTracksError(const TempDir &dir, const std::string &content, const std::string &where,
                        const std::string &words)
{
  requireReadError(dir.write("bad_tracks.csv", content), where, words, readTracks);
}

void requireRigError(const TempDir &dir, const std::string &content, const std::string &where,
                     const std::string &words)
{
  requireReadError(dir.write("bad_rig.yaml", content), where, words, readRig);
}

void requirePointsError(const TempDir &dir, const std::string &content, const std::string &where,
                        const std::string &words)
{
  requireReadError(dir.write("bad_points.csv", content), where, words, readPoints);
}

/* Checks every field of a planar motion sample, exactly. */
void checkSample(const MotionSample &s, long frame, double x, double y, double z, double heading, double yaw)
{
  CHECK(s.frame == frame);
  CHECK(s.x == x);
  CHECK(s.y == y);
  CHECK(s.z == z);
  CHECK(s.heading == heading);
  CHECK(s.yaw == yaw);
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/* Doubles that need all 17 digits, plus edge cases. */
std::vector<double> awkwardNumbers()
{
  std::vector<double> v = {0.1,     -0.0, 1.0 / 3.0, -2.0 / 3.0, 1e-300, 4.9406564584124654e-324,
                           1.7976931348623157e308, 123456789.123456789, -0.15030000000000001};
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> d(-10, 10);
  for (int i = 0; i < 40; ++i)
    v.push_back(d(rng) * std::pow(10.0, (i % 9) - 4));
  return v;
}

} // namespace

// ------------------------------------------------------------------------------------------ motion

TEST_CASE("motion log: fixture with images resolved against the CSV folder", "[io][motion]")
{
  const MotionLog m = readMotionCsv(kData + "motion.csv");
  REQUIRE(m.samples.size() == 4);
  REQUIRE(m.images.size() == 4);
  CHECK(m.samples[1].frame == 1);
  CHECK(m.samples[1].z == 0.05);
  CHECK(m.samples[2].yaw == 0.0698);
  CHECK(m.samples[3].x == 0.001);
  CHECK(m.samples[3].heading == 0.01);
  CHECK(m.images[0] == (fs::path(kData) / "images/0000.png").string());
  CHECK(m.images[3].empty());
  CHECK(m.find(2) == &m.samples[2]);
  CHECK(m.find(4) == nullptr);
  CHECK(m.find(-1) == nullptr);
  CHECK(m.indexOf(3) == 3);
  CHECK(m.indexOf(0) == 0);
  CHECK(m.indexOf(17) == -1);
}

TEST_CASE("motion log: steps no motion can make are refused, wraps and pauses are not", "[io][motion]")
{
  MotionLog log;
  for (long k = 0; k < 20; ++k) {
    MotionSample s;
    s.frame = k;
    s.z = 0.02 * k;
    s.heading = std::remainder(3.0 + 0.05 * k, 2 * M_PI); // wraps from +pi to -pi on the way
    s.yaw = 0.01 * k;
    log.samples.push_back(s);
  }
  CHECK_NOTHROW(checkMotionSteps(log, "m.csv"));
  // A robot that stands still, then drives 0.8 m in one step: below the 1 m floor.
  MotionLog still = log;
  for (MotionSample &s : still.samples)
    s.z = 0;
  still.samples[10].z = 0.8;
  CHECK_NOTHROW(checkMotionSteps(still, "m.csv"));
  const auto refused = [&](void (*edit)(MotionSample &), const char *word) {
    MotionLog bad = log;
    edit(bad.samples[7]);
    try {
      checkMotionSteps(bad, "m.csv");
      FAIL("accepted");
    } catch (const Error &e) {
      const std::string what = e.what();
      CHECK(what.find("m.csv: the row of frame 7") != std::string::npos);
      CHECK(what.find(word) != std::string::npos);
    }
  };
  refused([](MotionSample &s) { s.z = 1e6; }, "glitch");
  refused([](MotionSample &s) { s.x = 25.0; }, "glitch"); // 1000 times the 2 cm median step is 20 m
  refused([](MotionSample &s) { s.heading = 1e9; }, "heading");
  refused([](MotionSample &s) { s.yaw = -20.0; }, "yaw");
  refused([](MotionSample &s) { s.z = std::nan(""); }, "glitch");
}

TEST_CASE("motion log: round trip is exact to the bit", "[io][motion]")
{
  TempDir dir;
  const std::vector<double> nums = awkwardNumbers();
  MotionLog m;
  for (std::size_t i = 0; i + 5 <= nums.size(); ++i) {
    MotionSample s;
    s.frame = static_cast<long>(3 * i + 1);
    s.x = nums[i];
    s.y = nums[i + 1];
    s.z = nums[i + 2];
    s.heading = nums[i + 3];
    s.yaw = nums[i + 4];
    m.samples.push_back(s);
  }
  const std::string p = dir.file("motion.csv");
  writeMotionCsv(p, m);
  const MotionLog r = readMotionCsv(p);
  REQUIRE(r.samples.size() == m.samples.size());
  CHECK(r.images.empty());
  CHECK(slurp(p).rfind("frame,x,y,z,heading,yaw\n", 0) == 0);
  for (std::size_t i = 0; i < m.samples.size(); ++i) {
    CHECK(r.samples[i].frame == m.samples[i].frame);
    CHECK(sameBits(r.samples[i].x, m.samples[i].x));
    CHECK(sameBits(r.samples[i].y, m.samples[i].y));
    CHECK(sameBits(r.samples[i].z, m.samples[i].z));
    CHECK(sameBits(r.samples[i].heading, m.samples[i].heading));
    CHECK(sameBits(r.samples[i].yaw, m.samples[i].yaw));
  }
  CHECK(r.indexOf(m.samples[5].frame) == 5);
  CHECK(r.indexOf(m.samples[5].frame + 1) == -1);
}

TEST_CASE("motion log: images round trip relative to the output folder", "[io][motion]")
{
  TempDir dir;
  fs::create_directories(dir.path / "sub");
  MotionLog m;
  for (long f = 0; f < 4; ++f) {
    MotionSample s;
    s.frame = f;
    s.z = 0.1 * static_cast<double>(f);
    m.samples.push_back(s);
  }
  const std::string outside = (fs::path("/definitely/elsewhere") / "b, \"q\".png").string();
  m.images = {dir.file("img/a.png"), "", outside, dir.file("img/with space.png")};
  const std::string p = dir.file("motion.csv");
  writeMotionCsv(p, m);
  const std::string text = slurp(p);
  CHECK(text.rfind("frame,x,y,z,heading,yaw,image\n", 0) == 0);
  CHECK(text.find(",img/a.png\n") != std::string::npos); // written relative
  const MotionLog r = readMotionCsv(p);
  REQUIRE(r.images.size() == 4);
  CHECK(r.images[0] == dir.file("img/a.png"));
  CHECK(r.images[1].empty());
  CHECK(r.images[2] == outside);
  CHECK(r.images[3] == dir.file("img/with space.png"));

  // Inconsistent sizes are refused.
  m.images.pop_back();
  const std::string msg = errorOf([&] { writeMotionCsv(dir.file("m2.csv"), m); });
  CHECK(msg.find("images") != std::string::npos);
  CHECK_FALSE(fs::exists(dir.file("m2.csv")));
}

TEST_CASE("motion log: column order, extra columns, BOM, CRLF, spaces", "[io][motion]")
{
  TempDir dir;
  const MotionLog m = readMotionCsv(dir.write("m.csv", "note, yaw ,heading,z,y,x,frame,extra\n"
                                                      "a,0.5,0.25,3,2,1,7,\n"
                                                      " b , 0.75 , 0.5 , 6 , 5 , 4 , 9 , zzz \n"));
  REQUIRE(m.samples.size() == 2);
  checkSample(m.samples[0], 7, 1, 2, 3, 0.25, 0.5);
  CHECK(m.samples[1].frame == 9);
  CHECK(m.samples[1].x == 4);
  CHECK(m.samples[1].yaw == 0.75);

  // The fixture: BOM, CRLF, spaces around names, no yaw column, trailing empty line.
  const MotionLog f = readMotionCsv(kData + "motion_bom_crlf_noyaw.csv", 0.125);
  REQUIRE(f.samples.size() == 2);
  checkSample(f.samples[0], 10, 1, 2, 0.5, 0.1, 0.125);
  CHECK(f.samples[1].z == 0.75);
  CHECK(f.samples[1].yaw == 0.125);

  // Every permutation of the six columns reads the same.
  std::vector<std::string> cols = {"frame", "x", "y", "z", "heading", "yaw"};
  std::sort(cols.begin(), cols.end());
  int n = 0;
  do {
    std::string header, row;
    for (std::size_t i = 0; i < cols.size(); ++i) {
      header += (i ? "," : "") + cols[i];
      const std::string v = cols[i] == "frame"     ? "5"
                            : cols[i] == "x"       ? "1.5"
                            : cols[i] == "y"       ? "-2.5"
                            : cols[i] == "z"       ? "3e-3"
                            : cols[i] == "heading" ? "+0.5"
                                                   : "-0.25";
      row += (i ? "," : "") + v;
    }
    const MotionLog q = readMotionCsv(dir.write("perm.csv", header + "\r\n" + row + "\r\n"));
    REQUIRE(q.samples.size() == 1);
    checkSample(q.samples[0], 5, 1.5, -2.5, 3e-3, 0.5, -0.25);
    ++n;
  } while (std::next_permutation(cols.begin(), cols.end()));
  CHECK(n == 720);
}

TEST_CASE("motion log: missing yaw column with and without a fixed yaw", "[io][motion]")
{
  TempDir dir;
  const std::string p = dir.write("noyaw.csv", "frame,x,y,z,heading\n1,0,0,0,0\n2,0,0,1,0\n");
  const MotionLog m = readMotionCsv(p, -0.5);
  REQUIRE(m.samples.size() == 2);
  CHECK(m.samples[0].yaw == -0.5);
  CHECK(m.samples[1].yaw == -0.5);
  requireError(errorOf([&] { readMotionCsv(p); }), p + ": ", "no 'yaw' column and the rig file has no 'yaw'");
  requireError(errorOf([&] { readMotionCsv(p, std::numeric_limits<double>::quiet_NaN()); }), p + ": ",
               "not a finite");

  // A yaw column wins over the fixed yaw.
  const std::string q = dir.write("yaw.csv", "frame,x,y,z,heading,yaw\n1,0,0,0,0,0.3\n");
  CHECK(readMotionCsv(q, 9.0).samples[0].yaw == 0.3);
}

TEST_CASE("motion log: rejections name the file and the line, on one line", "[io][motion]")
{
  TempDir dir;
  const std::string H = "frame,x,y,z,heading,yaw\n";
  SECTION("missing file")
  {
    requireReadError(dir.file("nope.csv"), ": ", "cannot open", readMotion);
  }
  SECTION("a folder is unreadable")
  {
    fs::create_directories(dir.path / "folder.csv");
    requireReadError(dir.file("folder.csv"), ": ", "cannot", readMotion);
  }
  SECTION("empty file") { requireMotionError(dir, "", ": ", "empty file"); }
  SECTION("blank file") { requireMotionError(dir, "\xEF\xBB\xBF\r\n  \n", ": ", "empty file"); }
  SECTION("header only") { requireMotionError(dir, H, ": ", "no data rows"); }
  SECTION("header only, CRLF and blank line") { requireMotionError(dir, "frame,x,y,z,heading,yaw\r\n\r\n", ": ", "no data rows"); }
  SECTION("missing column")
  {
    requireMotionError(dir, "frame,x,y,heading,yaw\n1,0,0,0,0\n", ":1: ", "missing column 'z'");
    requireMotionError(dir, "x,y,z,heading,yaw\n0,0,0,0,0\n", ":1: ", "missing column 'frame'");
  }
  SECTION("duplicated column") { requireMotionError(dir, "frame,x,y,z,x,heading,yaw\n1,0,0,0,0,0,0\n", ":1: ", "duplicated column 'x'"); }
  SECTION("fewer fields") { requireMotionError(dir, H + "1,0,0,0,0,0\n2,0,0,0,0\n", ":3: ", "5 fields, the header has 6"); }
  SECTION("more fields") { requireMotionError(dir, H + "1,0,0,0,0,0,9\n", ":2: ", "7 fields"); }
  SECTION("text in a number") { requireMotionError(dir, H + "1,0,0,0,0,0\n2,0,abc,0,0,0\n", ":3: ", "column 'y': 'abc' is not a number"); }
  SECTION("trailing text after a number") { requireMotionError(dir, H + "1,0,0,1.5m,0,0\n", ":2: ", "'1.5m' is not a number"); }
  SECTION("hex is not accepted") { requireMotionError(dir, H + "1,0x10,0,0,0,0\n", ":2: ", "is not a number"); }
  SECTION("empty number") { requireMotionError(dir, H + "1,0,0,,0,0\n", ":2: ", "column 'z' is empty"); }
  SECTION("nan") { requireMotionError(dir, H + "1,0,0,0,nan,0\n", ":2: ", "'nan' is not a finite number"); }
  SECTION("NaN") { requireMotionError(dir, H + "1,0,0,0,0,NaN\n", ":2: ", "not a finite number"); }
  SECTION("inf") { requireMotionError(dir, H + "1,inf,0,0,0,0\n", ":2: ", "'inf' is not a finite number"); }
  SECTION("-Infinity") { requireMotionError(dir, H + "1,-Infinity,0,0,0,0\n", ":2: ", "not a finite number"); }
  SECTION("overflowing number") { requireMotionError(dir, H + "1,1e999,0,0,0,0\n", ":2: ", "out of range"); }
  SECTION("frame 1.5") { requireMotionError(dir, H + "1.5,0,0,0,0,0\n", ":2: ", "column 'frame': '1.5' is not an integer"); }
  SECTION("frame 1e3") { requireMotionError(dir, H + "1e3,0,0,0,0,0\n", ":2: ", "'1e3' is not an integer"); }
  SECTION("frame text") { requireMotionError(dir, H + "one,0,0,0,0,0\n", ":2: ", "'one' is not a number"); }
  SECTION("frame overflow") { requireMotionError(dir, H + "99999999999999999999999,0,0,0,0,0\n", ":2: ", "out of range"); }
  SECTION("negative frame") { requireMotionError(dir, H + "-3,0,0,0,0,0\n", ":2: ", "negative"); }
  SECTION("duplicated frame") { requireMotionError(dir, H + "1,0,0,0,0,0\n2,0,0,0,0,0\n2,0,0,1,0,0\n", ":4: ", "frame 2 is repeated (first at line 3)"); }
  SECTION("unsorted frames") { requireMotionError(dir, H + "1,0,0,0,0,0\n5,0,0,0,0,0\n3,0,0,1,0,0\n", ":4: ", "frame 3 follows frame 5"); }
  SECTION("unterminated quote") { requireMotionError(dir, "frame,x,y,z,heading,yaw,image\n1,0,0,0,0,0,\"a.png\n", ":2: ", "unterminated"); }
  SECTION("line numbers count blank lines") { requireMotionError(dir, H + "\n1,0,0,0,0,0\n\n2,0,x,0,0,0\n", ":5: ", "'x' is not a number"); }
  SECTION("embedded NUL and control characters stay on one line")
  {
    requireMotionError(dir, H + std::string("1,0,\0\n\r7,0,0,0\n", 16), ":2: ", "3 fields, the header has 6");
    requireMotionError(dir, H + "1,0,0,0,0,\r\x1b[2J\n", ":2: ", "'\\x0d\\x1b[2J' is not a number");
    requireMotionError(dir, H + std::string("1,0,1\0,0,0,0\n", 13), ":2: ", "'1\\x00' is not a number");
  }
}

TEST_CASE("csv: no crash on binary garbage and huge lines", "[io][robustness]")
{
  TempDir dir;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    std::string bytes(static_cast<std::size_t>(rng() % 4000), '\0');
    for (char &c : bytes)
      c = static_cast<char>(rng() & 0xff);
    if (trial % 2)
      bytes = "frame,x,y,z,heading,yaw\n" + bytes;
    const std::string p = dir.write("garbage.csv", bytes);
    const std::string m1 = errorOf([&] { readMotionCsv(p); });
    CHECK(m1.find('\n') == std::string::npos);
    const std::string m2 = errorOf([&] { readTracksCsv(p); });
    CHECK(m2.find('\n') == std::string::npos);
    const std::string m3 = errorOf([&] { readRigFile(p); });
    CHECK(m3.find('\n') == std::string::npos);
    CHECK(m3.rfind(p, 0) == 0);
  }
  // A 20 MB line in the header, and one in a number: over the 1 MiB line limit, refused before
  // the line is held whole.
  const std::string huge(20u << 20, '7');
  const std::string p1 = dir.write("huge1.csv", huge + "\n1\n");
  requireError(errorOf([&] { readTracksCsv(p1); }), p1 + ":1: ", "line longer than 1 MiB");
  const std::string p2 = dir.write("huge2.csv", "frame,id,u,v\n1,2," + huge + ",4\n");
  const std::string m = errorOf([&] { readTracksCsv(p2); });
  requireError(m, p2 + ":2: ", "line longer than 1 MiB");
  CHECK(m.size() < 300);
  // A long line within the limit is read: the number in it is out of range.
  const std::string long_number(100000, '7');
  const std::string p3 = dir.write("huge3.csv", "frame,id,u,v\n1,2,3," + long_number + "\n");
  const std::string m3 = errorOf([&] { readTracksCsv(p3); });
  requireError(m3, p3 + ":2: ", "out of range");
  CHECK(m3.size() < 300);
  // A raised line limit reads the 20 MB number and names it as out of range.
  InputLimits big;
  big.max_line_bytes = 64u << 20;
  requireError(errorOf([&] { readTracksCsv(p2, big); }), p2 + ":2: ", "out of range");
  // The size limit: a file over it is refused, naming the limit.
  InputLimits small;
  small.max_bytes = 1u << 20;
  requireError(errorOf([&] { readTracksCsv(p2, small); }), p2 + ": ", "larger than 1 MiB");
}

// ------------------------------------------------------------------------------------------ tracks

TEST_CASE("tracks: fixture grouped by id and sorted by frame", "[io][tracks]")
{
  const std::vector<Track> t = readTracksCsv(kData + "tracks.csv");
  REQUIRE(t.size() == 2);
  CHECK(t[0].id == 1);
  CHECK(t[1].id == 3);
  REQUIRE(t[0].observations.size() == 3);
  REQUIRE(t[1].observations.size() == 3);
  CHECK(t[0].observations[0].frame == 0);
  CHECK(t[0].observations[1].frame == 1);
  CHECK(t[0].observations[2].frame == 3);
  CHECK(t[0].observations[1].u == 101.5);
  CHECK(t[0].observations[1].v == 200.5);
  CHECK(t[1].observations[2].u == 323.75);
  CHECK(t[1].observations[2].v == 239.5);

  const MotionLog m = readMotionCsv(kData + "motion.csv");
  CHECK_NOTHROW(checkTracksAgainstMotion(t, m, kData + "tracks.csv"));
}

TEST_CASE("tracks: any row order, any column order, extra columns", "[io][tracks]")
{
  TempDir dir;
  const std::string p = dir.write("t.csv", "v,score,u,id,frame\r\n"
                                           "5,0.9,4,20,3\r\n"
                                           "2,0.1,1,10,2\r\n"
                                           "6,0.9,5,20,1\r\n"
                                           "3,0.2,2,10,0\r\n"
                                           "7,,8,5,9\r\n"
                                           "\r\n");
  const std::vector<Track> t = readTracksCsv(p);
  REQUIRE(t.size() == 3);
  CHECK(t[0].id == 5);
  CHECK(t[1].id == 10);
  CHECK(t[2].id == 20);
  REQUIRE(t[1].observations.size() == 2);
  CHECK(t[1].observations[0].frame == 0);
  CHECK(t[1].observations[0].u == 2);
  CHECK(t[1].observations[0].v == 3);
  CHECK(t[1].observations[1].frame == 2);
  REQUIRE(t[2].observations.size() == 2);
  CHECK(t[2].observations[0].frame == 1);
  CHECK(t[2].observations[1].frame == 3);
  CHECK(t[0].observations.size() == 1);
}

TEST_CASE("tracks: round trip is exact to the bit, rows by frame then id", "[io][tracks]")
{
  TempDir dir;
  const std::vector<double> nums = awkwardNumbers();
  std::vector<Track> tracks;
  std::size_t k = 0;
  for (long id : {2L, 7L, 11L}) {
    Track t;
    t.id = id;
    for (long f = id % 3; f < 12; f += 2) {
      t.observations.push_back({f, nums[k % nums.size()], nums[(k + 1) % nums.size()]});
      k += 2;
    }
    tracks.push_back(t);
  }
  const std::string p = dir.file("tracks.csv");
  writeTracksCsv(p, tracks);
  const std::string text = slurp(p);
  CHECK(text.rfind("frame,id,u,v\n", 0) == 0);
  // Rows ordered by frame, then id.
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  long pf = -1, pid = -1;
  while (std::getline(in, line)) {
    long f = 0, id = 0;
    REQUIRE(std::sscanf(line.c_str(), "%ld,%ld", &f, &id) == 2);
    CHECK((f > pf || (f == pf && id > pid)));
    pf = f;
    pid = id;
  }
  const std::vector<Track> r = readTracksCsv(p);
  REQUIRE(r.size() == tracks.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    CHECK(r[i].id == tracks[i].id);
    REQUIRE(r[i].observations.size() == tracks[i].observations.size());
    for (std::size_t j = 0; j < r[i].observations.size(); ++j) {
      CHECK(r[i].observations[j].frame == tracks[i].observations[j].frame);
      CHECK(sameBits(r[i].observations[j].u, tracks[i].observations[j].u));
      CHECK(sameBits(r[i].observations[j].v, tracks[i].observations[j].v));
    }
  }
}

TEST_CASE("tracks: rejections", "[io][tracks]")
{
  TempDir dir;
  const std::string H = "frame,id,u,v\n";
  SECTION("missing file")
  {
    requireReadError(dir.file("missing_tracks.csv"), ": ", "cannot open", readTracks);
  }
  SECTION("empty") { requireTracksError(dir, "", ": ", "empty file"); }
  SECTION("header only") { requireTracksError(dir, H, ": ", "no data rows"); }
  SECTION("missing column") { requireTracksError(dir, "frame,id,u\n1,2,3\n", ":1: ", "missing column 'v'"); }
  SECTION("duplicated column") { requireTracksError(dir, "frame,id,u,v,id\n1,2,3,4,5\n", ":1: ", "duplicated column 'id'"); }
  SECTION("fewer fields") { requireTracksError(dir, H + "1,2,3,4\n1,3,3\n", ":3: ", "3 fields, the header has 4"); }
  SECTION("text") { requireTracksError(dir, H + "1,2,abc,4\n", ":2: ", "column 'u': 'abc' is not a number"); }
  SECTION("nan") { requireTracksError(dir, H + "1,2,3,nan\n", ":2: ", "column 'v': 'nan' is not a finite number"); }
  SECTION("inf") { requireTracksError(dir, H + "1,2,inf,4\n", ":2: ", "not a finite number"); }
  SECTION("id 1.5") { requireTracksError(dir, H + "1,1.5,3,4\n", ":2: ", "column 'id': '1.5' is not an integer"); }
  SECTION("frame 1e3") { requireTracksError(dir, H + "1e3,1,3,4\n", ":2: ", "column 'frame': '1e3' is not an integer"); }
  SECTION("negative id") { requireTracksError(dir, H + "1,-1,3,4\n", ":2: ", "negative"); }
  SECTION("duplicated (frame, id)")
  {
    requireTracksError(dir, H + "1,7,3,4\n2,7,3,4\n1,8,0,0\n1,7,5,6\n", ":5: ",
                       "feature 7 is observed twice in frame 1 (first at line 2)");
  }
}

TEST_CASE("tracks: a frame the motion log does not have", "[io][tracks]")
{
  MotionLog m;
  for (long f : {10L, 11L, 13L}) {
    MotionSample s;
    s.frame = f;
    m.samples.push_back(s);
  }
  std::vector<Track> t(2);
  t[0].id = 3;
  t[0].observations = {{10, 0, 0}, {11, 0, 0}};
  t[1].id = 7;
  t[1].observations = {{11, 0, 0}, {12, 0, 0}, {14, 0, 0}};
  const std::string msg = errorOf([&] { checkTracksAgainstMotion(t, m, "dir/tracks.csv"); });
  CHECK(msg == "dir/tracks.csv: feature 7 is observed in frame 12, which the motion log does not have");
  t[1].observations = {{13, 0, 0}};
  CHECK_NOTHROW(checkTracksAgainstMotion(t, m, "dir/tracks.csv"));
}

// -------------------------------------------------------------------------------------------- rig

TEST_CASE("rig file: good files", "[io][rig]")
{
  TempDir dir;
  const RigFile f = readRigFile(kData + "rig.yaml");
  CHECK(f.camera_offset.x() == -0.1503);
  CHECK(f.camera_offset.y() == 0.0);
  CHECK(f.camera_offset.z() == 0.0);
  REQUIRE(f.yaw.has_value());
  CHECK(*f.yaw == 0.25);

  const RigFile g = readRigFile(dir.write("block.yaml", "%YAML 1.2\n---\ncamera_offset:\n  - 1\n  - -2.5e-1\n  - +3\n"));
  CHECK(g.camera_offset == Eigen::Vector3d(1, -0.25, 3));
  CHECK_FALSE(g.yaw.has_value());

  const RigFile h = readRigFile(dir.write("crlf.yaml", "\xEF\xBB\xBF" "camera_offset: [0, 0, 0]\r\nyaw: -1.5\r\n"));
  CHECK(h.camera_offset == Eigen::Vector3d::Zero());
  REQUIRE(h.yaw.has_value());
  CHECK(*h.yaw == -1.5);
}

TEST_CASE("rig file: round trip", "[io][rig]")
{
  TempDir dir;
  RigFile r;
  r.camera_offset = Eigen::Vector3d(-0.15030000000000001, 1.0 / 3.0, -0.0);
  const std::string p = dir.file("rig.yaml");
  writeRigFile(p, r);
  CHECK(slurp(p) == "camera_offset: [-0.15030000000000002, 0.33333333333333331, -0]\n");
  RigFile q = readRigFile(p);
  for (int i = 0; i < 3; ++i)
    CHECK(sameBits(q.camera_offset(i), r.camera_offset(i)));
  CHECK_FALSE(q.yaw.has_value());

  r.yaw = 2.0 / 3.0;
  writeRigFile(p, r);
  q = readRigFile(p);
  REQUIRE(q.yaw.has_value());
  CHECK(sameBits(*q.yaw, *r.yaw));

  r.camera_offset.x() = std::numeric_limits<double>::quiet_NaN();
  CHECK(errorOf([&] { writeRigFile(p, r); }).find("not finite") != std::string::npos);
  CHECK(sameBits(readRigFile(p).camera_offset.y(), 1.0 / 3.0)); // the old file is intact
}

TEST_CASE("rig file: rejections", "[io][rig]")
{
  TempDir dir;
  SECTION("missing file")
  {
    requireReadError(dir.file("missing.yaml"), ": ", "cannot open", readRig);
  }
  SECTION("empty file") { requireRigError(dir, "", ": ", "empty"); }
  SECTION("comments only") { requireRigError(dir, "# nothing\n", ": ", "empty"); }
  SECTION("missing key") { requireRigError(dir, "yaw: 0.1\n", ": ", "missing key 'camera_offset'"); }
  SECTION("two values") { requireRigError(dir, "camera_offset: [0.1, 0.2]\n", ":1: ", "sequence of 3 numbers"); }
  SECTION("four values") { requireRigError(dir, "camera_offset: [0.1, 0.2, 0.3, 0.4]\n", ":1: ", "sequence of 3 numbers"); }
  SECTION("a scalar") { requireRigError(dir, "camera_offset: 0.1\n", ":1: ", "sequence of 3 numbers"); }
  SECTION("text") { requireRigError(dir, "camera_offset: [0.1, abc, 0.3]\n", ":1: ", "'abc' is not a number"); }
  SECTION("NaN") { requireRigError(dir, "camera_offset: [0.1, 0.2, .nan]\n", ":1: ", "not a number"); }
  SECTION("nan") { requireRigError(dir, "\ncamera_offset: [nan, 0.2, 0.3]\n", ":2: ", "'nan' is not a finite number"); }
  SECTION("inf") { requireRigError(dir, "camera_offset: [0, 0, -inf]\n", ":1: ", "not a finite number"); }
  SECTION("nested") { requireRigError(dir, "camera_offset: [0, [1], 0]\n", ":1: ", "must be a number"); }
  SECTION("yaw text") { requireRigError(dir, "camera_offset: [0, 0, 0]\nyaw: left\n", ":2: ", "'yaw': 'left' is not a number"); }
  SECTION("yaw empty") { requireRigError(dir, "camera_offset: [0, 0, 0]\nyaw:\n", ":2: ", "'yaw' has no value"); }
  SECTION("duplicated key") { requireRigError(dir, "camera_offset: [0, 0, 0]\ncamera_offset: [1, 1, 1]\n", ":2: ", "duplicated key"); }
  SECTION("not a map") { requireRigError(dir, "- 1\n- 2\n", ":1: ", "not a YAML map"); }
  SECTION("a plain word") { requireRigError(dir, "hello\n", ":1: ", "not a YAML map"); }
  SECTION("not YAML")
  {
    requireRigError(dir, "camera_offset: [0, 0, 0\nyaw: {\n", ":", "not valid YAML");
    requireRigError(dir, "{{{{{{ ]]]\n", ":", "not valid YAML");
    requireRigError(dir, "camera_offset: [0, 0, 0]\n  bad indentation: : :\n\t- x", ":", "YAML");
    requireRigError(dir, std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), ": ", "NUL");
  }
  SECTION("deep nesting does not crash")
  {
    const std::string p = dir.write("deep.yaml", "camera_offset: " + std::string(100000, '[') + "\n");
    const std::string msg = errorOf([&] { readRigFile(p); });
    CHECK(msg.rfind(p, 0) == 0);
    CHECK(msg.find('\n') == std::string::npos);
  }
}

// ----------------------------------------------------------------------------------------- points

TEST_CASE("points: header, empty numbers when not ok, round trip", "[io][points]")
{
  TempDir dir;
  const std::vector<double> nums = awkwardNumbers();
  std::vector<PointRow> rows;
  for (int i = 0; i < 6; ++i) {
    PointRow r;
    r.id = 100 + i;
    r.estimate.frame = 40 + i;
    r.estimate.status = (i == 2) ? Status::Degenerate : (i == 4) ? Status::NoMotion : Status::Ok;
    r.estimate.v_P = Eigen::Vector3d(nums[3 * i], nums[3 * i + 1], nums[3 * i + 2]);
    r.estimate.c_P = Eigen::Vector3d(nums[3 * i + 3], nums[3 * i + 4], nums[3 * i + 5]);
    r.estimate.c_cov = Eigen::Matrix3d::Identity() * 1e-4;
    r.estimate.c_cov(2, 2) = nums[i + 20] * nums[i + 20];
    rows.push_back(r);
  }
  rows[5].estimate.status = Status::TooFewFrames; // NaN numbers, as the estimators leave them
  rows[5].estimate.v_P.setConstant(std::numeric_limits<double>::quiet_NaN());

  std::ostringstream out;
  writePointsCsv(out, rows);
  const std::string text = out.str();
  CHECK(text.rfind("id,frame,x,y,z,xc,yc,zc,sigma_zc,status\n", 0) == 0);
  CHECK(text.find("\n102,42,,,,,,,,degenerate\n") != std::string::npos);
  CHECK(text.find("\n104,44,,,,,,,,no_motion\n") != std::string::npos);
  CHECK(text.find("\n105,45,,,,,,,,too_few_frames\n") != std::string::npos);
  CHECK(text.find(",ok\n") != std::string::npos);

  const std::string p = dir.file("points.csv");
  writePointsCsv(p, rows);
  CHECK(slurp(p) == text);
  const std::vector<PointRow> r = readPointsCsv(p);
  REQUIRE(r.size() == rows.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    CHECK(r[i].id == rows[i].id);
    CHECK(r[i].estimate.frame == rows[i].estimate.frame);
    CHECK(r[i].estimate.status == rows[i].estimate.status);
    if (rows[i].estimate.ok()) {
      for (int k = 0; k < 3; ++k) {
        CHECK(sameBits(r[i].estimate.v_P(k), rows[i].estimate.v_P(k)));
        CHECK(sameBits(r[i].estimate.c_P(k), rows[i].estimate.c_P(k)));
      }
      CHECK(sameBits(r[i].estimate.sigmaZ(), rows[i].estimate.sigmaZ()));
    } else {
      CHECK(r[i].estimate.v_P.array().isNaN().all());
      CHECK(r[i].estimate.c_P.array().isNaN().all());
      CHECK(std::isnan(r[i].estimate.sigmaZ()));
    }
  }

  // No rows: a header alone, which reads back as no points.
  writePointsCsv(p, {});
  CHECK(slurp(p) == "id,frame,x,y,z,xc,yc,zc,sigma_zc,status\n");
  CHECK(readPointsCsv(p).empty());

  // Bad status words and text are rejected.
  requirePointsError(dir, "id,frame,x,y,z,xc,yc,zc,sigma_zc,status\n1,2,,,,,,,,bogus\n", ":2: ", "unknown status 'bogus'");
  requirePointsError(dir, "id,frame,x,y,z,xc,yc,zc,sigma_zc,status\n1,2,a,,,,,,,ok\n", ":2: ", "column 'x': 'a' is not a number");
}

// ----------------------------------------------------------------------------------------- atomic

TEST_CASE("atomic write: replaces an existing file, no partial file on failure", "[io][atomic]")
{
  TempDir dir;
  const std::string p = dir.file("out.csv");
  writeFileAtomically(p, "first\n");
  CHECK(slurp(p) == "first\n");
  writeFileAtomically(p, "second, longer contents\n");
  CHECK(slurp(p) == "second, longer contents\n");
  writeFileAtomically(p, "");
  CHECK(fs::exists(p));
  CHECK(slurp(p).empty());
  CHECK(dir.count() == 1); // no temporary file left beside it

  // Permissions of a replaced file are kept.
  fs::permissions(p, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  writeFileAtomically(p, "third\n");
  CHECK((fs::status(p).permissions() & fs::perms::all) ==
        (fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read));

  // The target folder does not exist: throws, leaves nothing.
  const std::string missing = dir.file("no/such/folder/out.csv");
  requireError(errorOf([&] { writeFileAtomically(missing, "x"); }), missing + ": ", "temporary file");
  CHECK_FALSE(fs::exists(dir.path / "no"));
  requireError(errorOf([&] { writePointsCsv(missing, {}); }), missing + ": ", "cannot");
  MotionLog m;
  m.samples.resize(1);
  CHECK_THROWS_AS(writeMotionCsv(missing, m), Error);
  CHECK_THROWS_AS(writeTracksCsv(missing, {}), Error);
  CHECK_THROWS_AS(writeRigFile(missing, RigFile()), Error);
  CHECK(dir.count() == 1);

  // The target is a folder: throws, the folder is untouched, no temporary file left.
  fs::create_directories(dir.path / "afolder");
  const std::string folder = dir.file("afolder");
  requireError(errorOf([&] { writeFileAtomically(folder, "x"); }), folder + ": ", "folder");
  CHECK(fs::is_directory(folder));
  CHECK(dir.count() == 2);

  // A path without a file name is refused.
  CHECK_THROWS_AS(writeFileAtomically(folder + "/", "x"), Error);
  CHECK(dir.count() == 2);
  CHECK(slurp(p) == "third\n");
}

TEST_CASE("rig file: unknown keys and a yaw axis the estimators do not model are refused", "[io][rig]")
{
  TempDir dir;
  requireRigError(dir, "camera_ofset: [-0.15, 0, 0]\n", ":1: ", "unknown key 'camera_ofset' (known: camera_offset");
  requireRigError(dir, "camera_offset: [-0.15, 0, 0]\nother: {a: 1}\n", ":2: ", "unknown key 'other'");
  requireRigError(dir, "camera_offset: [-0.15, 0, 0]\nyaw_axis: [1, 0, 0]\n", ":2: ", "'yaw_axis' is 90.0 deg from the vision frame's +Y");
  requireRigError(dir, "camera_offset: [-0.15, 0, 0]\nyaw_axis: [0.06, 1, 0]\n", ":2: ", "3.4 deg from the vision frame's +Y");
  // What calibrate-rig writes beside the values is known, and a tilt within 2 deg is accepted.
  const std::string calibrated = dir.write(
      "cal.yaml", "camera_offset: [-0.15, 0, 0.01]\nyaw_offset: 0.01\nyaw_axis: [0.02, 1, -0.01]\n"
                  "camera_offset_sigma: [0.0001, 0, 0.0001]\nyaw_offset_sigma: 0.0002\nyaw_offset_estimated: true\n"
                  "yaw_axis_sigma: [0.001, 0, 0.001]\nreprojection_rms_px: 0.05\n");
  CHECK_NOTHROW(readRigFile(calibrated));
}

TEST_CASE("rig file: camera_pose, a fixed 6-DoF mount (an arm's eMc)", "[io][rig]")
{
  TempDir dir;
  const std::string path = dir.write("eMc.yaml", "camera_pose: [0.0577148, -0.0339261, -0.0422745, 0.00178253, "
                                                 "0.00917657, 1.58178]\ncamera_pose_sigma: [1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3]\n");
  const RigFile rig = readRigFile(path);
  REQUIRE(rig.camera_pose.has_value());
  CHECK((*rig.camera_pose)[5] == 1.58178);
  REQUIRE(rig.camera_pose_sigma.has_value());
  // The mount it describes is ViSP's homogeneous matrix of that pose vector.
  const YawRig mount = rigOf(rig);
  const vpHomogeneousMatrix expect(*rig.camera_pose);
  const vpHomogeneousMatrix got = mount.vMc(0.0);
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 4; ++j)
      CHECK(got[i][j] == Approx(expect[i][j]).margin(1e-15));
  // Round trip, sigmas included.
  const std::string again = dir.file("again.yaml");
  writeRigFile(again, rig);
  const RigFile back = readRigFile(again);
  REQUIRE(back.camera_pose.has_value());
  for (unsigned i = 0; i < 6; ++i)
    CHECK((*back.camera_pose)[i] == (*rig.camera_pose)[i]);
  CHECK(*back.camera_pose_sigma == *rig.camera_pose_sigma);
  // Both forms, neither, a wrong count, a sigma without a pose, a rotation beyond pi.
  requireRigError(dir, "camera_offset: [0, 0, 0]\ncamera_pose: [0, 0, 0, 0, 0, 0]\n", ":2: ", "both 'camera_offset' and 'camera_pose'");
  requireRigError(dir, "yaw: 0.1\n", ": ", "missing key 'camera_offset' (or 'camera_pose')");
  requireRigError(dir, "camera_pose: [0, 0, 0, 0, 0]\n", ":1: ", "'camera_pose' must be a sequence of 6 numbers (it has 5)");
  requireRigError(dir, "camera_offset: [0, 0, 0]\ncamera_pose_sigma: [0, 0, 0, 0, 0, 0]\n", ":2: ", "'camera_pose_sigma' without 'camera_pose'");
  requireRigError(dir, "camera_pose: [0, 0, 0, 4, 0, 0]\n", ":1: ", "norm of at most pi");
  // The quaternion form, as tf_echo prints base_link -> optical frame: the same mount.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(1.2, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  char text[256];
  std::snprintf(text, sizeof text, "camera_pose: [0.1, -0.02, 0.3, %.17g, %.17g, %.17g, %.17g]\n", q.x(), q.y(), q.z(), q.w());
  const RigFile rq = readRigFile(dir.write("q.yaml", text));
  REQUIRE(rq.camera_pose.has_value());
  const Eigen::Vector3d tu((*rq.camera_pose)[3], (*rq.camera_pose)[4], (*rq.camera_pose)[5]);
  CHECK(tu.isApprox(1.2 * Eigen::Vector3d(0.3, -0.5, 0.8).normalized(), 1e-12));
  CHECK((*rq.camera_pose)[2] == 0.3);
  requireRigError(dir, "camera_pose: [0, 0, 0, 0, 0, 0, 0]\n", ":1: ", "'camera_pose': the quaternion (qx, qy, qz, qw) has norm 0");
}

TEST_CASE("motion log: the 6-DoF form (tx, ty, tz, tux, tuy, tuz) reads, round-trips and refuses mixtures", "[io][motion]")
{
  TempDir dir;
  const std::string p = dir.write("arm.csv", "frame,tx,ty,tz,tux,tuy,tuz,image\n"
                                            "1,0.5,0.1,0.09,2.2,-2.2,0.02,a.png\n"
                                            "2,0.51,0.12,0.1,2.21,-2.19,0.03,b.png\n");
  const MotionLog m = readMotionCsv(p);
  REQUIRE(m.samples.size() == 2);
  CHECK(m.samples[0].six_dof);
  CHECK(m.samples[0].yaw == 0.0); // no pan joint: yaw 0 without a yaw column or a rig yaw
  CHECK(m.samples[1].theta_u.y() == -2.19);
  // wMv is ViSP's pose vector.
  const vpHomogeneousMatrix expect(vpPoseVector(0.51, 0.12, 0.1, 2.21, -2.19, 0.03));
  const vpHomogeneousMatrix got = wMv(m.samples[1]);
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 4; ++j)
      CHECK(got[i][j] == Approx(expect[i][j]).margin(1e-14));
  // A fixed yaw from the rig applies as for planar logs; a yaw column wins.
  CHECK(readMotionCsv(p, 0.25).samples[0].yaw == 0.25);
  // Round trip exact to the bit (the planar columns are not written).
  const std::string out = dir.file("out.csv");
  writeMotionCsv(out, m);
  const MotionLog r = readMotionCsv(out);
  REQUIRE(r.samples.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(r.samples[i].six_dof);
    CHECK(r.samples[i].position() == m.samples[i].position());
    CHECK(r.samples[i].theta_u == m.samples[i].theta_u);
    CHECK(r.images[i] == m.images[i]);
  }
  // One 6-DoF column without the others is an error naming the missing one.
  const std::string partial = dir.write("partial.csv", "frame,x,y,z,heading,yaw,tux\n0,0,0,0,0,0,0\n");
  CHECK_THAT(errorOf([&] { readMotionCsv(partial); }), Catch::Contains("tx"));
  // A writer refuses a log that mixes both forms.
  MotionLog mixed = m;
  mixed.samples[1].six_dof = false;
  CHECK_THAT(errorOf([&] { writeMotionCsv(dir.file("mixed.csv"), mixed); }), Catch::Contains("mixes planar and 6-DoF"));
}

TEST_CASE("rig file: yaw_offset and yaw_axis", "[io][rig]")
{
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "yawdepth_rig_offset_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "rig.yaml").string();
  {
    std::ofstream f(path);
    f << "camera_offset: [-0.15, 0, 0.01]\nyaw_offset: 0.0087\nyaw_axis: [0.01, 1, 0]\n";
  }
  const RigFile rig = readRigFile(path);
  CHECK(rig.yaw_offset == 0.0087);
  REQUIRE(rig.yaw_axis.has_value());
  CHECK(rig.yaw_axis->norm() == Approx(1.0));
  std::vector<MotionSample> motion(2);
  motion[1].yaw = 0.5;
  applyRigFile(rig, motion);
  CHECK(motion[0].yaw == 0.0087);
  CHECK(motion[1].yaw == Approx(0.5087));
  // Round trip through the writer.
  writeRigFile(path, rig);
  const RigFile back = readRigFile(path);
  CHECK(back.yaw_offset == rig.yaw_offset);
  CHECK((*back.yaw_axis - *rig.yaw_axis).norm() < 1e-15);
  // Bad values are rejected with the file named.
  for (const char *bad : {"camera_offset: [0, 0, 0]\nyaw_offset: nan\n", "camera_offset: [0, 0, 0]\nyaw_axis: [0, 0]\n",
                          "camera_offset: [0, 0, 0]\nyaw_axis: [0, 0, 0]\n", "camera_offset: [0, 0, 0]\nyaw_offset:\n"}) {
    {
      std::ofstream f(path);
      f << bad;
    }
    CHECK_THROWS_AS(readRigFile(path), Error);
  }
  std::filesystem::remove_all(dir);
}

namespace {

/* The PLY test's input: the rig, six random motion samples (frames 10 to 15), and 20 rows of random
   points at those frames (every fifth degenerate) with a gray level each; seeded. */
struct PlyInput {
  YawRig rig{Eigen::Vector3d(-0.15, 0.02, 0.05)};
  std::vector<MotionSample> samples;
  std::vector<PointRow> rows;
  std::map<std::pair<long, long>, int> gray;
};

PlyInput plyInput()
{
  PlyInput in;
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (long f = 0; f < 6; ++f) {
    MotionSample s;
    s.frame = 10 + f;
    s.x = uni(rng);
    s.y = 0.1 * uni(rng);
    s.z = 2 * uni(rng);
    s.heading = uni(rng);
    s.yaw = uni(rng);
    in.samples.push_back(s);
  }
  for (long id = 0; id < 20; ++id) {
    PointRow r;
    r.id = 1000 + id;
    r.estimate.frame = in.samples[static_cast<std::size_t>(id % 6)].frame;
    r.estimate.c_P = Eigen::Vector3d(uni(rng), uni(rng), 2 + uni(rng));
    r.estimate.c_cov = Eigen::Matrix3d::Identity() * (0.001 * (id + 1)) * (0.001 * (id + 1));
    r.estimate.status = id % 5 == 4 ? Status::Degenerate : Status::Ok;
    in.rows.push_back(r);
    in.gray[{r.estimate.frame, r.id}] = static_cast<int>(id * 12);
  }
  return in;
}

/* A PLY text's header lines (appended to `header`, up to end_header) and its vertices' numbers. */
std::vector<std::vector<double>> parsePly(const std::string &text, std::vector<std::string> &header)
{
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line) && line != "end_header")
    header.push_back(line);
  std::vector<std::vector<double>> v;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::vector<double> row;
    double x;
    while (ls >> x)
      row.push_back(x);
    v.push_back(row);
  }
  return v;
}

} // namespace

TEST_CASE("ply: ok points in the world frame, header, colour only when every point has one", "[io][ply]")
{
  constexpr double kRoundOff = 1e-12; // m, for points within a few metres
  const PlyInput in = plyInput();
  const YawRig &rig = in.rig;
  const std::vector<MotionSample> &samples = in.samples;
  const std::vector<PointRow> &rows = in.rows;
  const std::map<std::pair<long, long>, int> &gray = in.gray;
  const std::vector<PlyPoint> pts = plyPoints(rig, samples, rows, gray);
  REQUIRE(pts.size() == 16); // the 4 degenerate rows left out
  std::size_t k = 0;
  for (const PointRow &r : rows) {
    if (!r.estimate.ok())
      continue;
    const MotionSample &s = samples[static_cast<std::size_t>(r.estimate.frame - 10)];
    const vpColVector w = wMc(rig, s) * vpColVector({r.estimate.c_P.x(), r.estimate.c_P.y(), r.estimate.c_P.z(), 1.0});
    CHECK(pts[k].id == r.id);
    CHECK((pts[k].w_P - Eigen::Vector3d(w[0], w[1], w[2])).norm() < kRoundOff);
    CHECK(pts[k].sigma_z == r.estimate.sigmaZ());
    CHECK(pts[k].gray == (r.id - 1000) * 12);
    ++k;
  }
  // The text: header, then one vertex per line that reads back to the same numbers.
  std::vector<std::string> header;
  const std::vector<std::vector<double>> v = parsePly(plyText(pts), header);
  REQUIRE(header.size() >= 3);
  CHECK(header[0] == "ply");
  CHECK(header[1] == "format ascii 1.0");
  CHECK(std::find(header.begin(), header.end(), "element vertex 16") != header.end());
  CHECK(std::find(header.begin(), header.end(), "property uchar red") != header.end());
  REQUIRE(v.size() == 16);
  for (std::size_t i = 0; i < v.size(); ++i) {
    REQUIRE(v[i].size() == 8); // x y z red green blue sigma_z id
    CHECK(v[i][0] == pts[i].w_P.x());
    CHECK(v[i][2] == pts[i].w_P.z());
    CHECK(v[i][3] == pts[i].gray);
    CHECK(v[i][5] == pts[i].gray);
    CHECK(v[i][6] == pts[i].sigma_z);
    CHECK(v[i][7] == pts[i].id);
  }
  // One point without a gray level: no colour at all; no points: a valid empty cloud.
  std::vector<PlyPoint> partial = pts;
  partial[3].gray = -1;
  header.clear();
  const std::vector<std::vector<double>> w = parsePly(plyText(partial), header);
  CHECK(std::find(header.begin(), header.end(), "property uchar red") == header.end());
  REQUIRE(w.size() == 16);
  CHECK(w[0].size() == 5);
  header.clear();
  CHECK(parsePly(plyText({}), header).empty());
  CHECK(std::find(header.begin(), header.end(), "element vertex 0") != header.end());
  // Refused: a point at a frame the motion does not have, an id beyond 32 bits, a gray level above 255.
  std::vector<PointRow> lost = rows;
  lost[0].estimate.frame = 99;
  CHECK_THROWS_AS(plyPoints(rig, samples, lost), Error);
  std::vector<PlyPoint> big = pts;
  big[0].id = 1L << 40;
  CHECK_THROWS_AS(plyText(big), Error);
  big = pts;
  big[0].gray = 256;
  CHECK_THROWS_AS(plyText(big), Error);
}
