// refineWindow() in a build without Ceres: the method reports that it is unavailable.
#include <yawdepth/error.h>
#include <yawdepth/refine/refine.h>

namespace yawdepth {

bool refineAvailable() { return false; }

RefineResult refineWindow(const CameraModel &, const YawRig &, const TracksByFrame &input,
                          const std::vector<PointEstimate> &initial, const RefineOptions &options)
{
  const std::vector<MotionSample> &motion = input.motion();
  const std::vector<Track> &tracks = input.tracks();
  options.validate();
  if (!initial.empty() && initial.size() != tracks.size())
    throw Error("refine: one initial estimate per track is needed (or none)");
  RefineResult result;
  result.available = false;
  result.motion = motion;
  result.points.resize(tracks.size());
  result.outliers.resize(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    result.points[i].status = Status::Unavailable;
    if (!tracks[i].observations.empty())
      result.points[i].frame = tracks[i].observations.back().frame;
    result.outliers[i].assign(tracks[i].observations.size(), false);
  }
  return result;
}

} // namespace yawdepth
