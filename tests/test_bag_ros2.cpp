// Tests of the ROS 2 side of the bag module: MCAP (chunks uncompressed, zstd, lz4; no summary; a
// split bag folder) and rosbag2's .db3 (schema versions 3 and 4; a bag folder) written by the
// reference libraries (tests/data/bags/writers/), every decoded field compared with the values
// written (ros2_expected.json); damaged files (cut, corrupt chunks, unknown compression, CRC,
// unknown records), and the CDR reader's bounds.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>
#include <yawdepth/bag/bag.h>
#include <yawdepth/bag/messages.h>
#include <yawdepth/error.h>

#include "file_support.h"

using namespace yawdepth;
using namespace yawdepth::test;
namespace fs = std::filesystem;

namespace {

const std::string kBags = std::string(YAWDEPTH_TEST_DATA_DIR) + "/bags/";

// ---- A small JSON reader for ros2_expected.json (objects, arrays, strings, numbers, booleans). ----
struct Json {
  enum Kind { Null, Bool, Number, String, Array, Object } kind = Null;
  double number = 0;
  bool boolean = false;
  std::string text;
  std::vector<Json> items;
  std::vector<std::pair<std::string, Json>> fields;

  const Json &operator[](const std::string &key) const
  {
    for (const auto &f : fields)
      if (f.first == key)
        return f.second;
    FAIL("no field '" << key << "' in the expected values");
    return *this;
  }
  const Json &operator[](std::size_t i) const { return items.at(i); }
  std::size_t size() const { return kind == Array ? items.size() : fields.size(); }
  double num() const
  {
    REQUIRE(kind == Number);
    return number;
  }
  std::int64_t i64() const { return kind == String ? std::stoll(text) : std::int64_t(num()); }
};

class JsonParser {
public:
  explicit JsonParser(const std::string &s) : s_(s) {}
  Json parse()
  {
    Json v = value();
    space();
    REQUIRE(p_ == s_.size());
    return v;
  }

private:
  void space()
  {
    while (p_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[p_])))
      ++p_;
  }
  std::string str()
  {
    REQUIRE(s_.at(p_) == '"');
    std::string out;
    for (++p_; s_.at(p_) != '"'; ++p_) {
      if (s_[p_] == '\\') {
        const char e = s_.at(++p_);
        if (e == 'n')
          out += '\n';
        else if (e == 't')
          out += '\t';
        else if (e == 'u') {
          out += char(std::stoi(s_.substr(p_ + 1, 4), nullptr, 16)); // ASCII only in our files
          p_ += 4;
        } else
          out += e;
      } else
        out += s_[p_];
    }
    ++p_;
    return out;
  }
  Json value()
  {
    space();
    Json v;
    const char c = s_.at(p_);
    if (c == '{') {
      v.kind = Json::Object;
      ++p_;
      space();
      if (s_.at(p_) == '}') {
        ++p_;
        return v;
      }
      for (;;) {
        space();
        std::string k = str();
        space();
        REQUIRE(s_.at(p_++) == ':');
        v.fields.emplace_back(k, value());
        space();
        if (s_.at(p_++) == '}')
          return v;
      }
    }
    if (c == '[') {
      v.kind = Json::Array;
      ++p_;
      space();
      if (s_.at(p_) == ']') {
        ++p_;
        return v;
      }
      for (;;) {
        v.items.push_back(value());
        space();
        if (s_.at(p_++) == ']')
          return v;
      }
    }
    if (c == '"') {
      v.kind = Json::String;
      v.text = str();
      return v;
    }
    if (s_.compare(p_, 4, "true") == 0 || s_.compare(p_, 5, "false") == 0) {
      v.kind = Json::Bool;
      v.boolean = s_[p_] == 't';
      p_ += v.boolean ? 4 : 5;
      return v;
    }
    if (s_.compare(p_, 4, "null") == 0) {
      p_ += 4;
      return v;
    }
    const char *start = s_.c_str() + p_;
    char *end = nullptr;
    v.kind = Json::Number;
    v.number = std::strtod(start, &end); // exact: JSON.stringify writes the shortest round trip
    REQUIRE(end != start);
    p_ += std::size_t(end - start);
    return v;
  }
  const std::string &s_;
  std::size_t p_ = 0;
};

Json readJson(const std::string &path)
{
  const std::string s = slurp(path);
  REQUIRE(!s.empty());
  return JsonParser(s).parse();
}

// ---- Comparison of each decoded message with the values written. ----
struct Counter {
  std::size_t messages = 0, fields = 0;
};

std::string ros1Type(const std::string &ros2)
{
  std::string t = ros2;
  const std::size_t m = t.find("/msg/");
  if (m != std::string::npos)
    t.erase(m, 4);
  return t;
}

