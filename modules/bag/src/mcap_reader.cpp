// The MCAP reader (https://mcap.dev/spec): records read from the file in order, chunks
// decompressed one at a time (none, zstd, lz4 frames; CRCs by zlib), topics from the summary's Channel and
// Statistics records or, for a file without a summary, from a scan of its data section.
#include "readers.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <lz4frame.h>
#include <map>
#include <set>
#include <yawdepth/error.h>
#include <zlib.h>
#include <zstd.h>

namespace yawdepth {
namespace bag_detail {

namespace {

constexpr std::uint64_t kMaxRecord = std::uint64_t(1) << 30; // a record or chunk read into memory
const std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::uint64_t kFooterRecord = 1 + 8 + 20; // opcode, length, summary_start, summary_offset_start, crc

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

std::string opName(std::uint8_t op)
{
  static const char *names[] = {nullptr,      "Header",     "Footer",        "Schema",     "Channel", "Message",
                                "Chunk",      "MessageIndex", "ChunkIndex",  "Attachment", "AttachmentIndex",
                                "Statistics", "Metadata",   "MetadataIndex", "SummaryOffset", "DataEnd"};
  if (op >= 1 && op <= 0x0F)
    return names[op];
  char s[32];
  std::snprintf(s, sizeof s, "unknown (opcode 0x%02x)", op);
  return s;
}


/* MCAP's CRC-32 is zlib's (the IEEE polynomial). */
std::uint32_t crc32(std::uint32_t crc, const std::uint8_t *p, std::size_t n)
{
  while (n > 0) { // zlib takes a uInt length
    const uInt step = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    crc = static_cast<std::uint32_t>(::crc32(crc, p, step));
    p += step;
    n -= step;
  }
  return crc;
}

std::uint64_t le(const std::uint8_t *p, int n)
{
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i)
    v = (v << 8) | p[i];
  return v;
}

/* Where a record is, for the messages: "<path>: a Channel record at byte 123" or
   "<path>: chunk at byte 456: a Channel record at offset 78". */
struct Where {
  const std::string *path = nullptr;
  std::uint64_t pos = 0;
  std::uint8_t op = 0;
  std::int64_t chunk = -1;
  std::string str() const
  {
    if (chunk >= 0)
      return *path + ": chunk at byte " + std::to_string(chunk) + ": " + opName(op) + " record at offset " +
             std::to_string(pos) + " of the chunk";
    return *path + ": " + opName(op) + " record at byte " + std::to_string(pos);
  }
};

/* A record's content, read field by field, never past its end. */
class Fields {
public:
  Fields(const std::uint8_t *p, std::size_t n, const Where &w) : p_(p), n_(n), w_(w) {}
  std::uint8_t u8() { return std::uint8_t(le(take(1), 1)); }
  std::uint16_t u16() { return std::uint16_t(le(take(2), 2)); }
  std::uint32_t u32() { return std::uint32_t(le(take(4), 4)); }
  std::uint64_t u64() { return le(take(8), 8); }
  std::string str()
  {
    const std::uint32_t len = u32();
    const std::uint8_t *s = take(len);
    return std::string(reinterpret_cast<const char *>(s), len);
  }
  /* uint32-length-prefixed bytes (a Schema's data, a map's content). */
  Fields sub32()
  {
    const std::uint32_t len = u32();
    return Fields(take(len), len, w_);
  }
  const std::uint8_t *rest(std::size_t &len)
  {
    len = n_ - pos_;
    const std::uint8_t *r = p_ + pos_;
    pos_ = n_;
    return r;
  }
  bool done() const { return pos_ == n_; }
  std::size_t pos() const { return pos_; }
  [[noreturn]] void fail(const std::string &why) const { throw Error(w_.str() + ": " + why); }

private:
  const std::uint8_t *take(std::size_t k)
  {
    if (k > n_ - pos_)
      fail("a field at offset " + std::to_string(pos_) + " needs " + std::to_string(k) + " bytes, the record has " +
           std::to_string(n_ - pos_) + " left (corrupt record)");
    const std::uint8_t *r = p_ + pos_;
    pos_ += k;
    return r;
  }
  const std::uint8_t *p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  const Where &w_;
};

/* One storage file: its size, whether it ends with a footer, its schemas and channels. */
struct McapFile {
  std::string path;
  std::ifstream in;
  std::uint64_t size = 0;
  bool complete = false;           // ends with a Footer record and the magic
  std::uint64_t summary_start = 0; // 0: no summary
  std::map<std::uint16_t, std::string> schemas;  // id -> name
  std::map<std::uint16_t, std::size_t> channels; // id -> topic index

