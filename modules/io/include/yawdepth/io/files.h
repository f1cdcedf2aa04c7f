#pragma once
/*!
  \file files.h
  \brief The public file formats (docs/formats.md): motion log, feature tracks, rig file,
  points output. Every reader throws yawdepth::Error with a one-line reason naming the file and,
  where there is one, the line and column: missing file, empty file, bad header, missing column,
  text in a number, NaN or infinite number, duplicated or unsorted frames.
*/
#include <Eigen/Core>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>
#include <visp3/core/vpPoseVector.h>
#include <yawdepth/core/input_limits.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief Contents of a rig file (YAML). */
struct RigFile {
  /*! `camera_offset: [x, y, z]` (m): the optical centre in the vision frame at yaw 0, the camera's
      axes parallel to the vision frame's; or the translation of `camera_pose`. */
  Eigen::Vector3d camera_offset = Eigen::Vector3d::Zero();
  /*! `camera_pose: [tx, ty, tz, tux, tuy, tuz]`, instead of `camera_offset`: the camera's pose in the
      vision frame at yaw 0 (vMc; an arm's hand-eye eMc) as a ViSP vpPoseVector (m, theta-u rad). */
  std::optional<vpPoseVector> camera_pose;
  /*! `camera_pose_sigma: [6 numbers]`: 1-sigma of camera_pose (m, rad), as calibrate-rig writes it (informational). */
  std::optional<Eigen::Matrix<double, 6, 1>> camera_pose_sigma;
  std::optional<double> yaw; //!< optional `yaw:` (rad), used when the motion log has no yaw column.
  /*! optional `yaw_offset:` (rad), the zero of the yaw reading: true yaw = reading + yaw_offset.
      Applied to every yaw of the motion log (applyRigFile()). Written by `calibrate-rig`. */
  double yaw_offset = 0.0;
  /*! optional `yaw_axis: [x, y, z]`, the measured direction of the yaw axis in the vision frame
      (unit; ideally (0, 1, 0)). Informational: the estimators take the yaw axis as the vision
      frame's Y; `calibrate-rig` measures it so that a tilted mechanism can be noticed and fixed. */
  std::optional<Eigen::Vector3d> yaw_axis;
  /*! optional `time_offset:` (s): the image at camera time t was taken at motion time
      t + time_offset; used by the commands when `--time-offset` is not given. Written by
      `calibrate-rig --estimate-time-offset`. */
  std::optional<double> time_offset;
  std::optional<double> time_offset_sigma; //!< optional `time_offset_sigma:` (s), informational.
};

/*! \brief The camera mount a rig file describes (from `camera_pose` or `camera_offset`). */
YawRig rigOf(const RigFile &rig);

/*!
  \brief Bring a motion log's yaw readings to true yaws with the rig file: adds `yaw_offset` to
  every row's yaw.
*/
void applyRigFile(const RigFile &rig, std::vector<MotionSample> &motion);

/*!
  \brief Read a rig YAML file. Required: `camera_offset` (3 finite numbers) or `camera_pose` (6),
  not both; optional `yaw`,
  `yaw_offset`, `yaw_axis` (refused when more than 2 degrees from +Y, which is the axis the
  estimators model), and the uncertainties calibrate-rig writes beside them. Any other key is an
  error naming it (a typo must not drop a setting silently).
*/
RigFile readRigFile(const std::string &path);

