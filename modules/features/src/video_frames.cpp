#include <yawdepth/features/video_frames.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/videoio.hpp>
#include <visp3/core/vpException.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>
#include <visp3/io/vpVideoReader.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>

#include "quiet_decoders.h"

namespace yawdepth {

namespace {

namespace fs = std::filesystem;

/* OpenCV's own log silenced while ViSP asks its video back ends (GStreamer, FFmpeg) to open or read:
   a file none can read would print several lines of each back end's complaints; the caller gets one
   yawdepth::Error instead. The previous level comes back at the end of scope. */
class QuietOpenCv {
public:
  QuietOpenCv() : previous_(cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT)) {}
  ~QuietOpenCv() { cv::utils::logging::setLogLevel(previous_); }
  QuietOpenCv(const QuietOpenCv &) = delete;
  QuietOpenCv &operator=(const QuietOpenCv &) = delete;

private:
  cv::utils::logging::LogLevel previous_;
};

/* FFmpeg's own log (av_log: "moov atom not found", a decoder's "error while decoding MB", also from
   its decoding threads, after a call returned) off for the process: OpenCV reads
   OPENCV_FFMPEG_LOGLEVEL once, when its FFmpeg back end is first used, and -8 is AV_LOG_QUIET. A
   level the user set, or OPENCV_FFMPEG_DEBUG, is left as it is. */
void quietFfmpeg()
{
  static std::once_flag once;
  std::call_once(once, [] {
    if (std::getenv("OPENCV_FFMPEG_DEBUG") == nullptr)
      ::setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0); // once, before OpenCV first reads it
  });
}

const char *const kPatternExample = "e.g. frames/frame_%04d.png";

std::size_t nameStart(const std::string &path)
{
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? 0 : slash + 1;
}

} // namespace

// ---- SequencePattern ----------------------------------------------------------------------------

bool SequencePattern::isPattern(const std::string &path) { return path.find('%', nameStart(path)) != std::string::npos; }

SequencePattern::SequencePattern(const std::string &pattern) : pattern_(pattern)
{
  const std::size_t start = nameStart(pattern);
  folder_ = pattern.substr(0, start);
  const std::string name = pattern.substr(start);
  const std::size_t n = name.size();
  int conversions = 0;
  std::string *part = &prefix_;
  for (std::size_t i = 0; i < n; ++i) {
    if (name[i] != '%') {
      *part += name[i];
      continue;
    }
    if (i + 1 < n && name[i + 1] == '%') {
      *part += '%';
      ++i;
      continue;
    }
    std::size_t end = 0; // the conversion's 'd'
    if (i + 1 < n && name[i + 1] == 'd') {
      width_ = 0;
      end = i + 1;
    } else if (i + 3 < n && name[i + 1] == '0' && name[i + 2] >= '1' && name[i + 2] <= '9' && name[i + 3] == 'd') {
      width_ = name[i + 2] - '0';
      end = i + 3;
    } else { // shown up to its conversion letter (or the end of the name)
      std::size_t k = i + 1;
      while (k < n && !std::isalpha(static_cast<unsigned char>(name[k])) && name[k] != '%')
        ++k;
      const std::string spec = name.substr(i, (k < n && name[k] != '%' ? k + 1 : k) - i);
      throw Error(pattern + ": not a numbered image sequence: '" + spec + "' is not %d or %0Nd with N from 1 to 9 (" +
                  kPatternExample + ")");
    }
    if (++conversions > 1)
      throw Error(pattern + ": not a numbered image sequence: its file name holds more than one %d or %0Nd (one "
                  "numbers the frames, " + std::string(kPatternExample) + ")");
    part = &suffix_;
    i = end;
  }
  if (conversions == 0)
    throw Error(pattern + ": not a numbered image sequence: its file name holds no %d or %0Nd (a "
                "literal % is written %%; " + std::string(kPatternExample) + ")");
}

std::string SequencePattern::file(long long number) const
{
  std::string digits = std::to_string(number);
  if (digits.size() < static_cast<std::size_t>(width_))
    digits.insert(0, static_cast<std::size_t>(width_) - digits.size(), '0');
  return folder_ + prefix_ + digits + suffix_;
}

std::set<long long> SequencePattern::numbersPresent() const
{
  std::set<long long> numbers;
  std::error_code ec;
  const fs::path folder = folder_.empty() ? fs::path(".") : fs::path(folder_);
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix_.size() + suffix_.size() || name.compare(0, prefix_.size(), prefix_) != 0 ||
        name.compare(name.size() - suffix_.size(), suffix_.size(), suffix_) != 0)
      continue;
    const std::string digits = name.substr(prefix_.size(), name.size() - prefix_.size() - suffix_.size());
    if (digits.size() > 18 || digits.find_first_not_of("0123456789") != std::string::npos)
      continue;
    const long long number = std::stoll(digits);
    std::error_code dir_ec;
    // Only the name printf gives the number (frame_00012.png is not %04d's 12), and no folder.
    if (file(number) == folder_ + name && !it->is_directory(dir_ec))
      numbers.insert(number);
  }
  return numbers;
}

