/*!
  \file image_file.cpp
  \brief Reading an image file as 8-bit gray: bounded reads, the size its header declares checked
  before decoding, a JPEG's structure checked (libjpeg decodes a truncated file to gray without an
  error), the decoders' complaints kept off stderr.
*/
#include <yawdepth/features/detector.h>

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#include <opencv2/imgcodecs.hpp>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

#include "quiet_decoders.h"

namespace yawdepth {

namespace {

/* An image's size from its header (PNG, JPEG, PGM/PPM/PBM, BMP), without decoding it; false for
   other formats or a header too damaged to tell (the decoder then has the last word). */
bool headerSize(const std::vector<unsigned char> &b, std::uint64_t &w, std::uint64_t &h) {
  const std::size_t n = b.size();
  auto be32 = [&](std::size_t i) {
    return (std::uint64_t(b[i]) << 24) | (std::uint64_t(b[i + 1]) << 16) | (std::uint64_t(b[i + 2]) << 8) | b[i + 3];
  };
  auto le32 = [&](std::size_t i) {
    return std::uint64_t(std::uint32_t(b[i]) | (std::uint32_t(b[i + 1]) << 8) | (std::uint32_t(b[i + 2]) << 16) |
                         (std::uint32_t(b[i + 3]) << 24));
  };
  if (n >= 24 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') {
    w = be32(16);
    h = be32(20);
    return true;
  }
  if (n >= 4 && b[0] == 0xFF && b[1] == 0xD8) { // JPEG: the first start-of-frame marker
    std::size_t i = 2;
    while (i + 9 < n) {
      if (b[i] != 0xFF) {
        ++i;
        continue;
      }
      const unsigned char m = b[i + 1];
      if (m == 0xFF || m == 0x01 || (m >= 0xD0 && m <= 0xD9)) {
        i += (m == 0xFF) ? 1 : 2;
        continue;
      }
      const std::size_t len = (std::size_t(b[i + 2]) << 8) | b[i + 3];
      if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC) {
        h = (std::uint64_t(b[i + 5]) << 8) | b[i + 6];
        w = (std::uint64_t(b[i + 7]) << 8) | b[i + 8];
        return true;
      }
      i += 2 + len;
    }
    return false;
  }
  if (n >= 26 && b[0] == 'B' && b[1] == 'M') {
    w = le32(18);
    const std::uint32_t hh = static_cast<std::uint32_t>(le32(22));
    h = static_cast<std::uint64_t>(std::abs(static_cast<std::int64_t>(static_cast<std::int32_t>(hh))));
    return true;
  }
  if (n >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6') { // PNM: two numbers after comments
    std::size_t i = 2;
    std::uint64_t v[2] = {0, 0};
    for (std::uint64_t &value : v) {
      for (;;) {
        while (i < n && std::isspace(b[i]))
          ++i;
        if (i < n && b[i] == '#') {
          while (i < n && b[i] != '\n')
            ++i;
          continue;
        }
        break;
      }
      if (i >= n || !std::isdigit(b[i]))
        return false;
      while (i < n && std::isdigit(b[i]) && value < (std::uint64_t(1) << 40))
        value = value * 10 + (b[i++] - '0');
    }
    w = v[0];
    h = v[1];
    return true;
  }
  return false;
}

/* Why a JPEG (it starts with SOI, 0xFFD8) cannot be whole, or empty when its structure holds: its
   segments, each within the file, a frame header (SOF) before the first scan (SOS), each scan's
   entropy-coded data up to the next marker, and the end-of-image marker (EOI, 0xFFD9) after the
   last scan. Bytes after EOI are not read (a camera's trailer); stray bytes between segments are
   skipped, as libjpeg does. Damage inside the entropy-coded data that keeps this structure is
   not seen (the decoder has the last word there). */
std::string jpegDamage(const std::vector<unsigned char> &b)
{
  const std::size_t n = b.size();
  const char *const truncated = "a truncated JPEG: it ends before its end-of-image marker";
  bool frame = false;
  std::size_t i = 2;
  for (;;) {
    while (i < n && b[i] != 0xFF) // stray bytes before a marker
      ++i;
    while (i < n && b[i] == 0xFF) // fill bytes
      ++i;
    if (i >= n)
      return truncated;
    const unsigned char m = b[i++]; // i: after the marker's code
    if (m == 0xD9)
      return "";
    if (m == 0x00 || m == 0x01 || m == 0xD8 || (m >= 0xD0 && m <= 0xD7))
      continue; // no segment: a stuffed byte out of a scan, TEM, a repeated SOI, RSTn
    if (i + 2 > n)
      return truncated;
    const std::size_t len = (std::size_t(b[i]) << 8) | b[i + 1];
    if (len < 2)
      return "a damaged JPEG: a segment of length " + std::to_string(len);
    if (i + len > n)
      return truncated;
    if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC)
      frame = true;
    i += len;
    if (m != 0xDA)
      continue;
    if (!frame)
      return "a damaged JPEG: image data before its frame header";
    // The scan's entropy-coded data: 0xFF is followed by 0x00 (a stuffed byte) or RSTn inside it,
    // by another marker at its end.
    for (;;) {
      const void *ff = i < n ? std::memchr(b.data() + i, 0xFF, n - i) : nullptr;
      if (ff == nullptr)
        return truncated;
      i = static_cast<std::size_t>(static_cast<const unsigned char *>(ff) - b.data());
      if (i + 1 >= n)
        return truncated;
      const unsigned char c = b[i + 1];
      if (c == 0x00 || (c >= 0xD0 && c <= 0xD7))
        i += 2;
      else if (c == 0xFF)
        i += 1;
      else
        break; // the marker after the scan
    }
  }
}

} // namespace

