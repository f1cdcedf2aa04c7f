// refineWindow() on the raw vectors: the inputs validated (validateInputs()), then the method, with
// Ceres (refine_ceres.cpp) or without (refine_unavailable.cpp).
#include <yawdepth/refine/refine.h>

namespace yawdepth {

RefineResult refineWindow(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                          const std::vector<Track> &tracks, const std::vector<PointEstimate> &initial,
                          const RefineOptions &options)
{
  return refineWindow(camera, rig, validateInputs(motion, tracks), initial, options);
}

} // namespace yawdepth