  void readAt(std::uint64_t at, void *dst, std::size_t n)
  {
    in.clear();
    in.seekg(std::streamoff(at));
    in.read(static_cast<char *>(dst), std::streamsize(n));
    if (!in || std::size_t(in.gcount()) != n)
      throw Error(path + ": cannot read " + std::to_string(n) + " bytes at byte " + std::to_string(at) +
                  " (the file changed or the disk failed)");
  }
};

struct Visit {
  std::int64_t start = INT64_MIN, end = INT64_MAX;
  std::vector<bool> topics;                                   // selected topic indices (empty: all)
  const std::function<bool(const BagMessage &)> *visit = nullptr; // nullptr: count only (the open scan)
};

class McapReader final : public BagReader {
public:
  McapReader(std::string path, const std::vector<std::string> &files) : path_(std::move(path))
  {
    for (const std::string &f : files) {
      auto file = std::make_unique<McapFile>();
      file->path = f;
      openFile(*file);
      files_.push_back(std::move(file));
    }
  }

  BagFormat format() const override { return BagFormat::Mcap; }
  const std::string &path() const override { return path_; }
  const std::vector<BagTopic> &topics() const override { return topics_; }

  void read(const BagReadOptions &options, const std::function<bool(const BagMessage &)> &visit) override
  {
    Visit v;
    v.start = options.start;
    v.end = options.end;
    v.visit = &visit;
    if (!options.topics.empty()) {
      v.topics.assign(topics_.size(), false);
      for (const std::string &name : options.topics)
        for (std::size_t i = 0; i < topics_.size(); ++i)
          if (topics_[i].name == name)
            v.topics[i] = true;
    }
    have_last_ = false;
    for (auto &f : files_)
      if (!walk(*f, v))
        return;
  }

private:
  void openFile(McapFile &f)
  {
    f.in.open(f.path, std::ios::binary);
    if (!f.in)
      throw Error(f.path + ": cannot open the bag");
    f.in.seekg(0, std::ios::end);
    f.size = std::uint64_t(f.in.tellg());
    std::uint8_t magic[8] = {};
    if (f.size < 8)
      throw Error(f.path + ": truncated at byte " + std::to_string(f.size) + " of 8 (in the MCAP magic)");
    f.readAt(0, magic, 8);
    if (std::memcmp(magic, kMagic, 8) != 0)
      throw Error(f.path + ": not an MCAP file (bad magic)");
    bool have_channels = false;
    if (f.size >= 8 + kFooterRecord + 8) {
      std::uint8_t tail[kFooterRecord + 8];
      const std::uint64_t footer = f.size - 8 - kFooterRecord;
      f.readAt(footer, tail, sizeof tail);
      if (std::memcmp(tail + kFooterRecord, kMagic, 8) == 0 && tail[0] == kFooter && le(tail + 1, 8) == 20) {
        f.complete = true;
        const std::uint64_t summary_start = le(tail + 9, 8);
        const std::uint32_t summary_crc = std::uint32_t(le(tail + 25, 4));
        if (summary_start != 0) {
          if (summary_start < 8 || summary_start > footer)
            throw Error(f.path + ": the footer's summary_start " + std::to_string(summary_start) +
                        " is outside the file (corrupt footer)");
          f.summary_start = summary_start;
          if (footer - summary_start <= kMaxRecord)
            have_channels = readSummary(f, footer, tail, summary_crc);
        }
      }
    }
    if (!have_channels) {
      // No summary: a pass over the data section finds the channels and counts the messages; it stops
      // quietly at damage, which read() then reports after the messages before it.
      Visit count;
      try {
        walk(f, count);
      } catch (const Error &) {
      }
    }
  }

