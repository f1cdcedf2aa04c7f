// `yawdepth track`: natural-feature tracks (KLT) from the images of a motion log, gated by the
// known motion; also what `measure --features klt` runs.
#include "commands.h"
#include "method_options.h"
#include "progress.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <unistd.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/video_frames.h>
#include <yawdepth/io/files.h>

namespace yawdepth::cli {

void addKltOptions(CLI::App *sub, KltArgs &args)
{
  sub->add_option("--max-features", args.klt.max_features, "KLT: most features tracked at once")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  sub->add_option("--min-distance", args.klt.min_distance, "KLT: minimum spacing of features (px)")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  sub->add_option("--track-sigma-px", args.klt.sigma_px, "KLT: tracker noise per point for the epipolar gate (px)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--min-depth", args.klt.min_depth, "KLT: the nearest a tracked point can be (m), for the epipolar gate")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--gate-sigmas", args.klt.gate_sigmas, "KLT: half-width of the epipolar band (sigmas)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--max-depth", args.klt.max_depth,
                  "KLT: the farthest a tracked point can be (m, above --min-depth; inf: no limit), for the guided search")
      ->check(CLI::Validator(
          [](std::string &s) {
            char *end = nullptr;
            const double v = std::strtod(s.c_str(), &end);
            return end != s.c_str() && *end == '\0' && v > 0 ? std::string()
                                                             : "must be a positive number or inf, not " + s;
          },
          "POSITIVE|inf"))
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--guided", [&args](const std::string &s) { args.klt.guided = kltGuidedFromString(s); },
         "KLT: search each feature's epipolar segment (NCC, then LK; ambiguous matches refused) where plain LK lost "
         "it or moved it farther than LK follows, and every feature of a frame where that is most (auto), for every "
         "feature (on), or never (off) [auto]")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  sub->add_option("--min-ncc", args.klt.min_ncc,
                  "KLT: cut a feature whose patch's zero-mean NCC with its patch at detection falls below this, and "
                  "drop its whole track (a corner on an occlusion edge or a T-junction); 0: no appearance check")
      ->check(CLI::Range(0.0, 0.999))
      ->capture_default_str();
  sub->add_option("--jump-sigmas", args.klt.jump_sigmas,
                  "KLT: split a feature (new id) whose step along its epipolar line is this many sigmas from its own "
                  "earlier steps; 0: no jump check")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  sub->add_flag("--no-gate", args.no_gate, "KLT: do not gate the tracks with the motion (no epipolar band)");
  sub->add_option("--video", args.video,
                  "Take the images from a video file (ViSP's vpVideoReader) or a numbered image sequence (one %d or %0Nd, "
                  "N up to 9, e.g. frames/frame_%04d.png; no gaps), "
                  "one frame per motion-log row in order, instead of the log's image column");
}

std::vector<NamedPath> imageInputs(const MotionLog &motion, const std::string &video)
{
  std::vector<NamedPath> out;
  if (video.empty()) {
    for (const std::string &image : motion.images)
      if (!image.empty())
        out.push_back({"--motion's image", image});
    return out;
  }
  if (!SequencePattern::isPattern(video)) {
    out.push_back({"--video", video});
    return out;
  }
  std::vector<std::string> files;
  try {
    files = SequencePattern(video).filesPresent();
  } catch (const Error &e) {
    throw Error(std::string("--video ") + e.what());
  }
  for (std::string &f : files)
    out.push_back({"--video", std::move(f)});
  return out;
}

/* trackSequence() on the log's images or --video's frames, with a progress line (ended before the
   summary is printed). */
static SequenceTracks trackImages(const CameraModel &camera, const YawRig &rig, const MotionLog &motion,
                                  const NoiseModel &noise, const KltArgs &args)
{
  const std::size_t n = motion.samples.size();
  ProgressLine progress;
  const auto report = [&](std::size_t done, std::size_t total) { progress.count("track", done, total, "frames"); };
  if (args.video.empty())
    return trackSequence(camera, rig, motion.samples, motion.images, noise, args.klt, !args.no_gate, report);
  std::unique_ptr<VideoFrames> opened;
  try {
    opened = std::make_unique<VideoFrames>(args.video);
  } catch (const Error &e) {
    throw Error(std::string("--video ") + e.what());
  }
  VideoFrames &video = *opened;
  const FrameSource frames = [&](std::size_t) {
    try {
      return video.next();
    } catch (const Error &e) {
      throw Error(std::string(e.what()) + "; the motion log has " + std::to_string(n) + " rows");
    }
  };
  return trackSequence(camera, rig, motion.samples, frames, noise, args.klt, !args.no_gate, report);
}