std::int64_t stampOf(const Json &h) { return h["stamp"]["sec"].i64() * 1000000000 + h["stamp"]["nanosec"].i64(); }

void same(Counter &c, double got, const Json &want)
{
  CHECK(got == want.num());
  ++c.fields;
}
void same(Counter &c, const std::string &got, const Json &want)
{
  REQUIRE(want.kind == Json::String);
  CHECK(got == want.text);
  ++c.fields;
}
void sameHeader(Counter &c, const RosHeader &h, const Json &want)
{
  CHECK(h.stamp == stampOf(want));
  same(c, h.frame_id, want["frame_id"]);
  ++c.fields;
}
template <typename V> void sameArray(Counter &c, const V &got, const Json &want)
{
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    same(c, double(got[i]), want[i]);
}
void samePose(Counter &c, const RosPose &p, const Json &want)
{
  same(c, p.position[0], want["position"]["x"]);
  same(c, p.position[1], want["position"]["y"]);
  same(c, p.position[2], want["position"]["z"]);
  same(c, p.orientation[0], want["orientation"]["x"]);
  same(c, p.orientation[1], want["orientation"]["y"]);
  same(c, p.orientation[2], want["orientation"]["z"]);
  same(c, p.orientation[3], want["orientation"]["w"]);
}

void sameMessage(Counter &c, const BagMessage &m, const Json &want)
{
  INFO("topic " << want["topic"].text << " at " << want["log_time"].text);
  REQUIRE(m.topic->name == want["topic"].text);
  REQUIRE(m.topic->type == ros1Type(want["type"].text));
  REQUIRE(m.topic->encoding == BagEncoding::Cdr);
  CHECK(m.log_time == want["log_time"].i64());
  const Json &v = want["value"];
  const std::string &type = m.topic->type;
  if (type == "sensor_msgs/Image") {
    const ImageMessage i = decodeImage(m);
    sameHeader(c, i.header, v["header"]);
    same(c, i.height, v["height"]);
    same(c, i.width, v["width"]);
    same(c, i.encoding, v["encoding"]);
    same(c, i.is_bigendian ? 1 : 0, v["is_bigendian"]);
    same(c, i.step, v["step"]);
    sameArray(c, i.data, v["data"]);
  } else if (type == "sensor_msgs/CompressedImage") {
    const CompressedImageMessage i = decodeCompressedImage(m);
    sameHeader(c, i.header, v["header"]);
    same(c, i.format, v["format"]);
    sameArray(c, i.data, v["data"]);
    REQUIRE(i.data.size() > 8);
    CHECK(i.data[1] == 'P'); // a PNG
  } else if (type == "sensor_msgs/CameraInfo") {
    const CameraInfoMessage i = decodeCameraInfo(m);
    sameHeader(c, i.header, v["header"]);
    same(c, i.height, v["height"]);
    same(c, i.width, v["width"]);
    same(c, i.distortion_model, v["distortion_model"]);
    sameArray(c, i.D, v["d"]);
    sameArray(c, i.K, v["k"]);
    sameArray(c, i.R, v["r"]);
    sameArray(c, i.P, v["p"]);
    same(c, i.binning_x, v["binning_x"]);
    same(c, i.binning_y, v["binning_y"]);
    same(c, i.roi_x_offset, v["roi"]["x_offset"]);
    same(c, i.roi_y_offset, v["roi"]["y_offset"]);
    same(c, i.roi_height, v["roi"]["height"]);
    same(c, i.roi_width, v["roi"]["width"]);
    CHECK(i.roi_do_rectify == v["roi"]["do_rectify"].boolean);
    ++c.fields;
  } else if (type == "geometry_msgs/PoseStamped") {
    const PoseMessage p = decodePose(m);
    sameHeader(c, p.header, v["header"]);
    samePose(c, p.pose, v["pose"]);
    for (double x : p.covariance)
      CHECK(x == 0);
  } else if (type == "geometry_msgs/PoseWithCovarianceStamped") {
    const PoseMessage p = decodePose(m);
    sameHeader(c, p.header, v["header"]);
    samePose(c, p.pose, v["pose"]["pose"]);
    sameArray(c, p.covariance, v["pose"]["covariance"]);
  } else if (type == "nav_msgs/Odometry") {
    const OdometryMessage o = decodeOdometry(m);
    sameHeader(c, o.header, v["header"]);
    same(c, o.child_frame_id, v["child_frame_id"]);
    samePose(c, o.pose, v["pose"]["pose"]);
    sameArray(c, o.covariance, v["pose"]["covariance"]);
  } else if (type == "tf2_msgs/TFMessage") {
    const TfMessage tf = decodeTf(m);
    REQUIRE(tf.transforms.size() == v["transforms"].size());
    for (std::size_t k = 0; k < tf.transforms.size(); ++k) {
      const TransformMessage &t = tf.transforms[k];
      const Json &w = v["transforms"][k];
      sameHeader(c, t.header, w["header"]);
      same(c, t.child_frame_id, w["child_frame_id"]);
      same(c, t.translation[0], w["transform"]["translation"]["x"]);
      same(c, t.translation[1], w["transform"]["translation"]["y"]);
      same(c, t.translation[2], w["transform"]["translation"]["z"]);
      same(c, t.rotation[0], w["transform"]["rotation"]["x"]);
      same(c, t.rotation[1], w["transform"]["rotation"]["y"]);
      same(c, t.rotation[2], w["transform"]["rotation"]["z"]);
      same(c, t.rotation[3], w["transform"]["rotation"]["w"]);
    }
  } else if (type == "sensor_msgs/JointState") {
    const JointStateMessage j = decodeJointState(m);
    sameHeader(c, j.header, v["header"]);
    REQUIRE(j.name.size() == v["name"].size());
    for (std::size_t k = 0; k < j.name.size(); ++k)
      same(c, j.name[k], v["name"][k]);
    sameArray(c, j.position, v["position"]);
    sameArray(c, j.velocity, v["velocity"]);
    sameArray(c, j.effort, v["effort"]);
  } else {
    FAIL("a message type the test does not know: " << type);
  }
  ++c.messages;
}

