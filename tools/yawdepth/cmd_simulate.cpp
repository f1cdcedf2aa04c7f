// `yawdepth simulate`: a synthetic sequence with known truth (motion log, tracks, true points).
#include "commands.h"

#include <filesystem>
#include <memory>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>
#include <yawdepth/simulation/scene.h>

namespace yawdepth::cli {

namespace {

struct SimulateArgs {
  std::string camera, camera_name, rig, out_dir;
  SceneOptions scene;
};

} // namespace

Runner addSimulate(CLI::App &app)
{
  auto a = std::make_shared<SimulateArgs>();
  CLI::App *sub = app.add_subcommand(
      "simulate", "Make a synthetic sequence with known truth: motion.csv (dead-reckoned), motion_truth.csv, "
                  "tracks.csv and truth.csv (true points in the points format) in --out-dir.");
  sub->add_option("--camera", a->camera, "Camera file: ViSP XML or OpenCV YAML/XML")->required();
  sub->add_option("--camera-name", a->camera_name, "Camera name in a ViSP XML file");
  sub->add_option("--rig", a->rig, "Rig file (YAML with camera_offset)")->required();
  sub->add_option("--out-dir", a->out_dir, "Output folder (created if missing)")->required();
  SceneOptions &s = a->scene;
  s.noise = NoiseModel{0.0, 0.0, 0.0, 0.0};
  sub->add_option("--frames", s.frames, "Number of frames")->check(CLI::Range(1, 1000000))->capture_default_str();
  sub->add_option("--step", s.step, "Forward translation per frame (m)")->check(Finite)->capture_default_str();
  sub->add_option("--lateral-step", s.lateral_step, "Sideways translation per frame (m)")->check(Finite)->capture_default_str();
  sub->add_option("--yaw", s.yaw, "Camera yaw at the first frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--yaw-rate", s.yaw_rate, "Yaw change per frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--heading", s.heading, "Robot heading at the first frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--turn-rate", s.turn_rate, "Heading change per frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--points", s.points, "Number of 3D points")->check(CLI::Range(0, 10000000))->capture_default_str();
  sub->add_option("--min-depth", s.min_depth, "Nearest depth in the first frame (m)")->check(Finite)->capture_default_str();
  sub->add_option("--max-depth", s.max_depth, "Farthest depth in the first frame (m)")->check(Finite)->capture_default_str();
  sub->add_option("--sigma-px", s.noise.sigma_px, "Pixel noise added to tracks (px)")->check(FiniteNonNegative)->capture_default_str();
  sub->add_option("--sigma-odom", s.noise.sigma_odom, "Odometry noise per increment, per axis (m)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-heading", s.noise.sigma_heading, "Heading noise per increment (rad)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--sigma-yaw", s.noise.sigma_yaw, "Noise of each yaw reading (rad)")->check(FiniteNonNegative)->capture_default_str();
  sub->add_option("--seed", s.seed, "Random seed")->capture_default_str();

  return [a]() {
    const CameraModel camera = loadCameraFile(a->camera, a->camera_name);
    const RigFile rig_file = readRigFile(a->rig);
    const YawRig rig(rig_file.camera_offset);
    const Scene scene = simulateScene(camera, rig, a->scene);

    std::error_code ec;
    std::filesystem::create_directories(a->out_dir, ec);
    if (ec)
      throw Error(a->out_dir + ": cannot create folder: " + ec.message());
    const std::filesystem::path dir(a->out_dir);
    MotionLog measured, truth;
    measured.samples = scene.measured;
    truth.samples = scene.truth;
    writeMotionCsv((dir / "motion.csv").string(), measured);
    writeMotionCsv((dir / "motion_truth.csv").string(), truth);
    writeTracksCsv((dir / "tracks.csv").string(), scene.tracks);

    std::vector<PointRow> rows;
    for (const Track &t : scene.tracks) {
      if (t.observations.empty())
        continue;
      const long frame = t.observations.back().frame;
      std::size_t index = 0;
      while (scene.truth[index].frame != frame)
        ++index;
      PointRow row;
      row.id = t.id;
      row.estimate.status = Status::Ok;
      row.estimate.frame = frame;
      row.estimate.c_P = scene.cameraPoint(rig, t.id, index);
      row.estimate.v_P = rotY(scene.truth[index].yaw) * (row.estimate.c_P + rig.cameraOffset());
      row.estimate.c_cov.setZero();
      rows.push_back(row);
    }
    writePointsCsv((dir / "truth.csv").string(), rows);
    return 0;
  };
}

} // namespace yawdepth::cli