  /* The summary section: schemas, channels, statistics. Returns whether it had channels. */
  bool readSummary(McapFile &f, std::uint64_t footer, const std::uint8_t *tail, std::uint32_t crc)
  {
    std::vector<std::uint8_t> s(std::size_t(footer - f.summary_start));
    if (!s.empty())
      f.readAt(f.summary_start, s.data(), s.size());
    if (crc != 0) {
      const std::uint32_t c = crc32(crc32(0, s.data(), s.size()), tail, 1 + 8 + 8 + 8);
      if (c != crc)
        throw Error(f.path + ": summary section CRC mismatch (corrupt file)");
    }
    struct Chan {
      std::uint16_t schema;
      std::string topic, encoding;
    };
    std::map<std::uint16_t, Chan> chans;
    std::map<std::uint16_t, std::uint64_t> counts;
    std::size_t pos = 0;
    while (pos < s.size()) {
      Where w{&f.path, f.summary_start + pos, 0, -1};
      if (s.size() - pos < 9)
        throw Error(f.path + ": summary section: a record header at byte " + std::to_string(w.pos) +
                    " runs into the footer (corrupt summary)");
      w.op = s[pos];
      const std::uint64_t len = le(&s[pos + 1], 8);
      if (len > s.size() - pos - 9)
        throw Error(w.str() + ": its length " + std::to_string(len) + " runs past the summary section (corrupt summary)");
      Fields r(&s[pos + 9], std::size_t(len), w);
      if (w.op == kSchema) {
        const std::uint16_t id = r.u16();
        f.schemas[id] = r.str();
      } else if (w.op == kChannel) {
        Chan c;
        const std::uint16_t id = r.u16();
        c.schema = r.u16();
        c.topic = r.str();
        c.encoding = r.str();
        chans[id] = c;
      } else if (w.op == kStatistics) {
        r.u64();                                   // message_count
        r.u16();                                   // schema_count
        r.u32(), r.u32(), r.u32(), r.u32();        // channel, attachment, metadata, chunk counts
        r.u64(), r.u64();                          // message start and end times
        Fields m = r.sub32();
        while (!m.done()) {
          const std::uint16_t id = m.u16();
          counts[id] = m.u64();
        }
      }
      pos += 9 + std::size_t(len);
    }
    for (const auto &c : chans) {
      const std::size_t t = addChannel(f, c.first, c.second.schema, c.second.topic, c.second.encoding,
                                       Where{&f.path, f.summary_start, kChannel, -1});
      const auto n = counts.find(c.first);
      if (n != counts.end())
        topics_[t].messages += n->second;
    }
    return !chans.empty();
  }

  std::size_t addChannel(McapFile &f, std::uint16_t id, std::uint16_t schema, const std::string &topic,
                         const std::string &encoding, const Where &w)
  {
    std::string type;
    if (schema != 0) {
      const auto s = f.schemas.find(schema);
      if (s == f.schemas.end())
        throw Error(w.str() + ": channel " + std::to_string(id) + " (" + topic + ") names schema " +
                    std::to_string(schema) + ", which was never defined");
      type = s->second;
      const std::size_t m = type.find("/msg/");
      if (m != std::string::npos)
        type.erase(m, 4); // ROS 2's "pkg/msg/Type" is ROS 1's "pkg/Type"
    }
    BagEncoding enc = BagEncoding::Cdr;
    if (encoding == "ros1")
      enc = BagEncoding::Ros1;
    else if (encoding != "cdr")
      type += " (" + encoding + " encoding)"; // no decoder takes it
    for (std::size_t i = 0; i < topics_.size(); ++i)
      if (topics_[i].name == topic) {
        f.channels[id] = i;
        return i;
      }
    BagTopic t;
    t.name = topic;
    t.type = type;
    t.encoding = enc;
    topics_.push_back(t);
    f.channels[id] = topics_.size() - 1;
    return topics_.size() - 1;
  }