std::vector<Track> kltTracks(const CameraModel &camera, const YawRig &rig, const MotionLog &motion,
                             const NoiseModel &noise, const KltArgs &args, bool quiet,
                             std::map<std::pair<long, long>, int> *gray, cv::Mat *last_image)
{
  if (motion.images.empty() && args.video.empty())
    throw Error("the motion log has no 'image' column: KLT tracking needs the image of each frame (or --video)");
  if (camera.width() == 0 || camera.height() == 0)
    throw Error("KLT tracking needs the camera's image size (image_width, image_height in the camera file)");
  const std::size_t n = motion.samples.size();
  SequenceTracks seq = trackImages(camera, rig, motion, noise, args);
  const KltStats &t = seq.totals;
  if (!quiet)
    std::cerr << "track: " << n << " frames, " << t.detected << " features detected, " << seq.tracks.size()
              << " tracked over 2 frames or more; cut: " << t.lost_epipolar << " outside the epipolar band, "
              << t.lost_fb << " forward-backward, " << t.lost_flow << " lost, " << t.lost_border
              << " left the image" << (t.lost_ambiguous ? ", " + std::to_string(t.lost_ambiguous) + " ambiguous" : "")
              << ", " << t.lost_appearance << " changed appearance (whole track dropped); split: " << t.split_jump
              << " jumped" << (t.guided ? "; " + std::to_string(t.guided) + " steps by the guided search" : "") << "\n";
  if (gray)
    *gray = std::move(seq.gray);
  if (last_image)
    *last_image = seq.last_image;
  return std::move(seq.tracks);
}

namespace {

struct TrackArgs {
  std::string camera, camera_name, rig, out;
  MotionOptions motion;
  MethodArgs method;
  KltArgs klt;
  InputOptions input;
  bool quiet = false;
};

} // namespace

Runner addTrack(CLI::App &app)
{
  auto a = std::make_shared<TrackArgs>();
  CLI::App *sub = app.add_subcommand(
      "track", "Track natural corners (KLT) through the images of a motion log, gated by the known motion.");
  addCameraOptions(sub, a->camera, a->camera_name, true, "with the image size");
  // Optional (scripts ran without it): the tracks are pixel positions, which the rig does not change.
  addRigOption(sub, a->rig, false,
               "the tracks written are pixel positions; the rig only places the epipolar gate (and gives a "
               "timestamped log's yaw and time_offset); without it the camera is at the vision frame's origin");
  addMotionOptions(sub, a->motion,
                   "Motion log with an image column (paths relative to the CSV's folder), any with --video, or a "
                   "timestamped one with --images");
  sub->add_option("--out", a->out, "Output tracks CSV (frame,id,u,v)")->required();
  addMotionNoiseOptions(sub, a->method);
  addKltOptions(sub, a->klt);
  addVerbosityOptions(sub, a->quiet, "No progress or summary on stderr");
  addInputOptions(sub, a->input);
  return [a]() {
    a->method.noise.validate();
    RigFile rig_file;
    if (!a->rig.empty())
      rig_file = readCommandRig("track", a->rig);
    const YawRig rig = rigOf(rig_file);
    MotionLog motion = loadCommandMotion("track", a->motion, &rig_file, a->input.limits(), a->quiet).log;
    checkMotionSteps(motion, a->motion.name());
    applyRigFile(rig_file, motion.samples);
    {
      std::vector<NamedPath> inputs = a->motion.inputs();
      inputs.push_back({"--camera", a->camera});
      if (!a->rig.empty())
        inputs.push_back({"--rig", a->rig});
      for (NamedPath &image : imageInputs(motion, a->klt.video))
        inputs.push_back(std::move(image));
      checkOutputs(inputs, {{"--out", a->out}});
    }
    const CameraModel camera = loadCameraFile(a->camera, a->camera_name);
    const bool six_dof = !motion.samples.empty() && motion.samples.front().six_dof;
    const NoiseModel noise = noiseForLog(a->method, six_dof, motion.yaw_column);
    const std::vector<Track> tracks = kltTracks(camera, rig, motion, noise, a->klt, a->quiet);
    stage("track", std::to_string(tracks.size()) + " tracks");
    writeTracksCsv(a->out, tracks);
    return 0;
  };
}

} // namespace yawdepth::cli