/* Whether this build reads `f` (MCAP needs zstd and lz4, .db3 SQLite). */
bool reads(BagFormat f)
{
  const std::vector<BagFormat> r = readableBagFormats();
  return std::find(r.begin(), r.end(), f) != r.end();
}

/* The bags of a folder of reference-written files that this build reads, each with its format. */
std::vector<std::pair<std::string, BagFormat>> bagsIn(const std::string &dir)
{
  std::vector<std::pair<std::string, BagFormat>> all = {
      {dir + "ros2_plain.mcap", BagFormat::Mcap}, {dir + "ros2_zstd.mcap", BagFormat::Mcap},
      {dir + "ros2_lz4.mcap", BagFormat::Mcap},   {dir + "ros2_unchunked.mcap", BagFormat::Mcap},
      {dir + "ros2_split", BagFormat::Mcap},      {dir + "ros2.db3", BagFormat::Sqlite3},
      {dir + "ros2_db3", BagFormat::Sqlite3}};
  all.erase(std::remove_if(all.begin(), all.end(), [](const auto &b) { return !reads(b.second); }), all.end());
  // rosbag2's compression (zstd, built with the MCAP reader's libraries): MESSAGE and FILE modes.
  if (reads(BagFormat::Mcap)) {
    all.emplace_back(dir + "ros2_zstd_mcap", BagFormat::Mcap);
    if (reads(BagFormat::Sqlite3)) {
      all.emplace_back(dir + "ros2_zstd_message", BagFormat::Sqlite3);
      all.emplace_back(dir + "ros2_zstd_file", BagFormat::Sqlite3);
    }
  }
  return all;
}

/* Every bag of `dir` read whole, each message compared with ros2_expected.json. */
Counter checkBags(const std::string &dir)
{
  const Json expected = readJson(dir + "ros2_expected.json");
  const Json &want = expected["messages"];
  std::map<std::string, std::pair<std::string, std::uint64_t>> topics; // name -> type, count
  for (const Json &m : want.items) {
    topics[m["topic"].text].first = ros1Type(m["type"].text);
    ++topics[m["topic"].text].second;
  }
  Counter c;
  for (const auto &bag : bagsIn(dir)) {
    INFO("bag " << bag.first);
    const std::unique_ptr<BagReader> r = openBag(bag.first);
    CHECK(r->format() == bag.second);
    CHECK(r->path() == bag.first);
    REQUIRE(r->topics().size() == topics.size());
    for (const BagTopic &t : r->topics()) {
      INFO("topic " << t.name);
      REQUIRE(topics.count(t.name));
      CHECK(t.type == topics[t.name].first);
      CHECK(t.encoding == BagEncoding::Cdr);
      CHECK(t.messages == topics[t.name].second);
    }
    std::size_t i = 0;
    r->read({}, [&](const BagMessage &m) {
      REQUIRE(i < want.size());
      sameMessage(c, m, want[i++]);
      return true;
    });
    CHECK(i == want.size());
  }
  return c;
}