/*! \brief A motion log: one MotionSample per frame, frames strictly increasing. */
struct MotionLog {
  std::vector<MotionSample> samples; //!< sorted by frame, no duplicates
  std::vector<std::string> images;   //!< same size as samples when the `image` column exists (paths
                                     //!< resolved against the CSV's folder), else empty
  bool yaw_column = true;            //!< whether the yaws were read from a `yaw` column (else fixed)
  /*! Whether the rows are pose samples at times (TUM, EuRoC, a `t` column without `frame`;
      yawdepth/io/recording.h) rather than one per frame: `frame` is then the row's index, and the
      log must be aligned to timed images (alignMotionToImages()) before it meets tracks. */
  bool timestamped = false;
  /*! Each row's time (s, motion clock): the samples' times of a timestamped log, or the images'
      motion-clock times of an aligned one (written as the `t` column); empty when unknown. */
  std::vector<double> times;
  /*! \brief The sample of `frame`, or nullptr when the log has no such frame. */
  const MotionSample *find(long frame) const;
  /*! \brief Index of `frame` in samples, or -1. */
  long indexOf(long frame) const;
};

/*!
  \brief Read a motion log CSV: columns frame,x,y,z,heading,yaw, or in the 6-DoF form
  frame,tx,ty,tz,tux,tuy,tuz[,yaw] (wMv as a vpPoseVector; MotionSample::six_dof), + optional image;
  column order free, unknown columns ignored. When the file has no `yaw` column, `fixed_yaw` is used
  for every row; without either, it is an error for a planar log and yaw 0 for a 6-DoF one. Read as a stream within `limits` (a regular
  file or a pipe, 256 MiB and 1 MiB per line by default: InputLimits).
*/
MotionLog readMotionCsv(const std::string &path, std::optional<double> fixed_yaw = std::nullopt,
                        const InputLimits &limits = InputLimits());

/*!
  \brief The noise model to estimate a motion log with: `noise`, except that a 6-DoF log without a
  `yaw` column has no pan joint, so its yaw is exact (sigma_yaw 0) unless `sigma_yaw_given` (the
  caller set sigma_yaw on purpose). `yawdepth estimate`/`measure` and the Python module use it.
  \param noise The noise model given. \param six_dof Whether the log's rows are 6-DoF
  (MotionSample::six_dof). \param yaw_column Whether it has a yaw column (MotionLog::yaw_column).
  \param sigma_yaw_given Whether noise.sigma_yaw was given by the user rather than left at its default.
*/
NoiseModel noiseForMotionLog(const NoiseModel &noise, bool six_dof, bool yaw_column, bool sigma_yaw_given);

/*!
  \brief Read feature tracks CSV: columns frame,id,u,v (any order, unknown columns ignored).
  Returns the tracks sorted by id, each track's observations sorted by frame. A repeated
  (frame, id) pair is an error. Read as a stream within `limits`, as readMotionCsv().
*/
std::vector<Track> readTracksCsv(const std::string &path, const InputLimits &limits = InputLimits());

/*!
  \brief Check the tracks against the motion log by the estimators' rules (yawdepth::validateInputs():
  every observed frame in the log, ...); throws yawdepth::Error naming the tracks file, the feature
  and the frame.
*/
void checkTracksAgainstMotion(const std::vector<Track> &tracks, const MotionLog &motion,
                              const std::string &tracks_path);

/*!
  \brief Refuse a motion log with a step that no motion between two frames can be: throws
  yawdepth::Error naming the first such row.

  A step is refused when the vision frame moved more than 1 m and more than 1000 times the log's
  median step (at least 1 cm: a log that mostly stands still), or when the heading or the yaw
  reading changed by more than 3 pi (one wrap of the angle, +pi to -pi, plus half a turn: a rotation
  of more than half a turn between two frames cannot be told from its opposite). Such a row is a
  glitch of the log (a wrong unit, a corrupted number); estimating through it gives numbers that
  look valid and are not.
  \param motion The log. \param motion_path Its name, for the message.
*/
void checkMotionSteps(const MotionLog &motion, const std::string &motion_path);

/*!
  \brief Mistakes of units a motion log's numbers suggest, one line each (empty: none): a yaw or
  heading column beyond a full turn (2 pi) or turning more than 1 rad between two rows (degrees
  given as radians?), a theta-u rotation beyond pi (theta-u angles are at most half a turn).
  Warnings, not errors: a continuous pan joint may wind past a turn.
  \param motion The log. \param motion_path Its name, for the message.
*/
std::vector<std::string> motionWarnings(const MotionLog &motion, const std::string &motion_path);

