#pragma once
/*!
  \file recording.h
  \brief A user's recording as it is: pose logs at their own rate (TUM, EuRoC, a yawdepth CSV with a
  time column `t`, ViSP's per-image vpPoseVector files), timestamped images (a folder named by
  timestamps, TUM's `rgb.txt`, EuRoC's `data.csv`), and the one place where the two are brought
  together: each image's pose interpolated on SE(3) at its time (docs/formats.md, "Timestamped
  recordings").

  Times: `t` in seconds (a double: at 1.7e9 s since 1970 its resolution is below 0.3 microsecond).
  Clocks: an image's time is on the camera's clock; `time_offset` S says the image at camera time t
  was taken at motion time t + S.

  The estimators never see a timestamp: alignMotionToImages() turns a timestamped log into the
  frame-based MotionLog (files.h) every command reads, frame i being the i-th image in time order.
*/
#include <cstddef>
#include <optional>
#include <string>
#include <vector>
#include <yawdepth/core/input_limits.h>
#include <yawdepth/io/files.h>

namespace yawdepth {

/*! \brief The form of a motion file (`--motion-format`). */
enum class MotionFormat {
  Auto,     //!< "auto": by content (detectMotionFormat()).
  Yawdepth, //!< "yawdepth": the CSV of docs/formats.md, frame-based (`frame`) or timestamped (`t`).
  Tum,      //!< "tum": `timestamp tx ty tz qx qy qz qw` per line, whitespace-separated, `#` comments.
  Euroc,    //!< "euroc": the ASL CSV, `#timestamp [ns],p_RS_R_x [m],...,q_RS_w [],...` (extra columns ignored).
  Visp      //!< "visp": one vpPoseVector YAML file per image (`rows: 6, cols: 1, data: ...`), in name order.
};

/*! \brief "auto", "yawdepth", "tum", "euroc", "visp". */
const char *toString(MotionFormat f);
/*! \brief Parse a format word; throws yawdepth::Error for an unknown one. */
MotionFormat motionFormatFromString(const std::string &word);

/*!
  \brief The format of a motion file by its content: a folder, or a file whose text is a
  vpPoseVector (`rows: 6`), is Visp; a first line starting `#timestamp` with commas, or a CSV header
  with a `timestamp` column and `p_..._x` columns, is Euroc; a CSV header with `frame` or `t` is
  Yawdepth; a first data line of 8 whitespace-separated numbers is Tum; anything else is Yawdepth
  (whose reader then names what is missing). A pipe cannot be read twice: it is Yawdepth unless
  the format is given. Throws yawdepth::Error when the file cannot be read.
*/
MotionFormat detectMotionFormat(const std::string &path, const InputLimits &limits = InputLimits());

/*!
  \brief Read a motion log in any of the formats. TUM, EuRoC and a yawdepth CSV with `t` (and no
  `frame`) give a timestamped log (MotionLog::timestamped, MotionLog::times): 6-DoF poses of the body
  (the vision frame) in the world, the rotation from a Hamilton quaternion normalised (a norm more
  than 1e-3 from 1, or 0, is an error naming the line), times strictly increasing. Visp gives a
  frame-based 6-DoF log, frame i from the i-th file. The yaw: a `yaw` column, else `fixed_yaw`, else
  0 (a planar yawdepth log without either is an error).
  \param paths One file; for Visp several files, or one folder (its `.yaml`/`.yml` files).
  \param format The format, or Auto. \param fixed_yaw The rig file's `yaw`. \param limits Input bounds.
*/
MotionLog readMotionFile(const std::vector<std::string> &paths, MotionFormat format = MotionFormat::Auto,
                         std::optional<double> fixed_yaw = std::nullopt, const InputLimits &limits = InputLimits());

/*!
  \brief One vpPoseVector YAML file as ViSP writes it (vpPoseVector::saveYAML: `rows: 6`,
  `cols: 1`, `data:` six one-element rows tx ty tz tux tuy tuz, m and theta-u rad).
*/
vpPoseVector readVispPoseFile(const std::string &path);

/*! \brief The images of a recording, in time order (or in name order when untimed). */
struct ImageList {
  std::vector<std::string> paths; //!< image files, resolved
  std::vector<double> times;      //!< camera-clock times (s), strictly increasing; empty when untimed
};

/*!
  \brief The images `--images PATH` names:
  - a folder: its image files (`.png .jpg .jpeg .pgm .ppm .pnm .bmp .tif .tiff`, any case); with
    `timed`, each name's stem is its time: with a decimal point in seconds (`1305031102.175304.png`,
    TUM), an integer in nanoseconds (`1403636579763555584.png`, EuRoC); a name that is not a
    timestamp is an error naming it. Untimed, they are taken in natural name order (`img2` before
    `img10`).
  - a list file: TUM's `rgb.txt` (`timestamp filename` per line, seconds, `#` comments) or EuRoC's
    `data.csv` (`#timestamp [ns],filename`); paths relative to the list's folder (or, for EuRoC's
    layout, to the `data/` folder beside it).
  Two images with one time, or a list whose times go back, are errors naming the line or file.
  \param path The folder or list. \param timed Whether times are required.
  \param limits The bounds on a list file (as for a motion log).
*/
ImageList readImageList(const std::string &path, bool timed = true, const InputLimits &limits = InputLimits());

/*! \brief How images are matched to a timestamped pose log. */
struct TimeAlignmentOptions {
  /*! The image at camera time t was taken at motion time t + time_offset (s). */
  double time_offset = 0.0;
  /*! An image between two pose samples further apart than this is skipped (s). */
  double max_pose_gap = 0.2;
  /*! \brief Throws yawdepth::Error unless both are finite and the gap is positive. */
  void validate() const;
};

/*! \brief A timestamped log resampled at the images' times, with what was matched and skipped. */
struct TimeAlignment {
  /*! Frame-based: frame i is the i-th image of the list (skipped images leave no row), `images`
      holds each row's image, `times` each row's motion-clock time. */
  MotionLog log;
  std::size_t images = 0;        //!< images in the list
  std::size_t matched = 0;       //!< images given a pose
  std::size_t before = 0;        //!< skipped: taken before the log's first pose
  std::size_t after = 0;         //!< skipped: taken after the log's last pose
  std::size_t in_gap = 0;        //!< skipped: between two poses more than max_pose_gap apart
  double image_first = 0;        //!< the first image's time, motion clock (s)
  double image_last = 0;         //!< the last image's time, motion clock (s)
  double motion_first = 0;       //!< the log's first time (s)
  double motion_last = 0;        //!< the log's last time (s)
  double motion_rate_hz = 0;     //!< the log's median rate (Hz)
  double image_rate_hz = 0;      //!< the images' median rate (Hz)
  /*! \brief One line: "N images (R Hz), M matched, ... skipped; poses at R Hz over [a, b] s". */
  std::string summary() const;
};

/*!
  \brief Each image's pose, interpolated between the two pose samples around its time
  (interpolateMotion(): translation linear, rotation by slerp, yaw linear and wrap-safe); an image
  outside the log's span, or between samples more than `max_pose_gap` apart, is skipped and
  counted, never extrapolated. Images and poses whose spans do not overlap at all are an error that
  gives both spans (and says so when one looks like nanoseconds and the other like seconds); so are
  no images matched.
  \param motion A timestamped log (readMotionFile()). \param images Timed images (readImageList()).
  \param options Offset and gap. \param motion_path, images_path Names for the messages.
*/
TimeAlignment alignMotionToImages(const MotionLog &motion, const ImageList &images,
                                  const TimeAlignmentOptions &options, const std::string &motion_path,
                                  const std::string &images_path);

/*!
  \brief What `--motion`, `--motion-format`, `--images`, `--time-offset` and `--max-pose-gap` say,
  for loadMotion().
*/
struct MotionInput {
  std::vector<std::string> motion;          //!< one motion file (Visp: several, or a folder)
  MotionFormat format = MotionFormat::Auto; //!< `--motion-format`
  std::string images;                       //!< `--images`, empty when not given
  std::optional<double> time_offset;        //!< `--time-offset`; unset: the rig file's, else 0
  double max_pose_gap = 0.2;                //!< `--max-pose-gap` (s)
};

/*! \brief A motion log ready for the commands, and how it was made. */
struct LoadedMotion {
  MotionLog log;                          //!< frame-based, with images when they were given
  MotionFormat format = MotionFormat::Yawdepth; //!< the format read
  std::optional<TimeAlignment> alignment; //!< set when a timestamped log was aligned to images
  double time_offset = 0.0;               //!< the offset used (s)
};

/*!
  \brief The one entry point of the commands: reads the motion in its format; a timestamped log is
  aligned to `--images` (required for it), ViSP pose files are paired with `--images` in order (as
  many of each); a frame-based log takes no `--images`. The time offset is `--time-offset`, else
  `rig_time_offset`, else 0.
  \throws yawdepth::Error with a one-line reason naming the file and line.
*/
LoadedMotion loadMotion(const MotionInput &input, std::optional<double> fixed_yaw,
                        std::optional<double> rig_time_offset, const InputLimits &limits = InputLimits());

} // namespace yawdepth