cv::Mat readGrayImage(const std::string &path, const CameraModel &camera)
{
  cv::Mat image = readGrayImage(path);
  if (camera.width() > 0 &&
      (image.cols != static_cast<int>(camera.width()) || image.rows != static_cast<int>(camera.height())))
    throw Error(path + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                " but the camera is " + std::to_string(camera.width()) + "x" + std::to_string(camera.height()));
  return image;
}

cv::Mat readGrayImage(const std::string &path) {
  // Read the bytes ourselves (clear messages for missing, empty, endless or huge files; only a
  // regular file or a pipe), check the size its header declares, then decode in memory.
  // The decoders of OpenCV and libpng/libjpeg print their own complaints on stderr for damaged
  // files; the library must not print, so stderr is silenced while decoding.
  constexpr std::size_t kMaxImageBytes = std::size_t(512) << 20;
  constexpr std::uint64_t kMaxImagePixels = std::uint64_t(1) << 28; // 268 Mpx: 16384 x 16384
  std::vector<unsigned char> bytes;
  try {
    bytes = readBinaryFile(path, kMaxImageBytes);
  } catch (const Error &e) {
    const std::string what = e.what();
    const std::string rest = what.compare(0, path.size() + 2, path + ": ") == 0 ? what.substr(path.size() + 2) : what;
    throw Error(path + ": cannot read image (" + rest + ")");
  }
  std::uint64_t w = 0, h = 0;
  if (headerSize(bytes, w, h) && (w == 0 || h == 0 || w > kMaxImagePixels || h > kMaxImagePixels ||
                                  w * h > kMaxImagePixels)) // (each side first: the product must not overflow)
    throw Error(path + ": cannot read image (its header declares " + std::to_string(w) + " x " + std::to_string(h) +
                " pixels; at most " + std::to_string(kMaxImagePixels) + " pixels are read)");
  if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) {
    const std::string damage = jpegDamage(bytes);
    if (!damage.empty())
      throw Error(path + ": cannot read image (" + damage + ")");
  }
  cv::Mat img;
  {
    const detail::QuietDecoders quiet;
    std::string failure;
    try {
      img = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception &e) {
      failure = e.err;
    }
    if (!failure.empty())
      throw Error(path + ": cannot read image (" + failure + ")");
  }
  if (img.empty())
    throw Error(path + ": cannot read image (truncated, damaged or not an image)");
  if (img.depth() != CV_8U) {
    cv::Mat eight;
    img.convertTo(eight, CV_8U, img.depth() == CV_16U ? 1.0 / 256 : 1.0);
    img = eight;
  }
  return img;
}

} // namespace yawdepth
