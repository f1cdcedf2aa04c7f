#pragma once
/*!
  \file board_report.h
  \brief The paper's Fig. 3 metrics of a measured board: block lengths, plane fit and each point's
  distance to it, as a table and as a PNG figure.
*/
#include <Eigen/Core>
#include <string>
#include <vector>
#include <yawdepth/core/types.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief A measured point of the board in one common frame (the world of the motion log). */
struct BoardPoint {
  long id = 0;                                   //!< feature id
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero(); //!< in the world frame (m)
  Eigen::Vector3d c_P = Eigen::Vector3d::Zero(); //!< in the camera frame of its frame (m)
  long frame = 0;                                //!< frame the point was estimated at
};

/*! \brief A distance between two neighbouring features (m). */
struct BlockLength {
  long id_a = 0;           //!< id of the first feature
  long id_b = 0;           //!< id of the second feature
  double length = 0;       //!< distance between the two (m)
};

/*! \brief Metrics of a measured board (lengths in metres). */
struct BoardMetrics {
  std::vector<BoardPoint> points;        //!< the valid points used
  std::vector<BlockLength> horizontal;   //!< along the board's rows (chessboard) / tag bottom and top edges
  std::vector<BlockLength> vertical;     //!< along the columns / tag left and right edges
  double nominal = 0;                    //!< the true block length (square or tag size)
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ(); //!< fitted plane (least squares, SVD)
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();   //!< a point of the fitted plane (the points' centroid)
  std::vector<double> plane_distance;    //!< signed distance of each point to the plane, same order as points
  double max_plane_distance = 0;         //!< largest |distance|
  double min_depth = 0;                  //!< smallest camera-frame depth of the points
  double max_depth = 0;                  //!< largest camera-frame depth of the points
  /*! Chessboard: the board's pose in the world (wMo) by a rigid least-squares fit (Umeyama) of the
      nominal corners, corner id r*COLS+c at (c SQUARE, r SQUARE, 0), to the measured ones: ViSP's and
      OpenCV's chessboard frame (origin at corner 0, x along a row). Only when `has_board_pose`. */
  bool has_board_pose = false;
  Eigen::Matrix3d w_R_o = Eigen::Matrix3d::Identity(); //!< rotation of the board frame in the world
  Eigen::Vector3d w_t_o = Eigen::Vector3d::Zero();     //!< the board origin (corner 0's nominal place) in the world (m)
  double board_fit_rms = 0;                           //!< RMS distance of the measured corners to the fitted nominal board (m)
  double board_scale = 1;                             //!< measured / nominal size (a similarity fit's scale)
  /*! \brief min, max, mean of a set of block lengths. */
  static Eigen::Vector3d stats(const std::vector<BlockLength> &v);
  /*! \brief The q-quantile (0..1, linear interpolation) of every block length, horizontal and vertical. */
  double quantile(double q) const;
  /*! \brief The fraction of all block lengths within `tolerance` of the nominal (m). */
  double fractionWithin(double tolerance) const;
};

/*!
  \brief Compute the metrics from estimated points.
  \param pattern The board's pattern (neighbour structure and nominal length).
  \param rig Yaw rig.
  \param rows Estimated points (only `ok` ones are used), each at its own frame.
  \param motion The motion log used, to bring every point into its world frame.
  \throws yawdepth::Error when fewer than 3 valid points remain.
*/
BoardMetrics boardMetrics(const PatternSpec &pattern, const YawRig &rig, const std::vector<MotionSample> &motion,
                          const std::vector<std::pair<long, PointEstimate>> &rows);

/*! \brief The metrics as a plain-text table (what `measure --report` prints and writes). */
std::string formatBoardMetrics(const BoardMetrics &m);

/*!
  \brief Write `report.txt`, `blocks.csv`, `plane.csv` and `figure.png` into `dir` (created).
  The figure has three panels: the points in the fitted plane with each block length, the
  distance of each point to the plane, and the points seen from above (X against depth).
  \param dir Output folder.
  \param m The metrics.
  \param title One line for the figure's title.
*/
void writeBoardReport(const std::string &dir, const BoardMetrics &m, const std::string &title);

/*! \brief The files writeBoardReport() writes into `dir` (for checks before writing). \param dir The folder. */
std::vector<std::string> boardReportFiles(const std::string &dir);

} // namespace yawdepth
