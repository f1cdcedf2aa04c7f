#pragma once
// Private to the bag module: a bounds-checked reader of ROS 2's CDR (XCDR1, "classic" CDR as
// Fast-DDS and the rmw layers write it). After the 4-byte encapsulation header (0x00 0x01: little
// endian, 0x00 0x00: big endian; two option bytes), every primitive is aligned to its size,
// relative to the first byte after the header. Every read checks the buffer's end.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace yawdepth {
namespace bag_detail {
namespace cdr {

class Reader {
public:
  /*! `where` starts every error message ("<topic>: message at t = ... s: "). Throws on a bad header. */
  Reader(const std::uint8_t *data, std::size_t size, std::string where);

  std::uint8_t u8();
  bool boolean(); // a byte, 0 or 1 (other values refused)
  std::uint16_t u16();
  std::uint32_t u32();
  std::int32_t i32();
  std::uint64_t u64();
  double f64();
  /*! uint32 length including the NUL, the bytes, the NUL. A length of 0 is read as "". */
  std::string string();
  /*! builtin_interfaces/Time (int32 sec, uint32 nanosec) as nanoseconds. */
  std::int64_t time();
  /*! A sequence's uint32 count, checked against what is left at `min_element_size` bytes each. */
  std::uint32_t count(std::size_t min_element_size, const char *field);
  /*! sequence<uint8>. */
  std::vector<std::uint8_t> bytes(const char *field);
  /*! sequence<float64>. */
  std::vector<double> doubles(const char *field);
  /*! sequence<string>. */
  std::vector<std::string> strings(const char *field);
  template <std::size_t N> void doubles(std::array<double, N> &a)
  {
    for (double &x : a)
      x = f64();
  }
  /*! Skips `n` doubles (a field read but not kept), checked like any other read. */
  void skipDoubles(std::size_t n);

  std::size_t offset() const { return pos_; }
  std::size_t size() const { return size_; }
  bool littleEndian() const { return little_; }

  [[noreturn]] void fail(const std::string &why) const;

private:
  void align(std::size_t n);
  const std::uint8_t *take(std::size_t n); // checked; advances
  template <typename T> T primitive();

  const std::uint8_t *data_ = nullptr; // after the encapsulation header
  std::size_t size_ = 0;
  std::size_t pos_ = 0;
  bool little_ = true;
  std::string where_;
};

} // namespace cdr
} // namespace bag_detail
} // namespace yawdepth
