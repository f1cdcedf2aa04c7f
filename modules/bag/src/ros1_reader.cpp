// ROS 1 bags (format 2.0) through Debian's rosbag_storage. Before the library sees a file, its
// record structure is checked here (http://wiki.ros.org/Bags/Format/2.0): every record's header
// and data lengths within the file, the bag header's index position, each chunk's sizes, the
// offsets its index records give and, in an uncompressed chunk, the message record at each offset.
// rosbag_storage trusts those numbers (it memcpy's by them), so a truncated or corrupt file must be
// refused before it is opened. The check reads record headers and index records only (seeking over
// the data): a 10 GB bag costs it a few reads per message, not a second pass over the bytes. The
// records inside a bz2 or lz4 chunk are not checked (that would mean decompressing every chunk
// twice): there rosbag_storage's own checks are all there is.
#include "readers.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <console_bridge/console.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/query.h>
#include <rosbag/view.h>
#include <ros/serialization.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {

namespace {

constexpr std::size_t kMagicSize = 13;                      // "#ROSBAG V2.0\n"
constexpr std::uint32_t kMaxHeader = 16u << 20;             // a record header (connection: its message definition)
constexpr std::uint64_t kMaxChunk = std::uint64_t(256) << 20; // a chunk, uncompressed (rosbag writes 768 KiB ones)

enum Op : std::uint8_t { kMsgData = 0x02, kBagHeader = 0x03, kIndexData = 0x04, kChunk = 0x05, kChunkInfo = 0x06, kConnection = 0x07 };


std::uint32_t le32(const std::uint8_t *p) { return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24; }
std::uint64_t le64(const std::uint8_t *p) { return std::uint64_t(le32(p)) | std::uint64_t(le32(p + 4)) << 32; }

/* A record header's fields, each `len name=value`; throws `what` on a malformed one. */
std::map<std::string, std::string> headerFields(const std::vector<std::uint8_t> &h, const std::string &what)
{
  std::map<std::string, std::string> f;
  std::size_t i = 0;
  while (i < h.size()) {
    if (h.size() - i < 4)
      throw Error(what + ": a header field's length is cut off");
    const std::uint32_t len = le32(&h[i]);
    i += 4;
    if (len > h.size() - i)
      throw Error(what + ": a header field of " + std::to_string(len) + " bytes in a header of " +
                  std::to_string(h.size()));
    const char *b = reinterpret_cast<const char *>(&h[i]);
    const char *eq = static_cast<const char *>(std::memchr(b, '=', len));
    if (!eq)
      throw Error(what + ": a header field without '='");
    f[std::string(b, eq)] = std::string(eq + 1, b + len);
    i += len;
  }
  return f;
}

/* `path`, unless it is not a regular file (a pipe could be read only once, and rosbag seeks). */
const std::string &regularFile(const std::string &path)
{
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error(path + ": a ROS 1 bag is read from a regular file (its index is at its end), not a pipe");
  return path;
}

/* Walks a ROS 1 bag's records (seeking over data, reading only headers and index records). */
class Ros1Checker {
public:
  explicit Ros1Checker(const std::string &path) : path_(path), in_(regularFile(path), std::ios::binary)
  {
    if (!in_)
      throw Error(path + ": cannot open the bag");
    in_.seekg(0, std::ios::end);
    size_ = std::uint64_t(in_.tellg());
  }

