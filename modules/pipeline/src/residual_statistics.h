#pragma once
/*
  residual_statistics.h: the statistics behind the residual check (residual_check.h): the relative
  pose's noise along the log, and the chi-square median and quantiles of its gate and variance
  factor. Private to yawdepth::pipeline (not installed); tests reach it through the module's src/
  directory.
*/
#include <cstddef>
#include <vector>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*
  Per-axis 1-sigma of the pose between rows `a` and `b` (any order; equal: no motion noise) of a
  motion log under `noise`: the increments' noise composed for MotionNoise::Increment (translation
  per increment and per metre, rotation per increment, per radian and per metre, and the translation
  the accumulated rotation error moves over each later step), two poses' errors for
  MotionNoise::Absolute; two yaw readings added to the rotation. sigma_rot in rad, sigma_trans in m.
*/
void relativePoseSigma(const NoiseModel &noise, const std::vector<MotionSample> &motion, std::size_t a, std::size_t b,
                       double &sigma_rot, double &sigma_trans);

// Median of a chi-square variable with `dof` degrees of freedom (Wilson-Hilferty; dof >= 1).
double chiSquareMedian(int dof);
// The `p` quantile of a chi-square variable with `dof` degrees of freedom (Wilson-Hilferty, p in (0.5, 1)).
double chiSquareQuantile(int dof, double p);

} // namespace yawdepth
