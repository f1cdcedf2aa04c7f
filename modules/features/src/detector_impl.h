#pragma once
/*!
  \file detector_impl.h
  \brief PatternDetector's state, shared by detector.cpp, chessboard_detector.cpp and
  apriltag_detector.cpp (private to the features module, never installed).
*/
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <visp3/detection/vpDetectorAprilTag.h>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/detector.h>

namespace yawdepth {

struct PatternDetector::Impl {
  PatternSpec pattern;
  DetectorOptions options;
  std::unique_ptr<vpDetectorAprilTag> apriltag;
  std::map<long, cv::Point2d> previous; //!< last chessboard detection, id -> pixel
  CameraModel camera;                   //!< for the AprilTag centre (diagonals on undistorted corners)
  bool camera_ok = false;

  FrameDetection detectChessboard(const cv::Mat &gray, long frame);
  FrameDetection detectAprilTag(const cv::Mat &gray, long frame);
};

/*! \brief ViSP's AprilTag detector for the pattern's family, set up with the options; throws
    yawdepth::Error for a family this ViSP does not have. */
std::unique_ptr<vpDetectorAprilTag> makeAprilTagDetector(const PatternSpec &pattern, const DetectorOptions &options);

} // namespace yawdepth