  void check()
  {
    std::uint64_t pos = kMagicSize;
    std::uint64_t index_pos = 0;
    bool header_seen = false;
    std::uint64_t chunk_size = 0;     // the last chunk's uncompressed size, for its index records
    std::uint64_t chunk_data_pos = 0; // where its data starts, when it is not compressed (else 0)
    bool after_chunk = false;
    while (pos < size_) {
      const std::uint64_t start = pos;
      std::uint8_t op = 0;
      std::map<std::string, std::string> fields;
      std::uint32_t data_len = 0;
      readRecordHeader(pos, op, fields, data_len);
      const std::uint64_t data_pos = pos;
      pos += data_len;
      if (!header_seen) {
        if (op != kBagHeader)
          corrupt(start, "the first record is not the bag header");
        header_seen = true;
        index_pos = field64(fields, "index_pos", start);
        if (index_pos == 0)
          throw Error(path_ + ": unindexed bag (its recording did not finish: rosbag reindex it)");
        if (index_pos > size_)
          throw Error(path_ + ": truncated or corrupt: read " + std::to_string(size_) + " of at least " +
                      std::to_string(index_pos) + " bytes (the index is at byte " + std::to_string(index_pos) +
                      ": a recording cut short, which rosbag reindex may recover)");
        if (index_pos < kMagicSize)
          corrupt(start, "the index position " + std::to_string(index_pos));
        continue;
      }
      switch (op) {
      case kChunk: {
        const std::string &c = field(fields, "compression", start);
        chunk_size = field32(fields, "size", start);
        chunk_data_pos = 0;
        if (chunk_size > kMaxChunk)
          corrupt(start, "a chunk of " + std::to_string(chunk_size) + " bytes");
        if (c == "none") {
          if (chunk_size != data_len)
            corrupt(start, "an uncompressed chunk of " + std::to_string(data_len) + " bytes says " +
                               std::to_string(chunk_size));
          chunk_data_pos = data_pos;
        } else if (c != "bz2" && c != "lz4") {
          corrupt(start, "a chunk compressed by '" + c + "' (rosbag knows none, bz2, lz4)");
        }
        after_chunk = true;
        break;
      }
      case kIndexData: {
        if (!after_chunk)
          corrupt(start, "an index record without its chunk");
        if (field32(fields, "ver", start) != 1)
          corrupt(start, "an index record of version other than 1");
        index_connections_.push_back(field32(fields, "conn", start));
        const std::uint32_t count = field32(fields, "count", start);
        if (std::uint64_t(count) * 12 != data_len)
          corrupt(start, "an index record of " + std::to_string(count) + " entries in " + std::to_string(data_len) +
                             " bytes");
        std::vector<std::uint8_t> d = readAt(data_pos, data_len);
        for (std::uint32_t k = 0; k < count; ++k) {
          const std::uint32_t offset = le32(&d[12 * k + 8]);
          if (offset >= chunk_size)
            corrupt(start, "an index entry points outside its chunk");
          if (chunk_data_pos != 0) // the message it names, read as rosbag_storage will
            checkMessage(chunk_data_pos + offset, chunk_size - offset);
        }
        break;
      }
      case kConnection:
        if (start >= index_pos)
          connections_.push_back(field32(fields, "conn", start));
        else
          field32(fields, "conn", start);
        field(fields, "topic", start);
        if (data_len < 4)
          corrupt(start, "a connection record without its header");
        headerFields(readAt(data_pos, data_len), where(start));
        break;
      case kChunkInfo:
        if (start < index_pos)
          corrupt(start, "a chunk info record before the index");
        {
          const std::uint64_t chunk_pos = field64(fields, "chunk_pos", start);
          if (chunk_pos < kMagicSize || chunk_pos >= index_pos)
            corrupt(start, "a chunk info record names a chunk at byte " + std::to_string(chunk_pos));
          chunk_positions_.push_back(chunk_pos);
          if (field32(fields, "ver", start) != 1)
            corrupt(start, "a chunk info record of version other than 1");
          if (std::uint64_t(field32(fields, "count", start)) * 8 != data_len)
            corrupt(start, "a chunk info record whose count does not match its size");
          field64(fields, "start_time", start);
          field64(fields, "end_time", start);
        }
        break;
      case kBagHeader:
        corrupt(start, "a second bag header");
      case kMsgData:
        corrupt(start, "a message outside a chunk");
      default:
        corrupt(start, "a record of unknown op " + std::to_string(op));
      }
      if (start == index_pos && op != kConnection && op != kChunkInfo)
        corrupt(start, "the index position does not start a connection or chunk info record");
    }
    if (!header_seen)
      truncated(size_, "no bag header");
    // Every index record's connection is one of the index's connection records.
    std::sort(connections_.begin(), connections_.end());
    for (std::uint32_t c : index_connections_)
      if (!std::binary_search(connections_.begin(), connections_.end(), c))
        corrupt(index_pos, "an index record names connection " + std::to_string(c) + ", which the index does not hold");
    // Every chunk info must name a chunk record.
    for (std::uint64_t c : chunk_positions_)
      if (!std::binary_search(chunks_.begin(), chunks_.end(), c))
        corrupt(c, "a chunk info record names byte " + std::to_string(c) + ", which is not a chunk");
  }

private:
  [[noreturn]] void truncated(std::uint64_t read, const std::string &why) const
  {
    throw Error(path_ + ": truncated or corrupt: " + why + " (read " + std::to_string(read) + " of " +
                std::to_string(size_) + " bytes)");
  }
  [[noreturn]] void corrupt(std::uint64_t at, const std::string &why) const
  {
    throw Error(path_ + ": truncated or corrupt: " + why + " at byte " + std::to_string(at) + " of " +
                std::to_string(size_));
  }
  std::string where(std::uint64_t at) const { return path_ + ": truncated or corrupt: at byte " + std::to_string(at); }

