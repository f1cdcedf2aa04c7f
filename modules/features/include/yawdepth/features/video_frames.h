#pragma once
/*!
  \file video_frames.h
  \brief A video file or an image sequence as the images of a motion log, through ViSP's
  vpVideoReader (a movie OpenCV can decode, or a numbered sequence such as `frames/%04d.png`).

  The frames are read in order, one per call of next(); the motion log's rows are matched to them in
  order (row i is the video's i-th frame, whatever the rows' frame numbers). A video that ends before
  the log does is an error, not a shorter sequence; frames after the log's last row are not read.
  While it opens and reads, OpenCV's log is silenced (a process-wide setting, restored after each call):
  a file no back end can read gives one yawdepth::Error, not each back end's complaints.
*/
#include <memory>
#include <string>
#include <opencv2/core.hpp>

namespace yawdepth {

/*! \brief The frames of a video or image sequence, in order (see the file). */
class VideoFrames {
public:
  /*!
    \param path A video file, or an image sequence's pattern (printf-style, e.g. `img%04d.png`).
    Reads the first frame. Throws yawdepth::Error (one line) when it cannot be opened or read.
  */
  explicit VideoFrames(const std::string &path);
  ~VideoFrames();
  VideoFrames(const VideoFrames &) = delete;
  VideoFrames &operator=(const VideoFrames &) = delete;
  /*! \brief Takes over another reader (which is left empty). */
  VideoFrames(VideoFrames &&) noexcept;
  /*! \brief Takes over another reader (which is left empty). */
  VideoFrames &operator=(VideoFrames &&) noexcept;

  /*! \brief The next frame, 8-bit gray (a colour video is converted); throws yawdepth::Error
      ("... ended after N frames") when there is none. */
  cv::Mat next();
  /*! \brief Frames returned so far. */
  std::size_t framesRead() const { return read_; }
  /*! \brief The path given. */
  const std::string &path() const { return path_; }

private:
  struct Reader;
  std::unique_ptr<Reader> reader_;
  std::string path_;
  std::size_t read_ = 0;
};

} // namespace yawdepth