  [[noreturn]] void truncated(const McapFile &f, std::uint64_t needed, const std::string &in) const
  {
    throw Error(f.path + ": truncated at byte " + std::to_string(f.size) + " of " + std::to_string(needed) + " (in " +
                in + "); " + (have_last_ ? "last message read at t = " + secondsText(last_) + " s" : "no message read"));
  }

  /* Schema, Channel and Message records (in the data section or a chunk). Returns false to stop. */
  bool record(McapFile &f, const Where &w, const std::uint8_t *p, std::size_t n, Visit &v)
  {
    Fields r(p, n, w);
    if (w.op == kSchema) {
      const std::uint16_t id = r.u16();
      f.schemas[id] = r.str();
    } else if (w.op == kChannel) {
      const std::uint16_t id = r.u16();
      const std::uint16_t schema = r.u16();
      const std::string topic = r.str();
      const std::string encoding = r.str();
      if (!f.channels.count(id)) {
        const std::size_t t = addChannel(f, id, schema, topic, encoding, w);
        if (!v.topics.empty() && t >= v.topics.size())
          v.topics.resize(t + 1, false);
      }
    } else if (w.op == kMessage) {
      const std::uint16_t id = r.u16();
      r.u32(); // sequence
      const std::int64_t log_time = std::int64_t(r.u64());
      r.u64(); // publish_time
      std::size_t size = 0;
      const std::uint8_t *data = r.rest(size);
      const auto c = f.channels.find(id);
      if (c == f.channels.end())
        r.fail("a message on channel " + std::to_string(id) + ", which was never defined");
      last_ = log_time;
      have_last_ = true;
      if (!v.visit) {
        ++topics_[c->second].messages;
        return true;
      }
      if (log_time < v.start || log_time > v.end || (!v.topics.empty() && !v.topics[c->second]))
        return true;
      BagMessage m;
      m.topic = &topics_[c->second];
      m.log_time = log_time;
      m.data = data;
      m.size = size;
      return (*v.visit)(m);
    }
    return true;
  }

  /* The data section of `f` in file order. Returns false when the visit stopped. */
  bool walk(McapFile &f, Visit &v)
  {
    std::uint64_t pos = 8;
    const std::uint64_t end = f.summary_start ? f.summary_start : f.size;
    while (pos < end) {
      std::uint8_t h[9];
      if (f.size - pos < 9)
        truncated(f, pos + 9, "a record header at byte " + std::to_string(pos));
      f.readAt(pos, h, 9);
      Where w{&f.path, pos, h[0], -1};
      const std::uint64_t len = le(h + 1, 8);
      const std::uint64_t body = pos + 9;
      if (len > f.size - body) {
        if (f.complete)
          throw Error(w.str() + ": its length " + std::to_string(len) + " runs beyond the file's end (" +
                      std::to_string(f.size) + " bytes; corrupt file)");
        truncated(f, len > UINT64_MAX - body ? UINT64_MAX : body + len, "a " + opName(h[0]) + " record at byte " + std::to_string(pos));
      }
      if (w.op == kDataEnd || w.op == kFooter)
        return true;
      if (w.op == kSchema || w.op == kChannel || w.op == kMessage) {
        if (len > kMaxRecord)
          throw Error(w.str() + ": " + std::to_string(len) + " bytes, over the 1 GiB limit of a record");
        buf_.resize(std::size_t(len));
        if (len)
          f.readAt(body, buf_.data(), buf_.size());
        if (!record(f, w, buf_.data(), buf_.size(), v))
          return false;
      } else if (w.op == kChunk) {
        if (!chunk(f, w, len, v))
          return false;
      }
      pos = body + len; // any other record, known or not, skipped by its length
    }
    if (f.summary_start == 0)
      truncated(f, f.size + 1, "the data section: no Data End record");
    return true;
  }