  std::vector<std::uint8_t> readAt(std::uint64_t pos, std::uint64_t n)
  {
    if (n > size_ || pos > size_ - n)
      truncated(size_, "a record of " + std::to_string(n) + " bytes at byte " + std::to_string(pos) + " runs past the end");
    std::vector<std::uint8_t> b(n);
    in_.clear();
    in_.seekg(std::streamoff(pos));
    in_.read(reinterpret_cast<char *>(b.data()), std::streamsize(n));
    if (!in_)
      truncated(pos, "cannot read " + std::to_string(n) + " bytes at byte " + std::to_string(pos));
    return b;
  }

  void readRecordHeader(std::uint64_t &pos, std::uint8_t &op, std::map<std::string, std::string> &fields,
                        std::uint32_t &data_len)
  {
    const std::uint64_t start = pos;
    if (size_ - pos < 4)
      truncated(pos, "a record header cut off at byte " + std::to_string(pos));
    const std::uint32_t header_len = le32(readAt(pos, 4).data());
    if (header_len > kMaxHeader)
      corrupt(start, "a record header of " + std::to_string(header_len) + " bytes");
    if (size_ - pos - 4 < std::uint64_t(header_len) + 4)
      truncated(pos, "a record cut off at byte " + std::to_string(pos));
    fields = headerFields(readAt(pos + 4, header_len), where(start));
    data_len = le32(readAt(pos + 4 + header_len, 4).data());
    pos += 8 + std::uint64_t(header_len);
    if (data_len > size_ - pos)
      truncated(pos, "a record of " + std::to_string(data_len) + " bytes at byte " + std::to_string(start) +
                         " runs past the end");
    const std::string &o = field(fields, "op", start);
    if (o.size() != 1)
      corrupt(start, "a record's op field is not one byte");
    op = std::uint8_t(o[0]);
    if (op == kChunk)
      chunks_.push_back(start);
  }

  /* The message record an index entry names in an uncompressed chunk: its header and data within
     the `room` bytes left in the chunk. */
  void checkMessage(std::uint64_t pos, std::uint64_t room)
  {
    if (room < 8)
      corrupt(pos, "a message cut off at the end of its chunk");
    const std::uint32_t hl = le32(readAt(pos, 4).data());
    if (hl > room - 8)
      corrupt(pos, "a message header runs past its chunk");
    const auto f = headerFields(readAt(pos + 4, hl), where(pos));
    const std::uint32_t dl = le32(readAt(pos + 4 + hl, 4).data());
    if (dl > room - 8 - hl)
      corrupt(pos, "a message runs past its chunk");
    const auto o = f.find("op");
    if (o == f.end() || o->second.size() != 1 || o->second[0] != char(kMsgData))
      corrupt(pos, "an index entry names a record that is not a message");
    field32(f, "conn", pos);
    field64(f, "time", pos);
  }

