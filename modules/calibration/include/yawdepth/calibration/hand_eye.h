#pragma once
/*!
  \file hand_eye.h
  \brief Hand-eye calibration of a camera on (or beside) a robot arm from images of a board and
  the robot's poses: the camera's pose on the hand (eye-in-hand, eMc) or in the base
  (eye-to-hand, rMc), with its uncertainty, for a rig file's `camera_pose`.

  Frames (ViSP's names): `r` the robot base, `e` the end-effector (hand), `c` the camera, `o` the
  board (object). Each image i comes with the hand's pose in the base, rMe_i, from the forward
  kinematics. The board is fixed:
  - eye-in-hand: the camera rides on the hand, the board is fixed in the base:
    \f[ {}^cM_{o,i} = ({}^rM_{e,i}\, {}^eM_c)^{-1}\, {}^rM_o \f]
    unknowns X = eMc and Y = rMo;
  - eye-to-hand: the camera is fixed in the base, the board rides on the hand:
    \f[ {}^cM_{o,i} = ({}^rM_c)^{-1}\, {}^rM_{e,i}\, {}^eM_o \f]
    unknowns X = rMc and Y = eMo.
  Both are \f$ {}^cM_{o,i} = X^{-1} A_i\, Y \f$ with A_i = eMr_i or rMe_i.

  Method: each image's board pose cMo_i by PnP on the undistorted corners; ViSP's
  vpHandEyeCalibration::calibrate() (the AX = XB closed form and its non-linear refinement) for a
  start; then the joint maximum a posteriori refinement of X, Y and every hand pose on the
  reprojection error of every corner in every image (Levenberg–Marquardt): the kinematics are not
  exact (an arm's forward kinematics err by a millimetre and a tenth of a degree), so each hand
  pose may move from the measured one, with a Gaussian prior of `sigma_pose_translation` and
  `sigma_pose_rotation` per axis, and the corners weigh `sigma_px` each. Without that, X absorbs the
  kinematics' errors (degrees on the franka set). Uncertainties: the Gauss–Newton information of
  the whitened problem, scaled by the variance factor when it exceeds 1.
*/
#include <string>
#include <vector>
#include <Eigen/Core>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/calibration/board_scale.h>
#include <yawdepth/calibration/time_offset.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/pattern.h>