/* The records of an MCAP file's top level: opcode, position, content length. */
struct Record {
  int op;
  std::size_t pos, len;
};
std::uint64_t le(const std::string &s, std::size_t at, int n)
{
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i)
    v = (v << 8) | static_cast<unsigned char>(s.at(at + std::size_t(i)));
  return v;
}
void putLe(std::string &s, std::size_t at, std::uint64_t v, int n)
{
  for (int i = 0; i < n; ++i)
    s.at(at + std::size_t(i)) = char((v >> (8 * i)) & 0xFF);
}
std::vector<Record> records(const std::string &s)
{
  std::vector<Record> out;
  std::size_t pos = 8;
  while (pos + 9 <= s.size() - 8) {
    const Record r{static_cast<unsigned char>(s[pos]), pos, std::size_t(le(s, pos + 1, 8))};
    out.push_back(r);
    if (r.op == 0x02)
      break;
    pos += 9 + r.len;
  }
  return out;
}
Record first(const std::vector<Record> &rs, int op)
{
  for (const Record &r : rs)
    if (r.op == op)
      return r;
  FAIL("no record of opcode " << op);
  return rs.front();
}

/* Opens and reads `path` whole, decoding every message; returns the messages read. */
std::size_t readAll(const std::string &path)
{
  std::size_t n = 0;
  const std::unique_ptr<BagReader> r = openBag(path);
  r->read({}, [&](const BagMessage &m) {
    const std::string &t = m.topic->type;
    if (t == "sensor_msgs/Image")
      decodeImage(m);
    else if (t == "sensor_msgs/CompressedImage")
      decodeCompressedImage(m);
    else if (t == "sensor_msgs/CameraInfo")
      decodeCameraInfo(m);
    else if (t == "nav_msgs/Odometry")
      decodeOdometry(m);
    else if (t == "tf2_msgs/TFMessage")
      decodeTf(m);
    else if (t == "sensor_msgs/JointState")
      decodeJointState(m);
    else
      decodePose(m);
    ++n;
    return true;
  });
  return n;
}

void requireOneLine(const std::string &message, const std::string &prefix, const std::string &words)
{
  INFO("message: " << message);
  CHECK(message.find('\n') == std::string::npos);
  CHECK(message.rfind(prefix, 0) == 0);
  CHECK(message.find(words) != std::string::npos);
}

/* A message of `type` over `bytes`, for the decoders. */
struct Raw {
  BagTopic topic;
  std::vector<std::uint8_t> bytes;
  BagMessage message() const
  {
    BagMessage m;
    m.topic = &topic;
    m.log_time = 1500000000;
    m.data = bytes.data();
    m.size = bytes.size();
    return m;
  }
};

/* The first message of `topic` in the reference MCAP bag. */
Raw firstOf(const std::string &topic)
{
  Raw raw;
  const std::unique_ptr<BagReader> r = openBag(kBags + (reads(BagFormat::Mcap) ? "ros2_zstd.mcap" : "ros2.db3"));
  BagReadOptions o;
  o.topics = {topic};
  r->read(o, [&](const BagMessage &m) {
    raw.topic = *m.topic;
    raw.bytes.assign(m.data, m.data + m.size);
    return false;
  });
  REQUIRE(!raw.bytes.empty());
  return raw;
}

} // namespace

TEST_CASE("bag_ros2: every reference-written bag decodes to the values written", "[bag]")
{
  const Counter c = checkBags(kBags);
  // 10 bags (5 MCAP and one compressed by rosbag2's FILE mode, 2 .db3 and one of each compression mode)
  // of 34 messages each, every field of every message compared.
  const std::size_t bags = bagsIn(kBags).size();
  const bool mcap = reads(BagFormat::Mcap), db3 = reads(BagFormat::Sqlite3);
  CHECK(bags == std::size_t((mcap ? 6 : 0) + (db3 ? 2 : 0) + (mcap && db3 ? 2 : 0)));
  CHECK(c.messages == bags * 34);
  CHECK(c.fields == bags * 2250);
}

TEST_CASE("bag_ros2: the bags written again with fresh values (YAWDEPTH_BAG_ROS2_DIR)", "[.][writers]")
{
  const char *dir = std::getenv("YAWDEPTH_BAG_ROS2_DIR");
  REQUIRE(dir);
  const Counter c = checkBags(std::string(dir) + "/");
  const std::size_t bags = bagsIn(std::string(dir) + "/").size();
  CHECK(c.messages == bags * 34);
  CHECK(c.fields >= bags * 2200); // the PNG's length varies with its pixels
  WARN("compared " << c.messages << " messages, " << c.fields << " fields");
}