  const std::string &field(const std::map<std::string, std::string> &f, const char *name, std::uint64_t at) const
  {
    auto it = f.find(name);
    if (it == f.end())
      corrupt(at, std::string("a record without its '") + name + "' field");
    return it->second;
  }
  std::uint32_t field32(const std::map<std::string, std::string> &f, const char *name, std::uint64_t at) const
  {
    const std::string &v = field(f, name, at);
    if (v.size() != 4)
      corrupt(at, std::string("a record's '") + name + "' field is not 4 bytes");
    return le32(reinterpret_cast<const std::uint8_t *>(v.data()));
  }
  std::uint64_t field64(const std::map<std::string, std::string> &f, const char *name, std::uint64_t at) const
  {
    const std::string &v = field(f, name, at);
    if (v.size() != 8)
      corrupt(at, std::string("a record's '") + name + "' field is not 8 bytes");
    return le64(reinterpret_cast<const std::uint8_t *>(v.data()));
  }

  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0;
  std::vector<std::uint64_t> chunks_, chunk_positions_;
  std::vector<std::uint32_t> connections_, index_connections_;
};

ros::Time rosTime(std::int64_t ns)
{
  if (ns <= 1)
    return ros::TIME_MIN;
  if (ns >= std::int64_t(0xffffffffLL) * 1000000000LL)
    return ros::TIME_MAX;
  ros::Time t;
  t.fromNSec(std::uint64_t(ns));
  return t;
}

class Ros1Reader final : public BagReader {
public:
  explicit Ros1Reader(const std::string &path) : path_(path)
  {
    Ros1Checker(path).check();
    try {
      bag_.open(path, rosbag::bagmode::Read);
      rosbag::View all(bag_);
      std::map<std::string, std::size_t> by_name;
      for (const rosbag::ConnectionInfo *c : all.getConnections()) {
        auto it = by_name.find(c->topic);
        if (it == by_name.end()) {
          by_name[c->topic] = topics_.size();
          BagTopic t;
          t.name = c->topic;
          t.type = c->datatype;
          t.encoding = BagEncoding::Ros1;
          topics_.push_back(t);
        } else if (topics_[it->second].type != c->datatype) { // refused when it is read
          mixed_[c->topic] = topics_[it->second].type + " and " + c->datatype;
        }
      }
      std::sort(topics_.begin(), topics_.end(), [](const BagTopic &a, const BagTopic &b) { return a.name < b.name; });
      for (BagTopic &t : topics_)
        t.messages = rosbag::View(bag_, rosbag::TopicQuery(t.name)).size();
    } catch (const rosbag::BagUnindexedException &) {
      throw Error(path + ": unindexed bag (its recording did not finish: rosbag reindex it)");
    } catch (const rosbag::BagException &e) {
      throw Error(path + ": truncated or corrupt: " + e.what());
    } catch (const ros::Exception &e) {
      throw Error(path + ": truncated or corrupt: " + e.what());
    } catch (const std::runtime_error &e) {
      if (dynamic_cast<const Error *>(&e))
        throw;
      throw Error(path + ": truncated or corrupt: " + e.what());
    }
  }

  BagFormat format() const override { return BagFormat::Ros1; }
  const std::string &path() const override { return path_; }
  const std::vector<BagTopic> &topics() const override { return topics_; }

  void read(const BagReadOptions &options, const std::function<bool(const BagMessage &)> &visit) override
  {
    std::vector<std::string> names = options.topics;
    if (names.empty())
      for (const BagTopic &t : topics_)
        names.push_back(t.name);
    names.erase(std::remove_if(names.begin(), names.end(), [&](const std::string &n) { return !topic(n); }),
                names.end());
    if (names.empty() || options.end < options.start)
      return;
    for (const std::string &n : options.topics) // (a read of every topic passes them as the first type)
      if (mixed_.count(n))
        throw Error(path_ + ": topic " + n + " has messages of two types, " + mixed_.at(n));
    std::int64_t last_good = INT64_MIN;
    std::uint64_t visited = 0;
    std::vector<std::uint8_t> buffer;
    bool in_visit = false; // the visitor's own exceptions pass through
    try {
      rosbag::View view(bag_, rosbag::TopicQuery(names), rosTime(options.start), rosTime(options.end));
      for (const rosbag::MessageInstance &m : view) {
        const std::int64_t t = std::int64_t(m.getTime().toNSec());
        if (t < options.start || t > options.end)
          continue;
        const BagTopic *tp = topic(m.getTopic());
        if (!tp)
          continue;
        const std::uint32_t n = m.size();
        buffer.resize(std::max<std::size_t>(n, 1));
        ros::serialization::OStream os(buffer.data(), n);
        m.write(os);
        BagMessage msg;
        msg.topic = tp;
        msg.log_time = t;
        msg.data = buffer.data();
        msg.size = n;
        ++visited;
        in_visit = true;
        if (!visit(msg))
          return;
        in_visit = false;
        last_good = t;
      }
    } catch (const Error &) {
      throw;
    } catch (const std::exception &e) {
      if (in_visit)
        throw;
      throw Error(path_ + ": truncated or corrupt: " + e.what() + " (after " + std::to_string(visited) + " messages" +
                  (last_good == INT64_MIN ? std::string() : ", last good message at t = " + secondsText(last_good) + " s") +
                  ")");
    }
  }

private:
  std::string path_;
  rosbag::Bag bag_;
  std::vector<BagTopic> topics_;
  std::map<std::string, std::string> mixed_; // topics recorded with two types: "A and B"
};

} // namespace

std::unique_ptr<BagReader> openRos1(const std::string &path)
{
  // rosbag_storage logs through console_bridge (to stderr); the library never prints: its
  // exceptions carry the reasons.
  static const bool quiet = [] {
    console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
    return true;
  }();
  (void)quiet;
  return std::make_unique<Ros1Reader>(path);
}

} // namespace bag_detail
} // namespace yawdepth
