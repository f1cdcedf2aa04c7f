// rosbag2's compression (rosbag2_compression, its only compressor plugin: zstd), undone as the bag is
// opened and read. Two modes, as the bag's metadata.yaml says (compression_mode) and as the bytes
// show, so that a storage file given alone is read as well:
//   FILE     each storage file is one zstd stream ("bag_0.db3.zstd", "bag_0.mcap.zstd"): decompressed
//            into a scratch file (SQLite needs a file), a buffer at a time, before the container is
//            opened; the scratch file is removed when the reader goes (or the program is interrupted).
//   MESSAGE  each message's serialized bytes are one zstd frame: decompressed as they are read, into a
//            buffer reused from message to message; a CDR message never starts with zstd's magic
//            number (its encapsulation header is 00 00 or 00 01), so the bytes tell which is which.
// Every message names the files the user gave, never a scratch file.
#include "readers.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <memory>
#include <unistd.h>
#include <vector>
#include <zstd.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {

namespace {

constexpr std::size_t kMaxMessageBytes = std::size_t(1) << 30; // as the MCAP reader's chunks

using Dctx = std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)>;

/* Whether `data` starts with a zstd frame's magic number (ZSTD_MAGICNUMBER, little endian). */
bool zstdMagic(const void *data, std::size_t size)
{
  static const unsigned char kMagic[4] = {ZSTD_MAGICNUMBER & 0xFF, (ZSTD_MAGICNUMBER >> 8) & 0xFF,
                                          (ZSTD_MAGICNUMBER >> 16) & 0xFF, (ZSTD_MAGICNUMBER >> 24) & 0xFF};
  return size >= 4 && std::memcmp(data, kMagic, 4) == 0;
}

Dctx newContext(const std::string &where)
{
  Dctx ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!ctx)
    throw Error(where + "cannot create a zstd decompression context");
  return ctx;
}

/* A file descriptor closed when it goes. */
struct Fd {
  int fd = -1;
  ~Fd()
  {
    if (fd >= 0)
      ::close(fd);
  }
};

/* `from` (a zstd stream, rosbag2's FILE mode) decompressed into `to`; errors name `from`. */
void decompressFile(const std::string &from, const std::string &to)
{
  Fd in{::open(from.c_str(), O_RDONLY | O_CLOEXEC)}, out{::open(to.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC)};
  if (in.fd < 0)
    throw Error(from + ": cannot open: " + std::strerror(errno));
  if (out.fd < 0)
    throw Error(from + ": cannot write its decompressed copy " + to + ": " + std::strerror(errno));
  Dctx ctx = newContext(from + ": ");
  std::vector<char> ibuf(ZSTD_DStreamInSize()), obuf(ZSTD_DStreamOutSize());
  std::size_t read_total = 0, pending = 0; // pending: 0 when the last frame ended
  for (;;) {
    const ssize_t n = ::read(in.fd, ibuf.data(), ibuf.size());
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      throw Error(from + ": read error after " + std::to_string(read_total) + " bytes: " + std::strerror(errno));
    if (n == 0)
      break;
    read_total += std::size_t(n);
    ZSTD_inBuffer ib{ibuf.data(), std::size_t(n), 0};
    while (ib.pos < ib.size) {
      ZSTD_outBuffer ob{obuf.data(), obuf.size(), 0};
      pending = ZSTD_decompressStream(ctx.get(), &ob, &ib);
      if (ZSTD_isError(pending))
        throw Error(from + ": zstd decompression failed after " + std::to_string(read_total) +
                    " bytes read: " + ZSTD_getErrorName(pending) + " (a corrupt compressed bag)");
      for (std::size_t done = 0; done < ob.pos;) {
        const ssize_t w = ::write(out.fd, obuf.data() + done, ob.pos - done);
        if (w < 0 && errno == EINTR)
          continue;
        if (w < 0)
          throw Error(from + ": cannot write its decompressed copy " + to + ": " + std::strerror(errno));
        done += std::size_t(w);
      }
    }
  }
  if (pending != 0 || read_total == 0)
    throw Error(from + ": truncated: the zstd stream ends unfinished after " + std::to_string(read_total) +
                " bytes (a compressed bag cut short)");
}

/* Error `e` again, each scratch file's path replaced by the file it was decompressed from. */
[[noreturn]] void rethrowNamed(const Error &e, const std::vector<std::pair<std::string, std::string>> &names)
{
  std::string what = e.what();
  for (const auto &[scratch, original] : names)
    for (std::size_t at = what.find(scratch); at != std::string::npos; at = what.find(scratch, at + original.size()))
      what.replace(at, scratch.size(), original);
  throw Error(what);
}

bool ros2(BagFormat f) { return f == BagFormat::Mcap || f == BagFormat::Sqlite3; }

/* The container's reader, its scratch files kept alive, its messages decompressed. */
class Rosbag2Reader : public BagReader {
public:
  Rosbag2Reader(std::string name, std::unique_ptr<BagReader> inner, std::vector<std::unique_ptr<ScratchFile>> scratch,
                std::vector<std::pair<std::string, std::string>> names)
      : name_(std::move(name)), inner_(std::move(inner)), scratch_(std::move(scratch)), names_(std::move(names)),
        ctx_(nullptr, ZSTD_freeDCtx)
  {
  }

