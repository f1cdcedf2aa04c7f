// libFuzzer target: yawdepth::loadCameraFile (ViSP camera XML through vpXmlParserCamera, OpenCV
// YAML/XML through cv::FileStorage, ROS camera_info and Kalibr camchain YAML through yaml-cpp; the
// format is detected from the content).
#include "fuzz_common.h"

#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".camera");
  const std::string &path = file.write(data, size);
  // Both with and without a camera name: a ViSP file with several cameras needs one; cam1 picks
  // a Kalibr camchain's second camera.
  for (const char *name : {"", "paper", "cam1"}) {
    try {
      const yawdepth::CameraModel camera = yawdepth::loadCameraFile(path, name);
      // A loaded camera must be usable, near its centre and at an image corner (a fisheye's
      // corner may be beyond 90 degrees: undistort() then returns false).
      Eigen::Vector2d m;
      camera.undistort(Eigen::Vector2d(camera.u0() + 10.0, camera.v0() - 7.0), m);
      camera.undistort(Eigen::Vector2d(-0.5, -0.5), m);
    } catch (const yawdepth::Error &) {
    }
  }
  return 0;
}
