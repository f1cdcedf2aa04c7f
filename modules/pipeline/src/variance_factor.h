#pragma once
// Private to the pipeline: the whole log's s0^2 from the tracks' residuals, the one formula
// checkResiduals() reports and rigDoubts() compares two models with; and the check with a gate
// wider than the model's, which only estimatePoints() asks for.
#include <vector>
#include <yawdepth/pipeline/residual_check.h>

namespace yawdepth {
namespace pipeline_detail {

/* s0 up to which a model fits the tracks: beyond it estimatePoints() warns that the sigmas are too
   small, and rigDoubts() does not call an alternative a fit. */
constexpr double kModelFitsS0 = 1.5;

/* s0^2 over the tracks with dof >= 1 and use[i] (every track when `use` is empty): the median of
   chi2 / chiSquareMedian(dof), robust to the few tracks that are not one point; `sigma` its
   standard error (chi2 / nu has the relative variance 2 / nu; the median of n such ratios has
   sqrt(pi / 2) times their spread over sqrt(n)). Returns the number of tracks it used; with fewer
   than `min_tracks` the factor is 1 and the sigma 0. */
int varianceFactor(const std::vector<TrackResidual> &tracks, const std::vector<bool> &use, int min_tracks,
                   double &factor, double &sigma);

/* checkResiduals() with the gate's threshold multiplied by gate_scale (>= 1): estimatePoints() uses
   1 / s0^2 when it made the model tighter, so that the gate is never tighter than the model given,
   which says what counts as a track that is not one point. */
ResidualCheckResult checkResidualsGated(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                        const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                        const ResidualCheckOptions &options, double gate_scale,
                                        std::vector<PointEstimate> &points);

} // namespace pipeline_detail
} // namespace yawdepth
