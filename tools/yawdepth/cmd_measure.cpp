// `yawdepth measure`: detect a pattern in the motion log's images, build tracks, estimate points,
// and optionally write the paper's Fig. 3 report.
#include <algorithm>
#include <cmath>
#include <map>
#include "commands.h"
#include "method_options.h"
#include "progress.h"

#include <filesystem>
#include <iostream>
#include <stdlib.h> // mkdtemp
#include <unistd.h>
#include <memory>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/io/files.h>
#include <yawdepth/report/board_report.h>
#include <yawdepth/report/cloud_report.h>

namespace yawdepth::cli {

namespace {

struct MeasureArgs {
  std::string camera, camera_name, rig, pattern, features, out, report, tracks_out, outliers, ply;
  MotionOptions motion;
  KltArgs klt;
  MethodArgs method;
  InputOptions input;
  bool quiet = false;
  std::string debug_dir;
  std::string bag;   // --bag: imported into a temporary folder first
  BagOptions bag_options;
};

/* Before anything is written: no output may replace an input (the images too) or another output. */
void checkMeasureOutputs(const MeasureArgs &a, const CLI::App &sub, const MotionLog &motion)
{
  std::vector<NamedPath> inputs = a.motion.inputs();
  inputs.push_back({"--camera", a.camera});
  inputs.push_back({"--rig", a.rig});
  for (NamedPath &image : imageInputs(motion, a.klt.video))
    inputs.push_back(std::move(image));
  std::vector<NamedPath> outputs; // --out, unless it is standard output (none, or "-")
  if (!a.out.empty() && a.out != "-")
    outputs.push_back({"--out", a.out});
  for (const auto &[option, value] : {std::pair<const char *, const std::string *>{"--tracks-out", &a.tracks_out},
                                      {"--outliers", &a.outliers}, {"--ply", &a.ply}})
    if (sub.count(option) > 0)
      outputs.push_back({option, *value});
  if (sub.count("--report") > 0) {
    if (a.report.empty())
      throw Error("--report: empty folder name");
    for (const std::string &f : a.features.empty() ? boardReportFiles(a.report) : cloudReportFiles(a.report))
      outputs.push_back({"--report", f});
  }
  for (const std::string &f : debugFiles(a.debug_dir, motion.images))
    outputs.push_back({"--debug-dir", f});
  checkOutputs(inputs, outputs);
}

/* The pattern's tracks through the images of `motion`: per-frame problems on stderr (unless --quiet)
   once the pattern was found somewhere, a progress line on a terminal, --debug-dir's pictures.
   `found` receives the number of frames the pattern was found in, `gray` the gray level at each feature. */
std::vector<Track> patternTracks(const MeasureArgs &a, const PatternSpec &pattern, const CameraModel &camera,
                                 const MotionLog &motion, std::size_t &found, std::map<std::pair<long, long>, int> &gray)
{
  const std::vector<std::string> debug_files = debugFiles(a.debug_dir, motion.images);
  const std::size_t n = motion.samples.size();
  PatternDetector detector(pattern);
  detector.setCamera(camera);
  std::vector<FrameDetection> detections;
  std::vector<std::string> failures; // per-frame reasons, printed once we know the run succeeds
  ProgressLine progress;
  for (std::size_t i = 0; i < n; ++i) {
    const long frame = motion.samples[i].frame;
    if (motion.images[i].empty()) {
      failures.push_back("measure: frame " + std::to_string(frame) + ": no image");
      continue;
    }
    const cv::Mat image = readGrayImage(motion.images[i], camera);
    FrameDetection d = detector.detect(image, frame);
    for (const FeatureObservation &f : d.features) // the gray level at each feature, for --ply
      gray[{frame, f.id}] = grayLevelAt(image, f.u, f.v);
    if (d.found)
      ++found;
    else
      failures.push_back("measure: frame " + std::to_string(frame) + ": " + d.reason);
    for (const std::string &w : d.warnings)
      failures.push_back("measure: frame " + std::to_string(frame) + ": " + w);
    if (!debug_files.empty())
      writeDebugImage(debug_files[i], image, d);
    detections.push_back(std::move(d));
    progress.count("measure", i + 1, n, "images, pattern found in " + std::to_string(found));
  }
  progress.finish();
  if (found == 0)
    throw Error("the pattern " + pattern.toString() + " was not found in any of the " + std::to_string(n) +
                " images" + (failures.empty() ? std::string() : " (" + failures.front().substr(9) + ")"));
  if (!a.quiet)
    for (const std::string &f : failures)
      std::cerr << f << "\n";
  return PatternDetector::toTracks(detections);
}

/* No silent loss: every board feature not measured is named on stderr, with why. */
void reportUnmeasured(const PatternSpec &pattern, const std::vector<Track> &tracks, const std::vector<PointRow> &rows)
{
  std::map<long, const PointEstimate *> by_id;
  std::map<long, std::size_t> seen;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    by_id[tracks[i].id] = &rows[i].estimate;
    seen[tracks[i].id] = tracks[i].observations.size();
  }
  BoardLayout layout;
  layout.pattern = pattern;
  std::size_t expected = 0, ok = 0;
  std::vector<std::string> lost;
  if (pattern.kind == PatternSpec::Kind::Chessboard) {
    for (const auto &f : layout.features()) {
      ++expected;
      auto it = by_id.find(f.first);
      if (it == by_id.end())
        lost.push_back("id " + std::to_string(f.first) + ": never detected");
      else if (!it->second->ok())
        lost.push_back("id " + std::to_string(f.first) + ": " + toString(it->second->status) + " (seen in " +
                       std::to_string(seen[f.first]) + " frames)");
      else
        ++ok;
    }
  } else {
    for (const auto &[id, e] : by_id) {
      ++expected;
      if (e->ok())
        ++ok;
      else
        lost.push_back("id " + std::to_string(id) + ": " + toString(e->status) + " (seen in " +
                       std::to_string(seen[id]) + " frames)");
    }
  }
  if (lost.empty())
    return;
  std::cerr << "measure: " << ok << " of " << expected
            << (pattern.kind == PatternSpec::Kind::Chessboard ? " board features" : " detected features")
            << " measured; not measured:";
  for (std::size_t k = 0; k < lost.size() && k < 20; ++k)
    std::cerr << (k ? ", " : " ") << lost[k];
  if (lost.size() > 20)
    std::cerr << ", and " << lost.size() - 20 << " more";
  std::cerr << "\n";
}

/* --report: the board's metrics in the world of the motion log, through the motion as the method
   estimated it; their summary on stderr unless --quiet. */
void writeMeasureReport(const MeasureArgs &a, const PatternSpec &pattern, const YawRig &rig, const MethodRun &run,
                        std::size_t found, std::size_t frames)
{
  std::vector<std::pair<long, PointEstimate>> pairs;
  for (const PointRow &row : run.rows)
    pairs.emplace_back(row.id, row.estimate);
  const BoardMetrics m = boardMetrics(pattern, rig, run.motion_estimate, pairs);
  const std::string title = "yawdepth measure: " + pattern.toString() + ", method " + a.method.method + ", " +
                            std::to_string(found) + " of " + std::to_string(frames) + " frames";
  writeBoardReport(a.report, m, title);
  if (!a.quiet)
    std::cerr << formatBoardMetrics(m) << "report: " << a.report << "/report.txt, " << a.report << "/figure.png\n";
}

/* --report with --features klt: the cloud over the last image and from above (cloud_report.h), and
   the count of each status. */
void writeKltReport(const MeasureArgs &a, const CameraModel &camera, const YawRig &rig, const MotionLog &motion,
                    const MethodRun &run, const std::string &method, const cv::Mat &last_image)
{
  CloudReportInput in;
  in.camera = camera;
  const std::vector<MotionSample> &poses = run.motion_estimate.empty() ? motion.samples : run.motion_estimate;
  in.image = last_image;
  in.cMw = wMc(rig, poses.back()).inverse();
  std::map<std::string, int> by_status;
  for (const PointRow &row : run.rows)
    ++by_status[toString(row.estimate.status)];
  for (const PlyPoint &p : plyPoints(rig, poses, run.rows))
    in.points.push_back({p.id, p.w_P, p.sigma_z});
  in.title = "yawdepth measure --features klt, method " + method + ": " + std::to_string(in.points.size()) +
             " ok points of " + std::to_string(run.rows.size()) + " tracks, frame " +
             std::to_string(motion.samples.back().frame);
  std::string summary = "tracks by status:\n";
  for (const auto &[word, count] : by_status)
    summary += "  " + word + ": " + std::to_string(count) + "\n";
  std::vector<double> rel;
  for (const PointRow &row : run.rows)
    if (row.estimate.ok())
      rel.push_back(row.estimate.sigmaZ() / row.estimate.c_P.z());
  if (!rel.empty()) {
    std::sort(rel.begin(), rel.end());
    char line[160];
    std::snprintf(line, sizeof line, "ok points' relative depth sigma: median %.3g %%, 90th percentile %.3g %%\n",
                  100 * rel[rel.size() / 2], 100 * rel[std::min(rel.size() - 1, rel.size() * 9 / 10)]);
    summary += line;
  }
  summary += "pictures: overlay.png (the points over the last image, coloured by depth), top_view.png (seen from "
             "above in the last camera, 2-sigma depth intervals)\n";
  in.summary = summary;
  writeCloudReport(a.report, in);
  if (!a.quiet)
    std::cerr << summary << "report: " << a.report << "/report.txt, " << a.report << "/overlay.png, " << a.report
              << "/top_view.png\n";
}

int runMeasure(const MeasureArgs &a, const CLI::App &sub)
{
  a.method.noise.validate();
  a.method.gates.validate();
  const bool klt = !a.features.empty();
  if (klt == (sub.count("--pattern") > 0))
    throw Error(klt ? "give --pattern or --features klt, not both" : "give --pattern or --features klt");
  if (klt && sub.count("--debug-dir") > 0)
    throw Error("--debug-dir draws pattern detections: it needs --pattern");
  const PatternSpec pattern = klt ? PatternSpec() : PatternSpec::parse(a.pattern);
  const CameraModel camera = loadCameraFile(a.camera, a.camera_name);
  const RigFile rig_file = readCommandRig("measure", a.rig);
  const YawRig rig = rigOf(rig_file);
  MotionLog motion = loadCommandMotion("measure", a.motion, &rig_file, a.input.limits(), a.quiet).log;
  checkMotionSteps(motion, a.motion.name());
  applyRigFile(rig_file, motion.samples);
  if (!klt && sub.count("--video") > 0)
    throw Error("--video gives natural features' images: it needs --features klt");
  if (motion.images.empty() && a.klt.video.empty())
    throw Error(a.motion.name() + ": no 'image' column: measure needs the image of each frame" +
                std::string(klt ? " (or --video)" : ""));
  checkMeasureOutputs(a, sub, motion);

  const std::size_t n = motion.samples.size();
  std::size_t found = 0;
  std::map<std::pair<long, long>, int> gray; // the gray level at each feature, for --ply
  std::vector<Track> tracks;
  cv::Mat last_image; // --features klt: the last image tracked, for --report
  if (klt) {
    const bool six_dof = n > 0 && motion.samples.front().six_dof;
    tracks = kltTracks(camera, rig, motion, noiseForLog(a.method, six_dof, motion.yaw_column), a.klt, a.quiet, &gray,
                       &last_image);
    found = n;
  } else {
    tracks = patternTracks(a, pattern, camera, motion, found, gray);
  }
  stage("measure", std::to_string(tracks.size()) + " tracks from " + std::to_string(n) + " images");
  if (sub.count("--tracks-out") > 0)
    writeTracksCsv(a.tracks_out, tracks);

  MethodArgs method = a.method;
  const PipelineOptions natural = naturalFeatureOptions(); // what the user did not choose, for natural features
  if (klt && method.method_option != nullptr && method.method_option->count() == 0)
    method.method = toString(natural.method);
  if (klt && method.residual_option != nullptr && method.residual_option->count() == 0)
    method.residual_check = natural.residual_check.enabled ? "on" : "off";
  if (klt && method.max_depth_sigma_option != nullptr && method.max_depth_sigma_option->count() == 0)
    method.max_depth_sigma = natural.max_depth_sigma;
  const MethodRun run = runMethodOnLog(camera, rig, motion, tracks, method);
  if (sub.count("--outliers") > 0)
    writeTracksCsv(a.outliers, rejectedObservations(tracks, run.outliers));
  if (!a.quiet && !klt)
    reportUnmeasured(pattern, tracks, run.rows);
  if (!a.report.empty() && klt)
    writeKltReport(a, camera, rig, motion, run, method.method, last_image);
  else if (!a.report.empty())
    writeMeasureReport(a, pattern, rig, run, found, n);
  writePointOutputs(a.out, sub.count("--ply") > 0 ? &a.ply : nullptr, rig, motion, run, gray);
  return 0;
}

/* A temporary folder, removed with its contents. */
struct ScratchDir {
  std::string path;
  ScratchDir()
  {
    std::string templ = (std::filesystem::temp_directory_path() / "yawdepth_bag_XXXXXX").string();
    if (!::mkdtemp(templ.data()))
      throw Error(std::filesystem::temp_directory_path().string() + ": cannot create a temporary folder for --bag");
    path = templ;
  }
  ~ScratchDir()
  {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  ScratchDir(const ScratchDir &) = delete;
  ScratchDir &operator=(const ScratchDir &) = delete;
};

/* measure --bag: the bag imported into a temporary folder (removed afterwards), then measured from
   the files written there; --camera and --rig, when given, replace the imported ones. */
int runMeasureBag(const MeasureArgs &a, const CLI::App &sub)
{
  ScratchDir scratch;
  const std::string out = (std::filesystem::path(scratch.path) / "import").string();
  const BagImportOptions o = a.bag_options.options(a.bag, out, a.motion.time_offset, a.motion.max_pose_gap);
  const BagImportResult r = importCommandBag("measure", o, a.quiet ? nullptr : &std::cerr);
  MeasureArgs m = a;
  m.bag.clear();
  m.motion.motion = {r.motion_path};
  m.motion.format = "yawdepth";
  m.motion.images.clear();
  m.motion.time_offset_option = nullptr; // applied by the import
  if (m.camera.empty())
    m.camera = r.camera_path;
  if (m.rig.empty())
    m.rig = r.rig_path;
  return runMeasure(m, sub);
}

} // namespace

Runner addMeasure(CLI::App &app)
{
  auto a = std::make_shared<MeasureArgs>();
  CLI::App *sub = app.add_subcommand(
      "measure", "Detect a chessboard or AprilTags (or track natural corners) in the images of a motion log and "
                 "measure their 3D points.");
  addCameraOptions(sub, a->camera, a->camera_name, false,
                   "required without --bag; with --bag the default is the bag's camera_info");
  addRigOption(sub, a->rig, false, "required without --bag (the rig changes every point); with --bag the default is "
                                   "the mount from /tf_static");
  addMotionOptions(sub, a->motion,
                   "Motion log with an image column (paths relative to the CSV's folder), a timestamped one with "
                   "--images, or with --features klt --video any motion log");
  sub->add_option("--pattern", a->pattern, "chessboard:COLSxROWS:SQUARE or apriltag:FAMILY:SIZE (metres)");
  sub->add_option("--features", a->features,
                  "klt: instead of a pattern, track natural corners (as `yawdepth track`) and measure them")
      ->check(CLI::IsMember({"klt"}));
  addKltOptions(sub, a->klt);
  addMethodOptions(sub, a->method, bestMethod());
  sub->get_option("--method")->description(sub->get_option("--method")->get_description() +
                                           ". With --features klt the default is window");
  sub->add_option("--out", a->out, "Output points CSV (default: standard output)");
  sub->add_option("--report", a->report,
                  "Folder for the paper's Fig. 3 report: report.txt, blocks.csv, plane.csv, figure.png; with --features "
                  "klt: report.txt, overlay.png (the points over the last image, coloured by depth), top_view.png");
  sub->add_option("--ply", a->ply,
                  "Also write the ok points as a PLY point cloud (world frame, gray level at the feature, sigma_z, id)");
  sub->add_option("--tracks-out", a->tracks_out, "Also write the detected features as a tracks CSV (frame,id,u,v)");
  sub->add_option("--outliers", a->outliers, "fused/refine: also write the observations rejected as outliers");
  addVerbosityOptions(sub, a->quiet, "No progress, summaries or per-frame detection messages on stderr");
  sub->add_option("--debug-dir", a->debug_dir,
                  "Write each image with its detected features and ids drawn (DIR/NNNN_NAME.png, NNNN its row in the log)");
  addInputOptions(sub, a->input);
  CLI::Option *bag = sub->add_option(
      "--bag", a->bag,
      "A ROS 1 or ROS 2 bag instead of --motion: imported as import-bag does (its options below, --time-offset and "
      "--max-pose-gap) into a temporary folder first");
  addBagOptions(sub, a->bag_options);
  bag->excludes(sub->get_option("--motion"))->excludes(sub->get_option("--images"));
  sub->get_option("--motion")->required(false);
  sub->parse_complete_callback([sub, a]() {
    if (!a->bag.empty()) {
      if (sub->count("--image-topic") == 0)
        throw CLI::RequiredError("--image-topic (with --bag)");
      return;
    }
    for (const char *o : {"--camera", "--rig", "--motion"})
      if (sub->count(o) == 0)
        throw CLI::RequiredError(o);
    for (const char *o : {"--image-topic", "--camera-info-topic", "--odom-topic", "--pose-topic", "--tf",
                          "--camera-frame", "--joint-topic", "--joint", "--joint-axis", "--joint-origin", "--start",
                          "--duration", "--every"})
      if (sub->count(o) > 0)
        throw CLI::ValidationError(o, "reads a bag: give --bag");
  });
  return [a, sub]() { return a->bag.empty() ? runMeasure(*a, *sub) : runMeasureBag(*a, *sub); };
}

} // namespace yawdepth::cli
