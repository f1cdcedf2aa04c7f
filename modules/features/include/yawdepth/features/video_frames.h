#pragma once
/*!
  \file video_frames.h
  \brief A video file or a numbered image sequence as the images of a motion log: a movie through
  ViSP's vpVideoReader (what OpenCV's FFmpeg back end can decode), a sequence such as
  `frames/frame_%04d.png` file by file (readGrayImage()).

  The frames are read in order, one per call of next(); the motion log's rows are matched to them in
  order (row i is the video's i-th frame, whatever the rows' frame numbers). A video that ends before
  the log does is an error, not a shorter sequence; frames after the log's last row are not read.
  A numbered sequence starts at the lowest number among its files and must have no gap: a missing
  file before the sequence's last one is an error naming it (every later row would otherwise get
  the wrong image).
  While a movie is opened and read, OpenCV's log is silenced (a process-wide setting, restored after
  each call) and so is C's stderr (FFmpeg's and GStreamer's own messages): a file no back end can
  read gives one yawdepth::Error, not each back end's complaints.
*/
#include <memory>
#include <set>
#include <string>
#include <vector>
#include <opencv2/core.hpp>

namespace yawdepth {

/*!
  \brief A numbered image sequence's name: a file name with one printf conversion, `%d` or `%0Nd`
  (N from 1 to 9: zero-padded to N digits), and `%%` for a literal `%`.
*/
class SequencePattern {
public:
  /*! \brief True when the file name of `path` (not its folder) holds a `%`: a pattern, not a movie. */
  static bool isPattern(const std::string &path);
  /*!
    \brief Parses `pattern`; throws yawdepth::Error (one line, naming the pattern) unless its file
    name holds exactly one conversion `%d` or `%0Nd`, N from 1 to 9, and no other `%` but `%%`.
  */
  explicit SequencePattern(const std::string &pattern);
  /*! \brief The file of frame number `number` (>= 0), as printf would name it. */
  std::string file(long long number) const;
  /*! \brief The numbers whose files exist in the pattern's folder, in increasing order. */
  std::set<long long> numbersPresent() const;
  /*! \brief The files that exist, in increasing number. */
  std::vector<std::string> filesPresent() const;
  /*! \brief The pattern, as given. */
  const std::string &pattern() const { return pattern_; }

private:
  std::string pattern_;
  std::string folder_; // with its trailing '/', or empty
  std::string prefix_, suffix_;
  int width_ = 0;
};

/*! \brief The frames of a video or image sequence, in order (see the file). */
class VideoFrames {
public:
  /*!
    \param path A video file, or an image sequence's pattern (SequencePattern, e.g. `img%04d.png`).
    Reads the first frame. Throws yawdepth::Error (one line) when it cannot be opened or read: a
    folder, a bad pattern, a sequence without any file, a file that is not a video.
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
      ("... ended after N frames") when there is none, or (a sequence) naming the missing or
      unreadable file. */
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