TEST_CASE("bag_ros2: topics and times select messages, the visit stops the read", "[bag]")
{
  const Json expected = readJson(kBags + "ros2_expected.json");
  const Json &want = expected["messages"];
  const std::int64_t t_a = want[5]["log_time"].i64(), t_b = want[25]["log_time"].i64();
  for (const auto &bag : bagsIn(kBags)) {
    INFO("bag " << bag.first);
    const std::unique_ptr<BagReader> r = openBag(bag.first);
    BagReadOptions o;
    o.topics = {"/odom", "/tf", "/no/such/topic"};
    o.start = t_a;
    o.end = t_b;
    std::vector<std::int64_t> got, expect;
    r->read(o, [&](const BagMessage &m) {
      got.push_back(m.log_time);
      CHECK((m.topic->name == "/odom" || m.topic->name == "/tf"));
      return true;
    });
    for (const Json &m : want.items)
      if ((m["topic"].text == "/odom" || m["topic"].text == "/tf") && m["log_time"].i64() >= t_a &&
          m["log_time"].i64() <= t_b)
        expect.push_back(m["log_time"].i64());
    CHECK(got == expect);
    CHECK(expect.size() >= 2);
    std::size_t n = 0;
    r->read({}, [&](const BagMessage &) { return ++n < 3; });
    CHECK(n == 3);
    REQUIRE(r->topic("/odom"));
    CHECK(r->topic("/odom")->type == "nav_msgs/Odometry");
    CHECK(r->topic("/nothing") == nullptr);
    CHECK(r->topicList().find("/camera/mono16 (sensor_msgs/Image, 3 messages)") != std::string::npos);
  }
}

TEST_CASE("bag_ros2: a decoder refuses a message of another type", "[bag]")
{
  const Raw odom = firstOf("/odom");
  requireOneLine(errorOf([&] { decodeImage(odom.message()); }), "/odom: ", "nav_msgs/Odometry, not sensor_msgs/Image");
  requireOneLine(errorOf([&] { decodeTf(odom.message()); }), "/odom: ", "not tf2_msgs/TFMessage");
}

TEST_CASE("bag_ros2: an MCAP file cut anywhere fails with its path, after the messages before the cut", "[bag]")
{
  if (!reads(BagFormat::Mcap))
    return; // this build reads no MCAP
  const TempDir dir;
  for (const char *name : {"ros2_zstd.mcap", "ros2_lz4.mcap", "ros2_plain.mcap", "ros2_unchunked.mcap"}) {
    const std::string whole = slurp(kBags + name);
    const std::size_t data_end = first(records(whole), 0x0F).pos;
    std::vector<std::size_t> cuts = {0, 1, 7, 8, 9, 12, 16, 17, 40, data_end, data_end + 5, whole.size() - 8,
                                     whole.size() - 1};
    for (std::size_t k = 50; k < whole.size(); k += 173)
      cuts.push_back(k);
    for (std::size_t cut : cuts) {
      INFO(name << " cut at " << cut);
      const std::string path = dir.write("cut.mcap", whole.substr(0, cut));
      std::size_t n = 0;
      try {
        n = readAll(path);
      } catch (const Error &e) {
        const std::string what = e.what();
        INFO(what);
        CHECK(what.find('\n') == std::string::npos);
        CHECK(what.rfind(path + ": ", 0) == 0);
        if (cut > 8)
          CHECK(what.find("truncated at byte " + std::to_string(cut) + " of ") != std::string::npos);
        continue;
      }
      // Read whole: only a cut after the data section (in the summary or the footer).
      CHECK(cut >= data_end + 9);
      CHECK(n == 34);
    }
  }
  // The message names the record and the last message read.
  const std::string whole = slurp(kBags + "ros2_zstd.mcap");
  std::vector<Record> chunks;
  for (const Record &r : records(whole))
    if (r.op == 0x06)
      chunks.push_back(r);
  REQUIRE(chunks.size() >= 2);
  const Record chunk = chunks[1];
  const std::string path = dir.write("cut.mcap", whole.substr(0, chunk.pos + 100));
  requireOneLine(errorOf([&] { readAll(path); }), path + ": ",
                 "truncated at byte " + std::to_string(chunk.pos + 100) + " of " +
                     std::to_string(chunk.pos + 9 + chunk.len) + " (in a Chunk record at byte " +
                     std::to_string(chunk.pos) + "); last message read at t = 1700000000.");
}

