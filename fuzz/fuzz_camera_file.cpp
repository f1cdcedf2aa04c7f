// libFuzzer target: yawdepth::loadCameraFile (ViSP camera XML through vpXmlParserCamera, OpenCV
// YAML/XML through cv::FileStorage; the format is detected from the content).
#include "fuzz_common.h"

#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  static const yawdepth_fuzz::TempFile file(".camera");
  const std::string &path = file.write(data, size);
  // Both with and without a camera name: a ViSP file with several cameras needs one.
  for (const char *name : {"", "paper"}) {
    try {
      const yawdepth::CameraModel camera = yawdepth::loadCameraFile(path, name);
      // A loaded camera must be usable.
      Eigen::Vector2d m;
      camera.undistort(Eigen::Vector2d(camera.u0() + 10.0, camera.v0() - 7.0), m);
    } catch (const yawdepth::Error &) {
    }
  }
  return 0;
}