/*!
  \brief Mistakes a rig file's numbers suggest, one line each (empty: none): the camera more than
  2 m from the vision frame's origin (millimetres given as metres?), a yaw_offset beyond a full turn
  (degrees?).
  \param rig The rig file. \param rig_path Its name, for the message.
*/
std::vector<std::string> rigWarnings(const RigFile &rig, const std::string &rig_path);

/*! \brief One output row: a feature id and its estimate. */
struct PointRow {
  long id = 0;             //!< Feature id, as in the tracks file.
  PointEstimate estimate;  //!< Its estimate at the last frame in which it was observed.
};

/*!
  \brief Write points CSV: header `id,frame,x,y,z,xc,yc,zc,sigma_zc,status`, numbers with 17
  significant digits; numbers are left empty when the status is not ok.
*/
void writePointsCsv(std::ostream &out, const std::vector<PointRow> &rows);
/*!
  \brief Same, to a file, atomically: written to a temporary file beside `path` and renamed over
  it only once complete, so a failed run never leaves a partial file looking complete.
*/
void writePointsCsv(const std::string &path, const std::vector<PointRow> &rows);

/*! \brief One vertex of a PLY point cloud (`--ply FILE`). */
struct PlyPoint {
  long id = 0;                                  //!< Feature id (within 32 bits).
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero(); //!< Position in the motion log's world frame (m).
  double sigma_z = 0;                           //!< 1-sigma depth uncertainty at its frame (m).
  int gray = -1;                                //!< Gray level at the feature (0-255), -1 when unknown.
};
/*!
  \brief The `ok` points of `rows` in the motion log's world frame:
  \f$ {}^wP = {}^wT_c(\text{frame})\, {}^cP \f$ with wMc() of the motion row of each point's frame.
  \param rig The rig. \param samples The motion (as estimated, when the method refines it).
  \param rows The points. \param gray Gray level of feature id at frame, keyed (frame, id), when known.
  Throws yawdepth::Error when a point's frame is not in `samples`.
*/
std::vector<PlyPoint> plyPoints(const YawRig &rig, const std::vector<MotionSample> &samples,
                                const std::vector<PointRow> &rows,
                                const std::map<std::pair<long, long>, int> &gray = {});
/*!
  \brief A PLY point cloud, ASCII 1.0 (MeshLab, CloudCompare, Open3D, PCL read it): per vertex
  `x y z` (double, m), `red green blue` (uchar, the gray level; only when every point has one),
  `sigma_z` (double, m) and `id` (int).
*/
std::string plyText(const std::vector<PlyPoint> &points);
/*! \brief plyText() to a file, atomically. */
void writePointsPly(const std::string &path, const std::vector<PlyPoint> &points);

/*! \brief Write a motion log CSV (frame,x,y,z,heading,yaw[,image], or the 6-DoF form when the
    samples are 6-DoF), atomically, 17 significant digits. */
void writeMotionCsv(const std::string &path, const MotionLog &motion);
/*! \brief Write feature tracks CSV (frame,id,u,v), rows ordered by frame then id, atomically. */
void writeTracksCsv(const std::string &path, const std::vector<Track> &tracks);
/*! \brief Write a rig YAML file, atomically. */
void writeRigFile(const std::string &path, const RigFile &rig);

/*!
  \brief Read a whole points CSV back (for tests and tools). Empty numbers read as NaN.

  The file holds only `sigma_zc` of the covariance: the estimates' `c_cov` is NaN except
  `c_cov(2, 2) = sigma_zc^2`, so that `sigmaZ()` returns `sigma_zc` exactly. A file with a header and
  no rows is valid (no points).
*/
std::vector<PointRow> readPointsCsv(const std::string &path, const InputLimits &limits = InputLimits());

} // namespace yawdepth
