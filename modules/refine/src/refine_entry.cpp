// What refine owns in every build: its options' rules, and refineWindow() on the raw vectors (the
// inputs validated, then the method, with Ceres (refine_ceres.cpp) or without (refine_unavailable.cpp)).
#include <yawdepth/refine/refine.h>

#include <cmath>
#include <yawdepth/error.h>

namespace yawdepth {

void RefineOptions::validate() const
{
  noise.validateFor(Method::Refine);
  gates.validate();
  if (!(robust_threshold_px >= kMinWeightPx))
    throw Error("refine: the robust threshold must be at least 1e-6 px (the scale of its robust loss)");
  if (!(std::isfinite(outlier_threshold_px) && outlier_threshold_px > 0))
    throw Error("refine: the outlier threshold must be finite and positive");
  if (max_iterations < 0)
    throw Error("refine: max_iterations must be non-negative");
  if (threads < 1)
    throw Error("refine: at least one thread is needed");
}

RefineResult refineWindow(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &motion,
                          const std::vector<Track> &tracks, const std::vector<PointEstimate> &initial,
                          const RefineOptions &options)
{
  return refineWindow(camera, rig, validateInputs(motion, tracks), initial, options);
}

} // namespace yawdepth
