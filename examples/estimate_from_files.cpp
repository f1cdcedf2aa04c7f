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
#include <vector>

#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/estimation/track_estimator.h>
#include <yawdepth/io/files.h>

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

    // Method::Exact (the default) uses each track's last two observations; Method::Paper is the
    // published eq. (5), kept for comparison.
    yawdepth::TrackEstimatorOptions options;
    options.method = yawdepth::Method::Exact;
    // sigma_zc is propagated from options.two_view.noise (default 0.3 px, 1 mm odometry per
    // increment, 0.05 deg heading and yaw): set it to your sensors' noise.

    std::printf("%zu features, %zu motion rows, camera kx = %.1f px\n", tracks.size(), motion.samples.size(),
                camera.kx());
    std::printf("%4s %6s %10s %10s  %s\n", "id", "frame", "Zc (m)", "sigma (mm)", "status");
    std::size_t ok = 0;
    for (const yawdepth::Track &track : tracks) {
      const yawdepth::PointEstimate e = yawdepth::estimateTrack(camera, rig, motion.samples, track, options);
      if (e.ok()) {
        ++ok;
        std::printf("%4ld %6ld %10.4f %10.2f  %s\n", track.id, e.frame, e.c_P.z(), 1e3 * e.sigmaZ(),
                    yawdepth::toString(e.status));
      } else { // no numbers for an invalid estimate, only the reason
        std::printf("%4ld %6ld %10s %10s  %s\n", track.id, e.frame, "-", "-", yawdepth::toString(e.status));
      }
    }
    std::printf("%zu of %zu features have a valid depth\n", ok, tracks.size());
  } catch (const yawdepth::Error &e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
