#pragma once
// The estimation options shared by `estimate` and `measure`: method, noise model, gates, refine's
// thresholds; and running the chosen method on tracks.
#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/core/files.h>
#include <yawdepth/io/files.h>

namespace yawdepth::cli {

struct MethodArgs {
  std::string command; // the subcommand's name, for warnings (set by addMethodOptions)
  std::string method;
  NoiseModel noise;
  const CLI::Option *sigma_yaw_option = nullptr; // to tell whether --sigma-yaw was given
  GateOptions gates;
  double robust_px = 1.0;
  double outlier_px = 2.0;
  const CLI::Option *method_option = nullptr; // to tell whether --method was given
  std::string residual_check = "off";           // --residual-check on|off
  const CLI::Option *residual_option = nullptr; // to tell whether --residual-check was given
  double max_depth_sigma = 0;                   // --max-depth-sigma (0: no gate)
  const CLI::Option *max_depth_sigma_option = nullptr;
  int threads = 1; // refine: Ceres threads (--threads)
};

/*! \brief Register the motion's noise options (--sigma-odom, --sigma-heading, --sigma-rot, --motion-noise,
    --sigma-yaw) on `sub`. */
void addMotionNoiseOptions(CLI::App *sub, MethodArgs &args);
/*! \brief Register --method (with `default_method`), --sigma-px, the motion's noise, gate and refine options and
    --residual-check on `sub`. */
void addMethodOptions(CLI::App *sub, MethodArgs &args, const std::string &default_method);

/*!
  \brief The noise model for a motion log: a 6-DoF log without a `yaw` column has no pan joint,
  so its yaw is exact (sigma_yaw 0) unless --sigma-yaw is given.
*/
NoiseModel noiseForLog(const MethodArgs &args, bool six_dof, bool yaw_column);

/*! \brief The best method this build has: refine with Ceres, else fused. */
std::string bestMethod();

/*! \brief KLT tracking options of `track` and `measure --features klt`. */
struct KltArgs {
  KltOptions klt;
  bool no_gate = false;
  std::string video; // --video: the images from a video or image sequence (VideoFrames) instead of the log's
};
/*!
  \brief The image files a command reads, for checkOutputs(): the log's `image` column, or `video`: the
  file itself, or every file of its folder whose name a numbered sequence's pattern (`%d`, `%04d`, ...)
  matches.
*/
std::vector<NamedPath> imageInputs(const MotionLog &motion, const std::string &video);
/*! \brief Register --max-features, --min-distance, --track-sigma-px, --min-depth, --gate-sigmas, --max-depth, --guided,
    --no-gate, --video. */
void addKltOptions(CLI::App *sub, KltArgs &args);
/*!
  \brief KLT tracks (KltTracker) through the images of a motion log, each frame gated by the motion's
  increment and its uncertainty from `noise`; tracks seen in fewer than 2 frames are dropped. Prints a
  one-line summary on stderr unless `quiet`. Throws yawdepth::Error for a missing or unreadable image
  or one of another size than the camera's. `gray`, when given, receives the gray level at every
  feature, keyed (frame, id).
*/
std::vector<Track> kltTracks(const CameraModel &camera, const YawRig &rig, const MotionLog &motion,
                             const NoiseModel &noise, const KltArgs &args, bool quiet,
                             std::map<std::pair<long, long>, int> *gray = nullptr, cv::Mat *last_image = nullptr);

/*! \brief The observations flagged in `outliers`, as tracks (for --outliers). */
std::vector<Track> rejectedObservations(const std::vector<Track> &tracks, const std::vector<std::vector<bool>> &outliers);

/*! \brief What runMethodOnLog() gives: a points row per track (same order), the outlier flags per
    track and observation, and the motion as the method estimated it (refine's refined rows; the
    measured rows for the other methods): where each point's frame is in the world. */
struct MethodRun {
  std::vector<PointRow> rows;
  std::vector<std::vector<bool>> outliers;
  std::vector<MotionSample> motion_estimate;
};
/*! \brief The chosen method on every track of a motion log, with the noise model of that log
    (noiseForLog()), through yawdepth::estimatePoints() (unusable observations out and flagged, refine
    started from fused), with a progress line for long refine solves. */
MethodRun runMethodOnLog(const CameraModel &camera, const YawRig &rig, const MotionLog &motion,
                         const std::vector<Track> &tracks, const MethodArgs &args);
/*!
  \brief The points outputs, in this order: the PLY cloud when `ply` is given (through the motion as
  estimated, or the measured one when there is none; `gray` the gray level at each feature, keyed (frame, id)),
  then the points CSV to `out` (standard output when empty or "-").
*/
void writePointOutputs(const std::string &out, const std::string *ply, const YawRig &rig, const MotionLog &motion,
                       const MethodRun &run, const std::map<std::pair<long, long>, int> &gray = {});

} // namespace yawdepth::cli
