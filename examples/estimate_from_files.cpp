/*
  estimate_from_files: estimate every tracked feature's 3D point from files.

  Usage: estimate_from_files <camera.yaml|.xml> <rig.yaml> <motion.csv> <tracks.csv>

  The four inputs are the project's public file formats (docs/formats.md); for instance
  `yawdepth simulate --camera calib/paper_camera.yaml --rig calib/paper_rig.yaml --out-dir DIR`
  writes a motion.csv and a tracks.csv to try it on. Each reader throws yawdepth::Error with a
  one-line message naming the file (and line) at fault; this program prints it and returns 1.
*/
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>
#include <yawdepth/pipeline/pipeline.h>

int main(int argc, char **argv)
{
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s <camera file> <rig.yaml> <motion.csv> <tracks.csv>\n", argv[0]);
    return 1;
  }
  try {
    // Camera: ViSP XML (vpXmlParserCamera) or OpenCV YAML/XML with distortion coefficients.
    const yawdepth::CameraModel camera = yawdepth::loadCameraFile(argv[1]);
    // Rig: the optical centre's offset from the yaw axis, and optionally a fixed yaw.
    const yawdepth::RigFile rig_file = yawdepth::readRigFile(argv[2]);
    const yawdepth::YawRig rig = yawdepth::rigOf(rig_file);
    // Motion log (one row per frame); the rig's fixed yaw is used if the log has no yaw column.
    const yawdepth::MotionLog motion = yawdepth::readMotionCsv(argv[3], rig_file.yaw);
    // Tracks: every observation of every feature, grouped by feature id.
    const std::vector<yawdepth::Track> tracks = yawdepth::readTracksCsv(argv[4]);
    yawdepth::checkTracksAgainstMotion(tracks, motion, argv[4]); // every frame must be in the log

    // The entry point for every method: estimatePoints(). Method::Window (every point with the last
    // frames' motion) runs in every build; bestMethod() is refine where Ceres was found. The noise
    // model (default 0.3 px, 1 mm odometry per increment, 0.05 deg heading and yaw) weighs every
    // observation and gives the sigmas: set it to your sensors' noise. The residual check measures
    // the pixel noise from the tracks and flags tracks that are not one point.
    yawdepth::PipelineOptions options;
    options.method = yawdepth::Method::Window;
    options.residual_check.enabled = true;
    const yawdepth::PipelineResult result = yawdepth::estimatePoints(camera, rig, motion.samples, tracks, options);
    for (const std::string &warning : result.warnings) // what the data say is wrong (units, signs, offsets)
      std::fprintf(stderr, "warning: %s\n", warning.c_str());

    std::printf("%zu features, %zu motion rows, camera kx = %.1f px, pixel noise %.2f px\n", tracks.size(),
                motion.samples.size(), camera.kx(), result.noise.sigma_px);
    std::printf("%4s %6s %10s %10s  %s\n", "id", "frame", "Zc (m)", "sigma (mm)", "status");
    std::size_t ok = 0;
    for (std::size_t i = 0; i < tracks.size(); ++i) {
      const yawdepth::PointEstimate &e = result.points[i]; // one per track, at its last observation
      if (e.ok()) {
        ++ok;
        std::printf("%4ld %6ld %10.4f %10.2f  %s\n", tracks[i].id, e.frame, e.c_P.z(), 1e3 * e.sigmaZ(),
                    yawdepth::toString(e.status));
      } else { // no numbers for an invalid estimate, only the reason
        std::printf("%4ld %6ld %10s %10s  %s\n", tracks[i].id, e.frame, "-", "-", yawdepth::toString(e.status));
      }
    }
    std::printf("%zu of %zu features have a valid depth\n", ok, tracks.size());
  } catch (const yawdepth::Error &e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