  BagFormat format() const override { return inner_->format(); }
  const std::string &path() const override { return name_; }
  const std::vector<BagTopic> &topics() const override { return inner_->topics(); }

  void read(const BagReadOptions &options, const std::function<bool(const BagMessage &)> &visit) override
  {
    const bool messages = ros2(inner_->format());
    try {
      inner_->read(options, [&](const BagMessage &m) {
        if (!messages || !zstdMagic(m.data, m.size))
          return visit(m);
        BagMessage d = m;
        d.size = decompress(m);
        d.data = buffer_.data();
        return visit(d);
      });
    } catch (const Error &e) {
      rethrowNamed(e, names_);
    }
  }

private:
  /* One message's zstd frame(s) into buffer_; its decompressed size. */
  std::size_t decompress(const BagMessage &m)
  {
    const std::string where = messageWhere(m);
    if (!ctx_)
      ctx_ = newContext(where);
    ZSTD_DCtx_reset(ctx_.get(), ZSTD_reset_session_only);
    const unsigned long long declared = ZSTD_getFrameContentSize(m.data, m.size);
    if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != ZSTD_CONTENTSIZE_ERROR && declared > kMaxMessageBytes)
      throw Error(where + "a zstd-compressed message of " + std::to_string(declared) + " bytes, over the 1 GiB limit");
    if (buffer_.size() < 4096)
      buffer_.resize(4096);
    if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != ZSTD_CONTENTSIZE_ERROR && declared > buffer_.size())
      buffer_.resize(std::size_t(declared));
    ZSTD_inBuffer ib{m.data, m.size, 0};
    std::size_t used = 0, pending = 1;
    while (ib.pos < ib.size || pending != 0) {
      if (used == buffer_.size()) {
        if (buffer_.size() >= kMaxMessageBytes)
          throw Error(where + "a zstd-compressed message over the 1 GiB limit");
        buffer_.resize(std::min(kMaxMessageBytes, 2 * buffer_.size()));
      }
      ZSTD_outBuffer ob{buffer_.data(), buffer_.size(), used};
      const std::size_t before_in = ib.pos;
      pending = ZSTD_decompressStream(ctx_.get(), &ob, &ib);
      if (ZSTD_isError(pending))
        throw Error(where + "a zstd-compressed message (rosbag2's MESSAGE compression) that does not decompress: " +
                    ZSTD_getErrorName(pending));
      if (ib.pos == ib.size && pending != 0 && ob.pos == used && ib.pos == before_in)
        throw Error(where + "a zstd-compressed message cut short (" + std::to_string(m.size) + " bytes)");
      used = ob.pos;
    }
    return used;
  }

  std::string name_;
  std::unique_ptr<BagReader> inner_;
  std::vector<std::unique_ptr<ScratchFile>> scratch_;
  std::vector<std::pair<std::string, std::string>> names_; // scratch path -> the file it came from
  Dctx ctx_;
  std::vector<std::uint8_t> buffer_;
};

} // namespace

bool zstdFile(const std::string &path)
{
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return false; // a pipe's first bytes are the container's to read
  unsigned char magic[4] = {0, 0, 0, 0};
  FILE *f = std::fopen(path.c_str(), "rb");
  if (!f)
    return false;
  const std::size_t n = std::fread(magic, 1, 4, f);
  std::fclose(f);
  return n == 4 && zstdMagic(magic, 4);
}

std::unique_ptr<BagReader> openRosbag2(const std::string &name, const std::vector<std::string> &files,
                                       const OpenContainer &open)
{
  std::vector<std::unique_ptr<ScratchFile>> scratch;
  std::vector<std::pair<std::string, std::string>> names;
  std::vector<std::string> storage;
  for (const std::string &f : files) {
    if (!zstdFile(f)) {
      storage.push_back(f);
      continue;
    }
    // bag_0.db3.zstd -> a scratch file ending in .db3 (the readers tell the container by its bytes).
    std::string stem = f.substr(f.find_last_of('/') + 1);
    if (stem.size() > 5 && stem.compare(stem.size() - 5, 5, ".zstd") == 0)
      stem.resize(stem.size() - 5);
    const std::size_t dot = stem.find_last_of('.');
    scratch.push_back(std::make_unique<ScratchFile>(dot == std::string::npos ? std::string() : stem.substr(dot)));
    decompressFile(f, scratch.back()->path());
    names.emplace_back(scratch.back()->path(), f);
    storage.push_back(scratch.back()->path());
  }
  std::unique_ptr<BagReader> inner;
  try {
    inner = open(storage.front(), name, storage);
  } catch (const Error &e) {
    rethrowNamed(e, names);
  }
  if (scratch.empty() && !ros2(inner->format()))
    return inner; // a ROS 1 bag: nothing to undo
  return std::make_unique<Rosbag2Reader>(name, std::move(inner), std::move(scratch), std::move(names));
}

} // namespace bag_detail
} // namespace yawdepth
