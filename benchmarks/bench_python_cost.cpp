// The C++ side of benchmarks/bench_python.py: the same calls the Python module makes, on the same
// files, timed here without Python. Prints one number: the median over REPEATS of the microseconds
// per call.
//   bench_python_cost estimate CAMERA RIG MOTION TRACKS METHOD REPEATS
//       one estimatePoints() of the log (what yawdepth.estimatePoints runs)
//   bench_python_cost update CAMERA RIG MOTION TRACKS REPEATS
//       a new DepthProvider fed every row of the log with that frame's features (what
//       DepthProvider.updateOdometry runs), the time per update
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/io/files.h>
#include <yawdepth/pipeline/pipeline.h>
#include <yawdepth/servo/depth_provider.h>

namespace {

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double seconds()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

} // namespace

int main(int argc, char **argv)
{
  using namespace yawdepth;
  const std::string mode = argc > 1 ? argv[1] : "";
  if (!((mode == "estimate" && argc == 8) || (mode == "update" && argc == 7))) {
    std::fprintf(stderr, "usage: bench_python_cost estimate CAMERA RIG MOTION TRACKS METHOD REPEATS\n"
                         "       bench_python_cost update CAMERA RIG MOTION TRACKS REPEATS\n");
    return 2;
  }
  try {
    const CameraModel camera = loadCameraFile(argv[2]);
    const RigFile rig_file = readRigFile(argv[3]);
    const YawRig rig = rigOf(rig_file);
    MotionLog motion = readMotionCsv(argv[4], rig_file.yaw);
    applyRigFile(rig_file, motion.samples);
    const std::vector<Track> tracks = readTracksCsv(argv[5]);
    const int repeats = std::atoi(argv[argc - 1]);
    std::vector<double> times;
    if (mode == "estimate") {
      PipelineOptions o;
      o.method = methodFromString(argv[6]);
      for (int r = 0; r < repeats; ++r) {
        const double t0 = seconds();
        const PipelineResult result = estimatePoints(camera, rig, motion.samples, tracks, o);
        times.push_back((seconds() - t0) * 1e6);
        if (result.points.size() != tracks.size())
          return 1;
      }
    } else {
      // each row's features, prepared before the clock starts (as the Python side does)
      std::vector<std::vector<std::pair<long, vpImagePoint>>> frames(motion.samples.size());
      for (const Track &t : tracks)
        for (const Observation &o : t.observations)
          frames[static_cast<std::size_t>(motion.indexOf(o.frame))].emplace_back(t.id, vpImagePoint(o.v, o.u));
      for (int r = 0; r < repeats; ++r) {
        DepthProvider provider(camera, rig);
        const double t0 = seconds();
        for (std::size_t k = 0; k < frames.size(); ++k)
          provider.update(motion.samples[k], frames[k]);
        times.push_back((seconds() - t0) * 1e6 / static_cast<double>(frames.size()));
      }
    }
    std::printf("%.3f\n", median(times));
  } catch (const Error &e) {
    std::fprintf(stderr, "bench_python_cost: %s\n", e.what());
    return 1;
  }
  return 0;
}