namespace yawdepth {

/*! \brief Where the camera is. */
enum class HandEyeSetup {
  EyeInHand, //!< the camera on the hand, the board fixed: solves eMc (and rMo)
  EyeToHand  //!< the camera fixed, the board on the hand: solves rMc (and eMo)
};
/*! \brief "eye-in-hand" or "eye-to-hand"; throws yawdepth::Error for another word. */
HandEyeSetup handEyeSetupFromString(const std::string &word);

/*! \brief One image of the hand-eye calibration. */
struct HandEyeView {
  vpHomogeneousMatrix rMe;               //!< the hand's pose in the base when the image was taken
  std::vector<FeatureObservation> features; //!< the board's features detected in the image
  std::string name;                      //!< for messages (the image's path)
};

/*! \brief Options of calibrateHandEye(). */
struct HandEyeOptions {
  HandEyeSetup setup = HandEyeSetup::EyeInHand; //!< where the camera is
  int min_points_per_view = 6;                  //!< views with fewer usable features are left out
  /*! A fit with a larger reprojection RMS failed (wrong poses, a pose log of another run, degrees
      for radians): calibrateHandEye() refuses it rather than return a pose that looks valid. */
  double max_rms_px = 20.0;
  double sigma_px = 0.3;                      //!< corner noise (px)
  double sigma_pose_translation = 1e-3;       //!< error of each hand pose from the kinematics, per axis (m)
  double sigma_pose_rotation = 0.1 * M_PI / 180; //!< the same for its rotation, per axis (rad)
  /*! A fit that moves a hand pose by more than this many of the sigmas above failed (refused). */
  double max_pose_correction_sigmas = 10.0;
  /*! Check the board's size against the hand's motion (board_scale.h): the fit again with a scale
      of the board's points free; a Mismatch is reported in HandEyeCalibration::board_scale, a gross
      one refused. The camera pose stays the one estimated with the size given. */
  bool check_board_scale = true;
  BoardScaleOptions board_scale; //!< when the scale differs enough from 1 to say so
};

/*! \brief Result of calibrateHandEye(). Uncertainties are 1-sigma: (tx, ty, tz) in metres, the
    rotation as a small rotation vector about the pose's own axes (rad). */
struct HandEyeCalibration {
  HandEyeSetup setup = HandEyeSetup::EyeInHand; //!< which setup was solved
  vpHomogeneousMatrix camera_pose;         //!< X: eMc (eye-in-hand) or rMc (eye-to-hand)
  vpHomogeneousMatrix target_pose;         //!< Y: rMo (eye-in-hand) or eMo (eye-to-hand)
  vpHomogeneousMatrix initial_camera_pose; //!< X from vpHandEyeCalibration (the start)
  Eigen::Matrix<double, 6, 1> camera_pose_sigma = Eigen::Matrix<double, 6, 1>::Zero(); //!< 1-sigma of X
  Eigen::Matrix<double, 6, 1> target_pose_sigma = Eigen::Matrix<double, 6, 1>::Zero(); //!< 1-sigma of Y
  double rms_px = 0;         //!< reprojection RMS per coordinate after the joint refinement (px)
  double initial_rms_px = 0; //!< the same with vpHandEyeCalibration's X and the best Y for it (px)
  int views = 0;             //!< views used
  int points = 0;            //!< corners used
  std::vector<double> view_rms_px;      //!< per used view, reprojection RMS per coordinate (px)
  std::vector<std::string> view_names;  //!< per used view, its name
  std::vector<std::string> skipped;     //!< views left out, each with the reason
  double pose_correction_mm = 0;        //!< largest correction of a hand pose's translation (mm)
  double pose_correction_deg = 0;       //!< largest correction of a hand pose's rotation (deg)
  /*! The board's size as the hand's motion sees it (NotEstimated when not checked). Eye-in-hand
      views all at one distance from the board, looking at one point, cannot tell it (the camera
      slides along its axis instead): its sigma is then large and the status Consistent. */
  BoardScaleCheck board_scale;
};

/*!
  \brief Hand-eye calibration (see the file).
  \param camera The calibrated camera (its distortion is used). \param board The board.
  \param views At least 3 views with the board, from robot poses whose rotations differ about at
         least two axes (otherwise X is not determined: an error says so).
  \param options The setup, the noise model and the refusal thresholds.
  Throws yawdepth::Error when too few views are usable, when the rotations are degenerate, or when
  the fit fails (RMS above `max_rms_px`).
*/
HandEyeCalibration calibrateHandEye(const CameraModel &camera, const BoardLayout &board,
                                    const std::vector<HandEyeView> &views, const HandEyeOptions &options = {});

/*! \brief The hand-eye calibration with the time offset (calibrateHandEyeWithTimeOffset()). */
struct TimedHandEyeCalibration {
  HandEyeCalibration hand_eye;    //!< the calibration at the estimated offset
  TimeOffsetEstimate time_offset; //!< the offset (time_offset.h)
  int images_used = 0;            //!< images with the board and a pose over the whole search range
};

/*!
  \brief Hand-eye calibration and the camera-to-motion time offset together, from a board seen
  while the arm moves continuously: for each offset tried the hand poses are interpolated at the
  images' times plus the offset and the calibration solved again (ViSP's start, the joint fit);
  the cost is the joint fit's whitened sum of squares (the corners' reprojection over `sigma_px`
  and the hand poses' departures from the interpolated ones over the kinematics' sigmas). The
  search, the sigma and the refusals are estimateTimeOffsetOverImages()'s, as for the yaw rig: the
  arm must change speed (at a constant velocity an offset is the same as another eMc or board pose),
  and a near-static arm is refused.
  \param camera, board As calibrateHandEye(). \param motion A timestamped log of the hand's 6-DoF
  poses in the base (readMotionFile(): TUM, EuRoC, a yawdepth CSV with t). \param image_times Each
  image's camera-clock time (s). \param features Each image's detected board features (empty when
  not found). \param names Each image's name, for messages. \param options As calibrateHandEye()
  (its refusals and board scale check apply to the final fit). \param search The offsets tried.
  \param max_pose_gap As TimeAlignmentOptions.
*/
TimedHandEyeCalibration calibrateHandEyeWithTimeOffset(const CameraModel &camera, const BoardLayout &board,
                                                       const MotionLog &motion, const std::vector<double> &image_times,
                                                       const std::vector<std::vector<FeatureObservation>> &features,
                                                       const std::vector<std::string> &names,
                                                       const HandEyeOptions &options, const TimeOffsetSearch &search,
                                                       double max_pose_gap = 0.2);

/*! \brief The rig file text for a hand-eye result: `camera_pose` (vMc = X as a vpPoseVector) and
    `camera_pose_sigma`, with comments naming the frames and the fit. */
std::string handEyeRigYaml(const HandEyeCalibration &cal);

} // namespace yawdepth