TEST_CASE("bag_ros2: corrupt MCAP chunks and records are refused with the path and where", "[bag]")
{
  if (!reads(BagFormat::Mcap))
    return; // this build reads no MCAP
  const TempDir dir;
  SECTION("a corrupt zstd or lz4 chunk")
  {
    for (const char *name : {"ros2_zstd.mcap", "ros2_lz4.mcap"}) {
      std::string s = slurp(kBags + name);
      const Record chunk = first(records(s), 0x06);
      for (std::size_t k = chunk.pos + 60; k < chunk.pos + 9 + chunk.len; k += 7)
        s[k] = char(s[k] ^ 0x5A);
      const std::string path = dir.write(name, s);
      requireOneLine(errorOf([&] { readAll(path); }), path + ": chunk at byte " + std::to_string(chunk.pos) + ": ",
                     "corrupt chunk");
    }
  }
  SECTION("an uncompressed_size other than the chunk's")
  {
    for (const char *name : {"ros2_zstd.mcap", "ros2_lz4.mcap"}) {
      const std::string whole = slurp(kBags + name);
      const Record chunk = first(records(whole), 0x06);
      const std::uint64_t usize = le(whole, chunk.pos + 9 + 16, 8);
      const std::string where = ": chunk at byte " + std::to_string(chunk.pos) + ": ";
      std::string s = whole;
      putLe(s, chunk.pos + 9 + 16, usize - 1, 8);
      std::string path = dir.write(name, s);
      requireOneLine(errorOf([&] { readAll(path); }), path + where,
                     "decompressed to more than " + std::to_string(usize - 1) + " bytes");
      putLe(s, chunk.pos + 9 + 16, usize + 1000, 8);
      path = dir.write(name, s);
      requireOneLine(errorOf([&] { readAll(path); }), path + where, "decompressed to " + std::to_string(usize) + " bytes");
      putLe(s, chunk.pos + 9 + 16, std::uint64_t(5) << 30, 8);
      path = dir.write(name, s);
      requireOneLine(errorOf([&] { readAll(path); }), path + where, "over the 1 GiB limit");
    }
  }
  SECTION("a CRC mismatch")
  {
    std::string s = slurp(kBags + "ros2_plain.mcap");
    const Record chunk = first(records(s), 0x06);
    REQUIRE(le(s, chunk.pos + 9 + 24, 4) != 0); // the writer wrote the CRC
    s[chunk.pos + chunk.len - 3] = char(s[chunk.pos + chunk.len - 3] ^ 1);
    const std::string path = dir.write("crc.mcap", s);
    requireOneLine(errorOf([&] { readAll(path); }), path + ": chunk at byte " + std::to_string(chunk.pos) + ": ",
                   "CRC mismatch");
  }
  SECTION("an unknown compression")
  {
    std::string s = slurp(kBags + "ros2_zstd.mcap");
    const Record chunk = first(records(s), 0x06);
    const std::size_t at = chunk.pos + 9 + 28; // after the times, the size and the CRC
    REQUIRE(s.substr(at + 4, 4) == "zstd");
    s.replace(at + 4, 4, "zstx");
    const std::string path = dir.write("xyz.mcap", s);
    requireOneLine(errorOf([&] { openBag(path)->read({}, [](const BagMessage &) { return true; }); }),
                   path + ": chunk at byte " + std::to_string(chunk.pos) + ": ", "unknown compression 'zstx'");
  }
  SECTION("a record longer than the file")
  {
    std::string s = slurp(kBags + "ros2_lz4.mcap");
    const Record chunk = first(records(s), 0x06);
    putLe(s, chunk.pos + 1, std::uint64_t(1) << 40, 8);
    const std::string path = dir.write("long.mcap", s);
    requireOneLine(errorOf([&] { readAll(path); }), path + ": Chunk record at byte " + std::to_string(chunk.pos),
                   "runs beyond the file's end");
  }
  SECTION("a message on a channel never defined")
  {
    std::string s = slurp(kBags + "ros2_unchunked.mcap");
    const Record m = first(records(s), 0x05);
    putLe(s, m.pos + 9, 999, 2);
    const std::string path = dir.write("chan.mcap", s);
    requireOneLine(errorOf([&] { readAll(path); }), path + ": Message record at byte " + std::to_string(m.pos),
                   "channel 999, which was never defined");
  }
  SECTION("bad magic")
  {
    std::string s = slurp(kBags + "ros2_zstd.mcap");
    s[4] = 'X';
    const std::string path = dir.write("magic.mcap", s);
    requireOneLine(errorOf([&] { openBag(path); }), path + ": ", "not a bag");
  }
}

TEST_CASE("bag_ros2: records of unknown opcodes are skipped by their length", "[bag]")
{
  if (!reads(BagFormat::Mcap))
    return; // this build reads no MCAP
  const TempDir dir;
  const std::string unknown = std::string(1, char(0x80)) + std::string("\x05\0\0\0\0\0\0\0", 8) + "hello";
  SECTION("a file without summary")
  {
    std::string s = slurp(kBags + "ros2_unchunked.mcap");
    const Record m = first(records(s), 0x05);
    s.insert(m.pos, unknown);
    CHECK(readAll(dir.write("op.mcap", s)) == 34);
  }
  SECTION("a chunked file, the footer's summary offset moved")
  {
    std::string s = slurp(kBags + "ros2_zstd.mcap");
    const Record chunk = first(records(s), 0x06);
    s.insert(chunk.pos, unknown);
    const std::size_t footer = s.size() - 8 - 29;
    REQUIRE(s[footer] == 0x02);
    putLe(s, footer + 9, le(s, footer + 9, 8) + unknown.size(), 8);
    putLe(s, footer + 17, le(s, footer + 17, 8) + unknown.size(), 8);
    putLe(s, footer + 25, 0, 4); // no summary CRC
    CHECK(readAll(dir.write("op.mcap", s)) == 34);
  }
}

