#include <yawdepth/features/video_frames.h>

#include <filesystem>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/videoio.hpp>
#include <visp3/core/vpException.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>
#include <visp3/io/vpVideoReader.h>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

/* OpenCV's own log silenced while ViSP asks its video back ends (GStreamer, FFmpeg, image sequences)
   to open or read: a file none can read would print several lines of each back end's complaints;
   the caller gets one yawdepth::Error instead. The previous level comes back at the end of scope. */
class QuietOpenCv {
public:
  QuietOpenCv() : previous_(cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT)) {}
  ~QuietOpenCv() { cv::utils::logging::setLogLevel(previous_); }
  QuietOpenCv(const QuietOpenCv &) = delete;
  QuietOpenCv &operator=(const QuietOpenCv &) = delete;

private:
  cv::utils::logging::LogLevel previous_;
};

} // namespace

/* ViSP's reader and its frame buffer. open() reads the first frame only to learn the size; the
   first acquire() returns that frame again, and end() is true once the last one was acquired. */
struct VideoFrames::Reader {
  vpVideoReader video;
  vpImage<unsigned char> image;
};

VideoFrames::VideoFrames(const std::string &path) : reader_(std::make_unique<Reader>()), path_(path)
{
  if (path.empty())
    throw Error("video: empty path");
  const QuietOpenCv quiet;
  if (path.find('%') == std::string::npos) { // a movie: a readable file that FFmpeg can open
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      throw Error(path + ": no such video file");
    // Asked of FFmpeg alone first: a file it cannot read would otherwise go to every other back end
    // (GStreamer loads its plugins, some probe USB devices and leak).
    if (!cv::VideoCapture(path, cv::CAP_FFMPEG).isOpened())
      throw Error(path + ": cannot open: not a video file FFmpeg can read");
  }
  try {
    reader_->video.setFileName(path);
    reader_->video.open(reader_->image);
  } catch (const vpException &e) {
    throw Error(path + ": cannot open the video or image sequence: " + e.getStringMessage());
  } catch (const std::exception &) { // ViSP parses the name before it knows what the file is
    throw Error(path + ": cannot open: not a video or an image sequence (e.g. frames/%04d.png) that ViSP can read");
  }
  if (reader_->image.getWidth() == 0 || reader_->image.getHeight() == 0)
    throw Error(path + ": cannot read the first frame of the video or image sequence");
}

VideoFrames::~VideoFrames() = default;
VideoFrames::VideoFrames(VideoFrames &&) noexcept = default;
VideoFrames &VideoFrames::operator=(VideoFrames &&) noexcept = default;

cv::Mat VideoFrames::next()
{
  Reader &r = *reader_;
  const std::string ended = path_ + ": the video ended after " + std::to_string(read_) + " frames";
  if (r.video.end())
    throw Error(ended);
  r.image.resize(0, 0);
  const QuietOpenCv quiet;
  try {
    r.video.acquire(r.image);
  } catch (const vpException &e) {
    throw Error(path_ + ": cannot read frame " + std::to_string(read_ + 1) + ": " + e.getStringMessage());
  } catch (const std::exception &e) {
    throw Error(path_ + ": cannot read frame " + std::to_string(read_ + 1) + ": " + e.what());
  }
  if (r.image.getWidth() == 0 || r.image.getHeight() == 0)
    throw Error(ended); // a movie shorter than its container said
  cv::Mat out;
  vpImageConvert::convert(r.image, out);
  ++read_;
  return out;
}

} // namespace yawdepth
