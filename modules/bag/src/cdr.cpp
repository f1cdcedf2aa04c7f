// The CDR reader of cdr.h.
#include "cdr.h"

#include <cstdio>
#include <cstring>
#include <yawdepth/error.h>

namespace yawdepth {
namespace bag_detail {
namespace cdr {

Reader::Reader(const std::uint8_t *data, std::size_t size, std::string where) : where_(std::move(where))
{
  if (size < 4 || !data)
    fail("CDR message of " + std::to_string(size) + " bytes, shorter than its 4-byte encapsulation header");
  if (data[0] == 0x28 && data[1] == 0xB5 && data[2] == 0x2F && data[3] == 0xFD)
#ifdef YAWDEPTH_BAG_ZSTD
    fail("a zstd-compressed message inside a zstd-compressed message, not CDR"); // openBag() undid the outer one
#else
    fail("a zstd-compressed message (rosbag2's MESSAGE compression), not CDR: this build was made without zstd "
         "(Debian: libzstd-dev)");
#endif
  if (data[0] != 0x00 || (data[1] != 0x00 && data[1] != 0x01)) {
    char h[16];
    std::snprintf(h, sizeof h, "%02x %02x", data[0], data[1]);
    fail(std::string("CDR encapsulation ") + h + ", not CDR_LE (00 01) or CDR_BE (00 00)");
  }
  little_ = data[1] == 0x01;
  data_ = data + 4;
  size_ = size - 4;
}

void Reader::fail(const std::string &why) const
{
  throw Error(where_ + why);
}

void Reader::align(std::size_t n)
{
  const std::size_t pad = (n - pos_ % n) % n;
  if (pad > size_ - pos_)
    fail("ends at byte " + std::to_string(size_ + 4) + " inside the padding before a field at byte " +
         std::to_string(pos_ + 4));
  pos_ += pad;
}

const std::uint8_t *Reader::take(std::size_t n)
{
  if (n > size_ - pos_)
    fail("ends at byte " + std::to_string(size_ + 4) + ", a field at byte " + std::to_string(pos_ + 4) + " needs " +
         std::to_string(n) + " bytes");
  const std::uint8_t *p = data_ + pos_;
  pos_ += n;
  return p;
}

template <typename T> T Reader::primitive()
{
  align(sizeof(T));
  const std::uint8_t *p = take(sizeof(T));
  std::uint8_t b[sizeof(T)];
  const bool host_little = [] {
    const std::uint16_t one = 1;
    std::uint8_t c;
    std::memcpy(&c, &one, 1);
    return c == 1;
  }();
  if (host_little == little_)
    std::memcpy(b, p, sizeof(T));
  else
    for (std::size_t i = 0; i < sizeof(T); ++i)
      b[i] = p[sizeof(T) - 1 - i];
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

std::uint8_t Reader::u8() { return *take(1); }

bool Reader::boolean()
{
  const std::size_t at = pos_ + 4;
  const std::uint8_t b = u8();
  if (b > 1)
    fail("a bool at byte " + std::to_string(at) + " is " + std::to_string(b) + ", not 0 or 1");
  return b == 1;
}

std::uint16_t Reader::u16() { return primitive<std::uint16_t>(); }
std::uint32_t Reader::u32() { return primitive<std::uint32_t>(); }
std::int32_t Reader::i32() { return primitive<std::int32_t>(); }
std::uint64_t Reader::u64() { return primitive<std::uint64_t>(); }
double Reader::f64() { return primitive<double>(); }

std::string Reader::string()
{
  const std::uint32_t n = u32();
  if (n == 0)
    return std::string();
  const std::size_t at = pos_ + 4;
  if (n > size_ - pos_)
    fail("a string at byte " + std::to_string(at) + " says " + std::to_string(n) + " bytes, beyond the message's " +
         std::to_string(size_ + 4));
  const std::uint8_t *p = take(n);
  if (p[n - 1] != 0)
    fail("a string at byte " + std::to_string(at) + " does not end with a NUL");
  return std::string(reinterpret_cast<const char *>(p), n - 1);
}

std::int64_t Reader::time()
{
  const std::int32_t sec = i32();
  const std::uint32_t nsec = u32();
  return std::int64_t(sec) * 1000000000 + std::int64_t(nsec);
}

std::uint32_t Reader::count(std::size_t min_element_size, const char *field)
{
  const std::uint32_t n = u32();
  const std::size_t left = size_ - pos_;
  if (min_element_size > 0 && n > left / min_element_size)
    fail(std::string(field) + ": a sequence of " + std::to_string(n) + " elements at byte " + std::to_string(pos_ + 4) +
         " is beyond the message's " + std::to_string(size_ + 4) + " bytes");
  return n;
}

std::vector<std::uint8_t> Reader::bytes(const char *field)
{
  const std::uint32_t n = count(1, field);
  const std::uint8_t *p = take(n);
  return std::vector<std::uint8_t>(p, p + n);
}

std::vector<double> Reader::doubles(const char *field)
{
  const std::uint32_t n = count(8, field);
  std::vector<double> v(n);
  for (double &x : v)
    x = f64();
  return v;
}

std::vector<std::string> Reader::strings(const char *field)
{
  const std::uint32_t n = count(4, field);
  std::vector<std::string> v(n);
  for (std::string &s : v)
    s = string();
  return v;
}

void Reader::skipDoubles(std::size_t n)
{
  if (n == 0)
    return;
  align(8);
  if (n > (size_ - pos_) / 8)
    take(size_ - pos_ + 1); // the bounds error
  take(n * 8);
}

} // namespace cdr
} // namespace bag_detail
} // namespace yawdepth