TEST_CASE("bag_ros2: rosbag2's compressed bags: damage named by the file given, no scratch file left", "[bag]")
{
  if (!reads(BagFormat::Mcap) || !reads(BagFormat::Sqlite3))
    return; // zstd comes with the MCAP reader's libraries
  const TempDir scratch, dir;
  const char *old_tmpdir = std::getenv("TMPDIR");
  const std::string saved = old_tmpdir ? old_tmpdir : "";
  ::setenv("TMPDIR", scratch.path.c_str(), 1);
  const std::string zst = slurp(kBags + "ros2_zstd_file/ros2_zstd_file_0.db3.zstd");
  {
    const std::unique_ptr<BagReader> r = openBag(kBags + "ros2_zstd_file");
    CHECK(r->path() == kBags + "ros2_zstd_file");
    CHECK(scratch.count() == 1); // the decompressed database, while the reader lives
  }
  CHECK(scratch.count() == 0);
  SECTION("a compressed bag given as its one file")
  {
    CHECK(readAll(dir.write("alone.db3.zstd", zst)) == 34);
  }
  SECTION("cut short")
  {
    const std::string cut = dir.write("cut.db3.zstd", zst.substr(0, zst.size() / 2));
    requireOneLine(errorOf([&] { openBag(cut); }), cut + ": ", "truncated");
  }
  SECTION("corrupt")
  {
    std::string bad = zst;
    for (std::size_t k = 20; k < bad.size(); k += 7)
      bad[k] = char(bad[k] ^ 0x5A);
    const std::string path = dir.write("bad.db3.zstd", bad);
    const std::string e = errorOf([&] { readAll(path); });
    requireOneLine(e, path + ": ", "");
    CHECK(e.find(scratch.path.string()) == std::string::npos); // never the scratch file's name
  }
  SECTION("a damaged message of MESSAGE compression names its topic")
  {
    std::string db = slurp(kBags + "ros2_zstd_message/ros2_zstd_message_0.db3");
    const std::string magic("\x28\xb5\x2f\xfd", 4);
    std::size_t damaged = 0;
    for (std::size_t at = db.find(magic); at != std::string::npos; at = db.find(magic, at + 4))
      if (at + 12 < db.size()) {
        db[at + 8] = char(db[at + 8] ^ 0xFF);
        db[at + 10] = char(db[at + 10] ^ 0xFF);
        ++damaged;
      }
    REQUIRE(damaged > 0);
    const std::string path = dir.write("damaged.db3", db);
    const std::string e = errorOf([&] { readAll(path); });
    INFO(e);
    CHECK(e.find("message at t = ") != std::string::npos);
    CHECK(e.find('\n') == std::string::npos);
  }
  SECTION("another compression format in metadata.yaml")
  {
    std::filesystem::create_directories(dir.path / "lz4");
    std::string meta = slurp(kBags + "ros2_zstd_file/metadata.yaml");
    meta.replace(meta.find("compression_format: \"zstd\""), 26, "compression_format: \"lz4\"");
    dir.write("lz4/metadata.yaml", meta);
    dir.write("lz4/ros2_zstd_file_0.db3.zstd", zst);
    requireOneLine(errorOf([&] { openBag(dir.file("lz4")); }), dir.file("lz4/metadata.yaml") + ": ",
                   "compression_format 'lz4'");
  }
  CHECK(scratch.count() == 0);
  if (old_tmpdir)
    ::setenv("TMPDIR", saved.c_str(), 1);
  else
    ::unsetenv("TMPDIR");
}

TEST_CASE("bag_ros2: refused .db3 files", "[bag]")
{
  if (!reads(BagFormat::Sqlite3))
    return; // this build reads no .db3
  const std::string other = kBags + "broken/not_rosbag2.db3";
  requireOneLine(errorOf([&] { openBag(other); }), other + ": ", "not a rosbag2 bag");
  const std::string json = kBags + "broken/json_topic.db3";
  requireOneLine(errorOf([&] { openBag(json); }), json + ": ", "topic /status is serialized as 'json', not cdr");
  const TempDir dir;
  std::string s = slurp(kBags + "ros2.db3");
  for (std::size_t k = 4096; k < s.size(); ++k)
    s[k] = char((k * 131) & 0xFF);
  const std::string path = dir.write("corrupt.db3", s);
  requireOneLine(errorOf([&] { readAll(path); }), path + ": ", "malformed");
}

