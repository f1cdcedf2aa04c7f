#pragma once
// Private to the pipeline: the likely mistakes in a rig file or a motion log's yaw that the tracks
// can tell apart from what was given (estimatePoints() warns about them).
#include <string>
#include <vector>
#include <yawdepth/geometry/track_inputs.h>
#include <yawdepth/pipeline/pipeline.h>

namespace yawdepth {
namespace pipeline_detail {

/* A mistake the tracks fit clearly better than the model given. */
struct RigDoubt {
  std::string what;           // "the lever arm's sign (...)", "the yaw's sign (...)"
  double s0_given = 1;        // the whole log's s0 with the rig and log as given (inf: too few tracks fit)
  double s0_alternative = 1;  // with the mistake undone
};

/*
  Each likely mistake undone in turn (the camera's lever arm negated, the yaw readings negated), the
  tracks re-estimated by `fused` and the whole log's s0 compared with the one of the model given
  (both with fused and the same residual check, so that the check's stand-in for the motion's
  variance, which overstates it, cancels in the comparison). A mistake is reported when undoing it
  lowers s0^2, over the tracks both models explain (the gates drop what a model cannot explain, so a
  wrong model can fit the rest better), by more than kBetter and by more than kEvidence standard
  errors of the two; when the alternative explains fewer than kMinTrackShare of the tracks the model
  given explains, by kDecisive at least (losing tracks to the gates is evidence against it) (or when,
  as given, too few tracks fit to measure it). Only the
  alternatives the motion can tell apart are tried: a lever arm of at least kMinLever with the yaw or
  the body turning by at least kMinYawSpan, the yaw's sign when it turns, or
  stays away from 0, by at least kMinYawSpan.
*/
std::vector<RigDoubt> rigDoubts(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                const PipelineOptions &options);

} // namespace pipeline_detail
} // namespace yawdepth