  bool chunk(McapFile &f, const Where &w, std::uint64_t len, Visit &v)
  {
    if (len > kMaxRecord + 4096)
      throw Error(w.str() + ": " + std::to_string(len) + " bytes, over the 1 GiB limit of a chunk");
    packed_.resize(std::size_t(len));
    if (len)
      f.readAt(w.pos + 9, packed_.data(), packed_.size());
    Fields r(packed_.data(), packed_.size(), w);
    const std::int64_t t0 = std::int64_t(r.u64()), t1 = std::int64_t(r.u64());
    const std::uint64_t usize = r.u64();
    const std::uint32_t ucrc = r.u32();
    const std::string compression = r.str();
    const std::uint64_t rlen = r.u64();
    std::size_t avail = 0;
    const std::uint8_t *records = r.rest(avail);
    const std::string where = f.path + ": chunk at byte " + std::to_string(w.pos);
    if (rlen > avail)
      throw Error(where + ": its records say " + std::to_string(rlen) + " bytes, the chunk holds " +
                  std::to_string(avail) + " (corrupt chunk)");
    if (compression != "" && compression != "zstd" && compression != "lz4")
      throw Error(where + ": unknown compression '" + compression + "'");
    if (usize > kMaxRecord)
      throw Error(where + ": uncompressed size " + std::to_string(usize) + " over the 1 GiB limit of a chunk");
    if (v.visit && (t1 < v.start || t0 > v.end) && rlen > 0 && t0 <= t1)
      return true; // wholly outside the time window (its channels are known from the summary or the open scan)
    const std::uint8_t *u = records;
    if (compression.empty()) {
      if (rlen != usize)
        throw Error(where + ": uncompressed records of " + std::to_string(rlen) + " bytes, its uncompressed_size says " +
                    std::to_string(usize) + " (corrupt chunk)");
    } else {
      // Decompressed into a buffer grown as output comes (a corrupt uncompressed_size costs no
      // memory), up to one byte more than it says: output beyond it is seen.
      const std::size_t cap = std::size_t(usize) + 1;
      const std::size_t got = compression == "zstd" ? zstd(where, records, std::size_t(rlen), cap)
                                                    : lz4(where, records, std::size_t(rlen), cap);
      if (got != usize)
        throw Error(where + ": decompressed to " + (got > usize ? "more than " + std::to_string(usize) : std::to_string(got)) +
                    " bytes, its uncompressed_size says " + std::to_string(usize) + " (corrupt chunk)");
      u = plain_.data();
    }
    if (ucrc != 0 && crc32(0, u, std::size_t(usize)) != ucrc)
      throw Error(where + ": CRC mismatch of its uncompressed records (corrupt chunk)");
    std::size_t pos = 0;
    while (pos < usize) {
      Where iw{&f.path, pos, 0, std::int64_t(w.pos)};
      if (usize - pos < 9)
        throw Error(where + ": a record header at offset " + std::to_string(pos) + " runs past the chunk's end (corrupt chunk)");
      iw.op = u[pos];
      const std::uint64_t ilen = le(u + pos + 1, 8);
      if (ilen > usize - pos - 9)
        throw Error(iw.str() + ": its length " + std::to_string(ilen) + " runs past the chunk's end (corrupt chunk)");
      if (!record(f, iw, u + pos + 9, std::size_t(ilen), v))
        return false;
      pos += 9 + std::size_t(ilen);
    }
    return true;
  }

