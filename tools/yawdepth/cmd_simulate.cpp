// `yawdepth simulate`: a synthetic sequence with known truth. Random 3D points (tracks only), or a
// rendered chessboard / AprilTag board (images named in motion.csv, plus tracks of the true
// feature positions).
#include <functional>
#include <utility>
#include "commands.h"
#include "progress.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/io/files.h>
#include <yawdepth/render/renderer.h>
#include <yawdepth/simulation/scene.h>

namespace yawdepth::cli {

namespace {

struct SimulateArgs {
  std::string camera, camera_name, rig, out_dir;
  SceneOptions scene;
  std::string arm;           // --arm: a 6-DoF path (approach, orbit, random), or empty for the planar robot
  double arm_distance = 0.6; // --arm-distance (m)
  // Board mode.
  std::string pattern;
  double board_distance = 0.62, board_tilt = 0.0, board_offset_x = 0.0, board_offset_y = 0.0;
  std::string tags;
  double tag_gap = -1;
  double outer_square = 0;
  bool photo = false, quiet = false;
  RenderOptions render;
  /*! the options --photo sets when they are not given, each with how to take the preset's value */
  std::vector<std::pair<CLI::Option *, std::function<void(RenderOptions &, const RenderOptions &)>>> photo_options;
};

/* Pose of the board in the world: facing the first camera, its pattern centred on the optical
   axis at `distance`, turned by `tilt` about the board's vertical axis. */
Eigen::Isometry3d boardPose(const YawRig &rig, const MotionSample &first, const BoardLayout &board, const SimulateArgs &a)
{
  // Centre of the features (not of the margin).
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
  for (const auto &f : board.features()) {
    lo = lo.cwiseMin(f.second);
    hi = hi.cwiseMax(f.second);
  }
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  Eigen::Isometry3d cMb = Eigen::Isometry3d::Identity();
  cMb.linear() = rotY(a.board_tilt);
  cMb.translation() = Eigen::Vector3d(a.board_offset_x, a.board_offset_y, a.board_distance) - cMb.linear() * centre;
  return toIsometry(wMc(rig, first)) * cMb;
}

/* The scene's options: files, the planar robot's path or --arm's, the points, the noise, the seed. */
void addSimulateSceneOptions(CLI::App *sub, SimulateArgs &a)
{
  addCameraOptions(sub, a.camera, a.camera_name, true, "with the image size to render a board");
  addRigOption(sub, a.rig, true);
  sub->add_option("--out-dir", a.out_dir, "Output folder (created if missing)")->required();
  SceneOptions &s = a.scene;
  s.noise = NoiseModel{0.0, 0.0, 0.0, 0.0, 0.0};
  sub->add_option("--frames", s.frames, "Number of frames")->check(CLI::Range(1, 1000000))->capture_default_str();
  sub->add_option("--step", s.step, "Forward translation per frame (m)")->check(Finite)->capture_default_str();
  sub->add_option("--lateral-step", s.lateral_step, "Sideways translation per frame (m)")->check(Finite)->capture_default_str();
  sub->add_option("--yaw", s.yaw, "Camera yaw at the first frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--yaw-rate", s.yaw_rate, "Yaw change per frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--heading", s.heading, "Robot heading at the first frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--turn-rate", s.turn_rate, "Heading change per frame (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--points", s.points, "Number of random 3D points (without --pattern)")
      ->check(CLI::Range(0, 10000000))
      ->capture_default_str();
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
  sub->add_option("--sigma-rot", s.noise.sigma_rot, "Rotation noise per increment, per axis, with --arm (rad)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--motion-noise", [&s](const std::string &w) { s.noise.motion_noise = motionNoiseFromString(w); },
         "How the written motion log errs: increment (dead reckoning, the errors accumulate) or absolute (each pose "
         "errs by --sigma-odom and --sigma-rot/--sigma-heading about the truth, as forward kinematics)")
      ->check(CLI::IsMember({"increment", "absolute"}))
      ->default_str("increment");
  // 6-DoF mode: an arm-like camera path instead of the planar robot.
  CLI::Option *arm = sub->add_option("--arm", a.arm,
                                     "A 6-DoF arm-like path instead of the planar robot: approach, orbit or random "
                                     "(motion.csv then has the 6-DoF columns tx,ty,tz,tux,tuy,tuz)")
                         ->check(CLI::IsMember({"approach", "orbit", "random"}));
  sub->add_option("--arm-distance", a.arm_distance, "With --arm: distance of the target the camera looks at (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  for (const char *planar : {"--step", "--lateral-step", "--heading", "--turn-rate", "--sigma-heading"})
    arm->excludes(planar);
  sub->add_option("--seed", s.seed, "Random seed")->capture_default_str();
}

/* Board mode's options: the pattern, its pose, and how its images are rendered (--photo's preset). */
void addSimulateBoardOptions(CLI::App *sub, SimulateArgs &a)
{
  sub->add_option("--pattern", a.pattern,
                  "Render a board instead of random points: chessboard:COLSxROWS:SQUARE or apriltag:FAMILY:SIZE");
  sub->add_option("--board-distance", a.board_distance, "Board centre along the first camera's optical axis (m)")
      ->check(Finite)
      ->capture_default_str();
  sub->add_option("--board-tilt", a.board_tilt, "Board turned about its vertical axis (rad)")->check(Finite)->capture_default_str();
  sub->add_option("--board-offset-x", a.board_offset_x, "Board centre offset along the first camera's X (m)")
      ->check(Finite)
      ->capture_default_str();
  sub->add_option("--board-offset-y", a.board_offset_y, "Board centre offset along the first camera's Y (m)")
      ->check(Finite)
      ->capture_default_str();
  addTagsOption(sub, a.tags);
  sub->add_option("--tag-gap", a.tag_gap, "AprilTag board: gap between tags (m; default a quarter tag)")->check(Finite);
  sub->add_option("--blur", a.render.blur_sigma_px, "Optical blur, Gaussian sigma (px)")->check(FiniteNonNegative)->capture_default_str();
  sub->add_option("--image-noise", a.render.noise_sigma, "Sensor noise, Gaussian sigma (gray levels)")
      ->check(FiniteNonNegative)
      ->capture_default_str();
  sub->add_option("--wall", a.render.wall_texel,
                  "The board hangs on a textured wall in its plane (smooth random texture, blobs about WALL m across, "
                  "seeded by --seed), for natural-feature tracking; 0 = a uniform background")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  sub->add_option("--outer-square", a.outer_square, "Chessboard: width of the outer squares (m; default a full square)")
      ->check(FiniteNonNegative);
  sub->add_flag("--photo", a.photo,
                "Make the images look like a consumer camera's photographs (the options below, unless given): "
                "light gradient 0.3, vignetting 0.35, defocus 1.5 px, Bayer, shot noise 0.15, image noise 1.5, "
                "gamma 2.2, JPEG 85, blur 0.6");
  // Each option --photo sets when it is not given, with how to take the preset's value.
  using Copy = std::function<void(RenderOptions &, const RenderOptions &)>;
  const auto photo = [&](CLI::Option *o, Copy copy) { a.photo_options.emplace_back(o, std::move(copy)); };
  photo(sub->add_option("--light-gradient", a.render.light_gradient, "Relative change of the light across the image (0..1)")
            ->check(CLI::Range(0.0, 1.0)),
        [](RenderOptions &r, const RenderOptions &p) { r.light_gradient = p.light_gradient; });
  photo(sub->add_option("--vignetting", a.render.vignetting, "Relative fall-off of the light at the image corners (0..1)")
            ->check(CLI::Range(0.0, 1.0)),
        [](RenderOptions &r, const RenderOptions &p) { r.vignetting = p.vignetting; });
  photo(sub->add_option("--defocus", a.render.defocus_px, "Defocus blur sigma (px) = DEFOCUS x |focus distance / depth - 1|")
            ->check(CLI::Range(0.0, 1000.0)),
        [](RenderOptions &r, const RenderOptions &p) { r.defocus_px = p.defocus_px; });
  photo(sub->add_option("--shot-noise", a.render.shot_noise, "Shot noise variance per gray level of signal")
            ->check(FiniteNonNegative),
        [](RenderOptions &r, const RenderOptions &p) { r.shot_noise = p.shot_noise; });
  photo(sub->add_option("--gamma", a.render.gamma, "Response curve: out = 255 (in / 255)^(1 / GAMMA)")->check(CLI::Range(0.1, 10.0)),
        [](RenderOptions &r, const RenderOptions &p) { r.gamma = p.gamma; });
  photo(sub->add_option("--jpeg-quality", a.render.jpeg_quality, "JPEG round trip at this quality (1..100; 0 = none)")
            ->check(CLI::Range(0, 100)),
        [](RenderOptions &r, const RenderOptions &p) { r.jpeg_quality = p.jpeg_quality; });
  photo(sub->add_flag("--bayer", a.render.bayer, "Bayer mosaic (RGGB) and demosaicing"),
        [](RenderOptions &r, const RenderOptions &p) { r.bayer = p.bayer; });
  photo(sub->get_option("--image-noise"), [](RenderOptions &r, const RenderOptions &p) { r.noise_sigma = p.noise_sigma; });
  photo(sub->get_option("--blur"), [](RenderOptions &r, const RenderOptions &p) { r.blur_sigma_px = p.blur_sigma_px; });
  sub->add_option("--focus-distance", a.render.focus_distance, "Depth in focus for --defocus (m; default the board distance)")
      ->check(FiniteNonNegative);
  sub->add_option("--supersampling", a.render.supersampling, "Anti-aliasing samples per pixel side")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
}

/* The render options as given, completed by --photo's preset and the focus distance, checked. */
void completeRenderOptions(const CameraModel &camera, SimulateArgs &a)
{
  if (a.photo) {
    const RenderOptions preset = photoLikeRenderOptions(a.board_distance);
    for (const auto &[option, copy] : a.photo_options)
      if (option->count() == 0)
        copy(a.render, preset);
  }
  if (a.render.defocus_px > 0 && !(a.render.focus_distance > 0))
    a.render.focus_distance = a.board_distance;
  checkRenderOptions(camera, a.render);
}

/* --out-dir created, and its four logs checked against the inputs. */
void makeOutputFolder(const SimulateArgs &a)
{
  std::error_code ec;
  std::filesystem::create_directories(a.out_dir, ec);
  if (ec)
    throw Error(a.out_dir + ": cannot create folder: " + ec.message());
  const std::filesystem::path dir(a.out_dir);
  const std::vector<NamedPath> inputs = {{"--camera", a.camera}, {"--rig", a.rig}};
  std::vector<NamedPath> outputs;
  for (const char *name : {"motion.csv", "motion_truth.csv", "tracks.csv", "truth.csv"})
    outputs.push_back({"--out-dir", (dir / name).string()});
  checkOutputs(inputs, outputs);
}

/* The board of --pattern, --outer-square, --tags and --tag-gap. */
BoardLayout simulatedBoard(const SimulateArgs &a)
{
  BoardLayout board;
  board.pattern = PatternSpec::parse(a.pattern);
  if (a.outer_square > 0) {
    if (board.pattern.kind != PatternSpec::Kind::Chessboard || a.outer_square > board.pattern.square)
      throw Error("--outer-square: a chessboard's outer squares, at most one square wide");
    board.outer_square = a.outer_square;
  }
  if (board.pattern.kind == PatternSpec::Kind::AprilTag) {
    int tx = 0, ty = 0;
    char x = 0;
    if (std::sscanf(a.tags.c_str(), "%d%c%d", &tx, &x, &ty) != 3 || x != 'x' || tx < 1 || ty < 1 || tx > 50 ||
        ty > 50)
      throw Error("--tags must be COLSxROWS with 1..50 tags each, not '" + a.tags + "'");
    board.tags_x = tx;
    board.tags_y = ty;
    board.gap = a.tag_gap >= 0 ? a.tag_gap : 0.25 * board.pattern.tag_size;
  }
  return board;
}

/* The board's image at every true pose, written to --out-dir as frame_NNNN.png and named in both logs. */
void renderBoardImages(const CameraModel &camera, const YawRig &rig, const Scene &scene, const BoardLayout &board,
                       const Eigen::Isometry3d &wMb, const SimulateArgs &a, MotionLog &measured, MotionLog &truth)
{
  const std::filesystem::path dir(a.out_dir);
  ProgressLine progress;
  for (std::size_t k = 0; k < scene.truth.size(); ++k) {
    progress.count("simulate", k, scene.truth.size(), "images rendered");
    RenderOptions ro = a.render;
    ro.seed = a.scene.seed * 1000003ULL + k;
    ro.wall_seed = a.scene.seed;
    const cv::Mat img = renderBoard(camera, rig, scene.truth[k], board, wMb, ro);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.png", k);
    const std::string path = (dir / name).string();
    std::vector<unsigned char> png;
    if (!cv::imencode(".png", img, png))
      throw Error(path + ": cannot encode the image");
    if (sameFile(path, a.camera) || sameFile(path, a.rig))
      throw Error("--out-dir: " + path + " is an input (refusing to overwrite it)");
    writeFileAtomically(path, std::string(png.begin(), png.end()));
    measured.images.push_back(path);
    truth.images.push_back(path);
  }
  progress.count("simulate", scene.truth.size(), scene.truth.size(), "images rendered");
}

/* Tracks of the true feature positions (with --sigma-px noise), like a perfect detector: each point
   wherever it is in front of the camera and inside the image. */
std::vector<Track> trueFeatureTracks(const CameraModel &camera, const YawRig &rig, const Scene &scene,
                                     const std::vector<long> &ids, const std::vector<Eigen::Vector3d> &w_points,
                                     const SimulateArgs &a)
{
  std::mt19937_64 rng(a.scene.seed + 17);
  std::normal_distribution<double> g(0.0, 1.0);
  const double sigma_px = a.scene.noise.sigma_px;
  std::vector<Track> tracks;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    Track t;
    t.id = ids[i];
    for (const MotionSample &row : scene.truth) {
      Eigen::Matrix3d R;
      Eigen::Vector3d tt;
      fromVisp(wMc(rig, row).inverse(), R, tt);
      const Eigen::Vector3d c = R * w_points[i] + tt;
      if (!(c.z() > 1e-6))
        continue;
      const Eigen::Vector2d uv = camera.project(c.head<2>() / c.z());
      if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() <= camera.width() - 1.0 && uv.y() <= camera.height() - 1.0))
        continue;
      t.observations.push_back({row.frame, uv.x() + sigma_px * g(rng), uv.y() + sigma_px * g(rng)});
    }
    tracks.push_back(t);
  }
  return tracks;
}