std::vector<std::string> SequencePattern::filesPresent() const
{
  std::vector<std::string> files;
  for (const long long number : numbersPresent())
    files.push_back(file(number));
  return files;
}

// ---- VideoFrames --------------------------------------------------------------------------------

/* A movie: ViSP's reader and its frame buffer; open() reads the first frame only to learn the size,
   the first acquire() returns that frame again, and end() is true once the last one was acquired.
   A numbered sequence: its pattern, the numbers present, the first frame (read to check it). */
struct VideoFrames::Reader {
  vpVideoReader video;
  vpImage<unsigned char> image;
  std::unique_ptr<SequencePattern> sequence;
  std::set<long long> numbers;
  cv::Mat first;
};

VideoFrames::VideoFrames(const std::string &path) : reader_(std::make_unique<Reader>()), path_(path)
{
  if (path.empty())
    throw Error("video: empty path");
  Reader &r = *reader_;
  if (SequencePattern::isPattern(path)) {
    r.sequence = std::make_unique<SequencePattern>(path);
    r.numbers = r.sequence->numbersPresent();
    if (r.numbers.empty())
      throw Error(path + ": no file of this numbered image sequence exists (frame 0 would be " + r.sequence->file(0) +
                  ")");
    r.first = readGrayImage(r.sequence->file(*r.numbers.begin()));
    return;
  }
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw Error(path + ": is a folder, not a video file (give a video file, or a numbered image sequence such as " +
                (fs::path(path) / "frame_%04d.png").lexically_normal().string() + ")");
  if (!fs::is_regular_file(path, ec))
    throw Error(path + (fs::exists(path, ec) ? ": is not a regular file (a video file is read from disk)"
                                             : ": no such video file"));
  quietFfmpeg();
  const QuietOpenCv quiet;
  const detail::QuietDecoders quiet_decoders;
  // Asked of FFmpeg alone first: a file it cannot read would otherwise go to every other back end
  // (GStreamer loads its plugins, some probe USB devices and leak).
  if (!cv::VideoCapture(path, cv::CAP_FFMPEG).isOpened())
    throw Error(path + ": cannot open: not a video file FFmpeg can read");
  try {
    r.video.setFileName(path);
    r.video.open(r.image);
  } catch (const vpException &e) {
    throw Error(path + ": cannot open the video: " + e.getStringMessage());
  } catch (const std::exception &) {
    throw Error(path + ": cannot open: not a video that ViSP can read");
  }
  if (r.image.getWidth() == 0 || r.image.getHeight() == 0)
    throw Error(path + ": cannot read the first frame of the video");
}

VideoFrames::~VideoFrames() = default;
VideoFrames::VideoFrames(VideoFrames &&) noexcept = default;
VideoFrames &VideoFrames::operator=(VideoFrames &&) noexcept = default;

cv::Mat VideoFrames::next()
{
  Reader &r = *reader_;
  const std::string ended = path_ + ": the video ended after " + std::to_string(read_) + " frames";
  if (r.sequence) {
    if (read_ == 0) {
      ++read_;
      return std::move(r.first);
    }
    const long long number = *r.numbers.begin() + static_cast<long long>(read_);
    if (r.numbers.count(number) == 0) {
      const auto later = r.numbers.upper_bound(number);
      if (later == r.numbers.end())
        throw Error(ended);
      throw Error(r.sequence->file(number) + ": missing from the numbered image sequence " + path_ + " (its frame " +
                  std::to_string(read_ + 1) + "; the sequence goes on at " + r.sequence->file(*later) +
                  "): a gap would give every later row the wrong image");
    }
    cv::Mat image = readGrayImage(r.sequence->file(number));
    ++read_;
    return image;
  }
  if (r.video.end())
    throw Error(ended);
  r.image.resize(0, 0);
  {
    const QuietOpenCv quiet;
    const detail::QuietDecoders quiet_decoders;
    try {
      r.video.acquire(r.image);
    } catch (const vpException &e) {
      throw Error(path_ + ": cannot read frame " + std::to_string(read_ + 1) + ": " + e.getStringMessage());
    } catch (const std::exception &e) {
      throw Error(path_ + ": cannot read frame " + std::to_string(read_ + 1) + ": " + e.what());
    }
  }
  if (r.image.getWidth() == 0 || r.image.getHeight() == 0)
    throw Error(ended); // a movie shorter than its container said
  cv::Mat out;
  vpImageConvert::convert(r.image, out);
  ++read_;
  return out;
}

} // namespace yawdepth