  /* Makes room for more output in plain_ (first 4 times the input `n`, then doubling, at most `cap`
     bytes); false when it is full. */
  bool grow(std::size_t out, std::size_t cap, std::size_t n)
  {
    if (out < plain_.size())
      return true;
    if (plain_.size() >= cap)
      return false;
    const std::size_t first = n < (SIZE_MAX >> 3) ? std::max<std::size_t>(4 * n, 1 << 16) : cap;
    plain_.resize(std::min(cap, plain_.empty() ? first : plain_.size() * 2));
    return true;
  }

  std::size_t zstd(const std::string &where, const std::uint8_t *src, std::size_t n, std::size_t cap)
  {
    if (!zstd_)
      zstd_.reset(ZSTD_createDStream());
    ZSTD_DStream *ds = zstd_.get();
    if (!ds || ZSTD_isError(ZSTD_DCtx_reset(ds, ZSTD_reset_session_only)))
      throw Error(where + ": cannot create a zstd decompression context");
    ZSTD_inBuffer in{src, n, 0};
    std::size_t out = 0, ret = 1, consumed = 0;
    plain_.clear();
    while (grow(out, cap, n)) {
      ZSTD_outBuffer o{plain_.data(), plain_.size(), out};
      ret = ZSTD_decompressStream(ds, &o, &in);
      if (ZSTD_isError(ret))
        throw Error(where + ": zstd decompression failed: " + ZSTD_getErrorName(ret) + " (corrupt chunk)");
      const bool progress = o.pos > out || in.pos > consumed;
      out = o.pos;
      consumed = in.pos;
      if ((in.pos == in.size && ret == 0) || (!progress && out < plain_.size()))
        break; // the last frame ended, or no progress (the input ended inside a frame)
    }
    if (out < cap && ret != 0)
      throw Error(where + ": zstd frame cut short (corrupt chunk)");
    return out;
  }

  std::size_t lz4(const std::string &where, const std::uint8_t *src, std::size_t n, std::size_t cap)
  {
    if (!lz4_) {
      LZ4F_dctx *raw = nullptr;
      if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION)))
        throw Error(where + ": cannot create an lz4 decompression context");
      lz4_.reset(raw);
    }
    LZ4F_dctx *ctx = lz4_.get();
    LZ4F_resetDecompressionContext(ctx); // after a corrupt frame too
    std::size_t in = 0, out = 0, ret = 1;
    plain_.clear();
    while (grow(out, cap, n)) {
      std::size_t dst = plain_.size() - out, srcn = n - in;
      ret = LZ4F_decompress(ctx, plain_.data() + out, &dst, src + in, &srcn, nullptr);
      if (LZ4F_isError(ret))
        throw Error(where + ": lz4 decompression failed: " + LZ4F_getErrorName(ret) + " (corrupt chunk)");
      in += srcn;
      out += dst;
      if ((in == n && ret == 0) || (dst == 0 && srcn == 0 && out < plain_.size()))
        break; // the last frame ended, or no progress (the input ended inside a frame)
    }
    if (out < cap && ret != 0)
      throw Error(where + ": lz4 frame cut short (corrupt chunk)");
    return out;
  }

  std::string path_;
  std::vector<std::unique_ptr<McapFile>> files_;
  std::vector<BagTopic> topics_;
  std::vector<std::uint8_t> buf_, packed_, plain_;
  // The decompression contexts, kept from chunk to chunk.
  std::unique_ptr<ZSTD_DStream, decltype(&ZSTD_freeDStream)> zstd_{nullptr, ZSTD_freeDStream};
  std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> lz4_{nullptr, LZ4F_freeDecompressionContext};
  std::int64_t last_ = 0;
  bool have_last_ = false;
};

} // namespace

std::unique_ptr<BagReader> openMcap(const std::string &path, const std::vector<std::string> &files)
{
  return std::make_unique<McapReader>(path, files);
}

} // namespace bag_detail
} // namespace yawdepth