TEST_CASE("bag_ros2: the CDR reader never reads past a message", "[bag]")
{
  for (const char *topic : {"/camera/camera_info", "/camera/rgb8", "/camera/compressed", "/odom", "/pose",
                            "/pose_cov", "/tf", "/tf_static", "/joint_states"}) {
    INFO(topic);
    Raw raw = firstOf(topic);
    const std::size_t whole = raw.bytes.size();
    // Every shorter message is refused (a heap copy of exactly that size: ASan sees any overread).
    for (std::size_t n = 0; n < whole; ++n) {
      Raw cut = raw;
      cut.bytes.resize(n);
      cut.bytes.shrink_to_fit();
      const BagMessage m = cut.message();
      try {
        if (raw.topic.type == "sensor_msgs/CameraInfo")
          decodeCameraInfo(m);
        else if (raw.topic.type == "sensor_msgs/Image")
          decodeImage(m);
        else if (raw.topic.type == "sensor_msgs/CompressedImage")
          decodeCompressedImage(m);
        else if (raw.topic.type == "nav_msgs/Odometry")
          decodeOdometry(m);
        else if (raw.topic.type == "tf2_msgs/TFMessage")
          decodeTf(m);
        else if (raw.topic.type == "sensor_msgs/JointState")
          decodeJointState(m);
        else
          decodePose(m);
        // Only the trailing alignment padding of the last field may go.
        CHECK(whole - n < 8);
      } catch (const Error &e) {
        const std::string what = e.what();
        CHECK(what.rfind(std::string(topic) + ": message at t = 1.500000000 s: ", 0) == 0);
        CHECK(what.find('\n') == std::string::npos);
      }
    }
  }
  // A string length beyond the message: the header's frame_id (after the 4-byte encapsulation and the stamp).
  Raw pose = firstOf("/pose");
  pose.bytes[12] = 0xFF;
  pose.bytes[13] = 0xFF;
  requireOneLine(errorOf([&] { decodePose(pose.message()); }), "/pose: message at t = 1.500000000 s: ",
                 "beyond the message");
  // A sequence count beyond the message.
  Raw tf = firstOf("/tf");
  tf.bytes[4] = 0x40;
  tf.bytes[6] = 0x01;
  requireOneLine(errorOf([&] { decodeTf(tf.message()); }), "/tf: ", "transforms: a sequence of");
  // Encapsulations other than CDR_LE and CDR_BE.
  Raw other = firstOf("/pose");
  other.bytes[1] = 0x03; // PL_CDR_LE
  requireOneLine(errorOf([&] { decodePose(other.message()); }), "/pose: ", "CDR encapsulation 00 03");
  Raw zstd = firstOf("/pose");
  zstd.bytes[0] = 0x28, zstd.bytes[1] = 0xB5, zstd.bytes[2] = 0x2F, zstd.bytes[3] = 0xFD;
  requireOneLine(errorOf([&] { decodePose(zstd.message()); }), "/pose: ", "zstd-compressed message");
  // A missing NUL.
  Raw nul = firstOf("/pose");
  const std::size_t len = std::size_t(nul.bytes[12]);
  nul.bytes[16 + len - 1] = 'x';
  requireOneLine(errorOf([&] { decodePose(nul.message()); }), "/pose: ", "does not end with a NUL");
}

TEST_CASE("bag_ros2: big-endian CDR", "[bag]")
{
  // geometry_msgs/PoseStamped in CDR_BE, written by hand: stamp, frame_id "map", 7 doubles aligned to 8.
  std::vector<std::uint8_t> b = {0x00, 0x00, 0x00, 0x00};
  auto be = [&](std::uint64_t v, int n) {
    for (int i = n - 1; i >= 0; --i)
      b.push_back(std::uint8_t(v >> (8 * i)));
  };
  be(1700000001, 4);
  be(250, 4);
  be(4, 4);
  for (char ch : std::string("map"))
    b.push_back(std::uint8_t(ch));
  b.push_back(0);
  while ((b.size() - 4) % 8)
    b.push_back(0xEE); // padding, any value
  const double values[7] = {1.5, -2.25, 3e-3, 0, 0, 0.6, 0.8};
  for (double v : values) {
    std::uint64_t u;
    std::memcpy(&u, &v, 8);
    be(u, 8);
  }
  Raw raw;
  raw.topic.name = "/pose_be";
  raw.topic.type = "geometry_msgs/PoseStamped";
  raw.topic.encoding = BagEncoding::Cdr;
  raw.bytes = b;
  const PoseMessage p = decodePose(raw.message());
  CHECK(p.header.stamp == 1700000001LL * 1000000000 + 250);
  CHECK(p.header.frame_id == "map");
  CHECK(p.pose.position[0] == 1.5);
  CHECK(p.pose.position[1] == -2.25);
  CHECK(p.pose.position[2] == 3e-3);
  CHECK(p.pose.orientation[2] == 0.6);
  CHECK(p.pose.orientation[3] == 0.8);
}