/* truth.csv's rows: each tracked point in its track's last frame, from the true motion. */
std::vector<PointRow> truthRows(const YawRig &rig, const Scene &scene, const std::vector<Track> &tracks,
                                const std::vector<Eigen::Vector3d> &w_points)
{
  std::vector<PointRow> rows;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const Track &t = tracks[i];
    if (t.observations.empty())
      continue;
    const long frame = t.observations.back().frame;
    std::size_t index = 0;
    while (scene.truth[index].frame != frame)
      ++index;
    Eigen::Matrix3d R;
    Eigen::Vector3d tt;
    fromVisp(wMc(rig, scene.truth[index]).inverse(), R, tt);
    PointRow row;
    row.id = t.id;
    row.estimate.status = Status::Ok;
    row.estimate.frame = frame;
    row.estimate.c_P = R * w_points[i] + tt;
    row.estimate.v_P = rig.visionPoint(scene.truth[index].yaw, row.estimate.c_P);
    row.estimate.c_cov.setZero();
    rows.push_back(row);
  }
  return rows;
}

int runSimulate(SimulateArgs &a)
{
  const CameraModel camera = loadCameraFile(a.camera, a.camera_name);
  const RigFile rig_file = readCommandRig("simulate", a.rig);
  const YawRig rig = rigOf(rig_file);
  const bool board_mode = !a.pattern.empty();
  SceneOptions so = a.scene;
  if (board_mode)
    so.points = 0;
  if (!a.arm.empty())
    so.vision_poses = armTrajectory(rig, armPathFromString(a.arm), so.frames, a.arm_distance, so.seed, so.yaw);
  if (board_mode)
    completeRenderOptions(camera, a); // before the output folder is created
  const Scene scene = simulateScene(camera, rig, so);
  stage("simulate", "scene of " + std::to_string(scene.truth.size()) + " frames");
  makeOutputFolder(a);

  std::vector<long> ids;
  std::vector<Eigen::Vector3d> w_points;
  std::vector<Track> tracks = scene.tracks;
  MotionLog measured, truth;
  measured.samples = scene.measured;
  truth.samples = scene.truth;
  if (board_mode) {
    const BoardLayout board = simulatedBoard(a);
    if (camera.width() == 0 || camera.height() == 0)
      throw Error(a.camera + ": the camera file has no image size (image_width, image_height): cannot render");
    const Eigen::Isometry3d wMb = boardPose(rig, scene.truth.front(), board, a);
    for (const auto &f : board.features()) {
      ids.push_back(f.first);
      w_points.push_back(wMb * f.second);
    }
    renderBoardImages(camera, rig, scene, board, wMb, a, measured, truth);
    stage("simulate", std::to_string(scene.truth.size()) + " images rendered");
    tracks = trueFeatureTracks(camera, rig, scene, ids, w_points, a);
  } else {
    for (std::size_t i = 0; i < scene.w_points.size(); ++i) {
      ids.push_back(static_cast<long>(i));
      w_points.push_back(scene.w_points[i]);
    }
  }
  // The logs hold yaw *readings*: true yaw minus the rig's yaw_offset (its reading's zero).
  for (auto *log : {&measured, &truth})
    for (MotionSample &m : log->samples)
      m.yaw -= rig_file.yaw_offset;
  const std::filesystem::path dir(a.out_dir);
  writeMotionCsv((dir / "motion.csv").string(), measured);
  writeMotionCsv((dir / "motion_truth.csv").string(), truth);
  writeTracksCsv((dir / "tracks.csv").string(), tracks);
  writePointsCsv((dir / "truth.csv").string(), truthRows(rig, scene, tracks, w_points));
  return 0;
}

} // namespace

Runner addSimulate(CLI::App &app)
{
  auto a = std::make_shared<SimulateArgs>();
  CLI::App *sub = app.add_subcommand(
      "simulate", "Make a synthetic sequence with known truth in --out-dir: motion.csv (dead-reckoned), "
                  "motion_truth.csv, tracks.csv and truth.csv (true points in the points format); with --pattern, "
                  "also the rendered images (frame_NNNN.png, named in motion.csv).");
  addSimulateSceneOptions(sub, *a);
  addSimulateBoardOptions(sub, *a);
  addVerbosityOptions(sub, a->quiet, "No progress on stderr");
  return [a]() { return runSimulate(*a); };
}

} // namespace yawdepth::cli
