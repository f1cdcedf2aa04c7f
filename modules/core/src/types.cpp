#include <cmath>
#include <cstdio>
#include <string>
#include <yawdepth/error.h>
#include <yawdepth/core/types.h>

namespace yawdepth {

const char *toString(Status s)
{
  switch (s) {
  case Status::Ok:
    return "ok";
  case Status::Degenerate:
    return "degenerate";
  case Status::Behind:
    return "behind";
  case Status::NoMotion:
    return "no_motion";
  case Status::TooFewFrames:
    return "too_few_frames";
  case Status::UndistortFailed:
    return "undistort_failed";
  case Status::Unavailable:
    return "unavailable";
  case Status::Inconsistent:
    return "inconsistent";
  }
  return "unknown";
}

const char *toString(Method m)
{
  switch (m) {
  case Method::Paper:
    return "paper";
  case Method::Exact:
    return "exact";
  case Method::Fused:
    return "fused";
  case Method::Window:
    return "window";
  case Method::Refine:
    return "refine";
  }
  return "unknown";
}

Method methodFromString(const std::string &word)
{
  for (Method m : {Method::Paper, Method::Exact, Method::Fused, Method::Window, Method::Refine})
    if (word == toString(m))
      return m;
  throw Error("unknown method '" + word + "' (expected paper, exact, fused, window or refine)");
}

Method toMethod(TrackMethod m) { return static_cast<Method>(static_cast<int>(m)); }

Method toMethod(StreamMethod m) { return static_cast<Method>(static_cast<int>(m)); }

const char *toString(TrackMethod m) { return toString(toMethod(m)); }

const char *toString(StreamMethod m) { return toString(toMethod(m)); }

TrackMethod trackMethodFromString(const std::string &word)
{
  for (TrackMethod m : {TrackMethod::Paper, TrackMethod::Exact, TrackMethod::Fused})
    if (word == toString(m))
      return m;
  (void)methodFromString(word); // an unknown word: that error
  throw Error("method " + word + " does not estimate each track on its own (paper, exact or fused do)");
}

StreamMethod streamMethodFromString(const std::string &word)
{
  for (StreamMethod m : {StreamMethod::Fused, StreamMethod::Window})
    if (word == toString(m))
      return m;
  (void)methodFromString(word); // an unknown word: that error
  throw Error("method " + word + " does not run frame by frame (window or fused do)");
}

bool modelsTrackerCorrelation(Method m) { return m == Method::Window || m == Method::Refine; }

Status statusFromString(const std::string &word)
{
  for (Status s : {Status::Ok, Status::Degenerate, Status::Behind, Status::NoMotion, Status::TooFewFrames,
                   Status::UndistortFailed, Status::Unavailable, Status::Inconsistent})
    if (word == toString(s))
      return s;
  throw Error("unknown status word '" + word + "'");
}

static vpColVector toVispVec(const Eigen::Vector3d &e)
{
  vpColVector v(3);
  for (unsigned i = 0; i < 3; ++i)
    v[i] = e(i);
  return v;
}

vpColVector PointEstimate::cP() const { return toVispVec(c_P); }
vpColVector PointEstimate::vP() const { return toVispVec(v_P); }
vpMatrix PointEstimate::covariance() const
{
  vpMatrix M(3, 3);
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j)
      M[i][j] = c_cov(i, j);
  return M;
}

static void checkSigma(double v, const char *name)
{
  if (!std::isfinite(v) || v < 0)
    throw Error(std::string(name) + " must be a finite non-negative number");
}

void NoiseModel::validate() const
{
  checkSigma(sigma_px, "sigma-px");
  checkSigma(sigma_odom, "sigma-odom");
  checkSigma(sigma_heading, "sigma-heading");
  checkSigma(sigma_rot, "sigma-rot");
  checkSigma(sigma_yaw, "sigma-yaw");
  checkSigma(odom_per_metre, "odom-per-metre");
  checkSigma(rot_per_radian, "rot-per-radian");
  checkSigma(rot_per_metre, "rot-per-metre");
  if (!(pixel_correlation >= 0 && pixel_correlation <= kMaxPixelCorrelation))
    throw Error("pixel-correlation must be in [0, 0.99]");
  if (motion_noise != MotionNoise::Increment && motion_noise != MotionNoise::Absolute)
    throw Error("invalid motion noise model");
  if (motion_noise == MotionNoise::Absolute && (odom_per_metre > 0 || rot_per_radian > 0 || rot_per_metre > 0))
    throw Error("absolute (per pose) motion noise has no per-metre or per-radian terms: they describe increments");
}

void NoiseModel::validateFor(Method m) const
{
  validate();
  const std::string name = toString(m);
  const bool weighted = m == Method::Fused || m == Method::Window || m == Method::Refine;
  if (weighted && !(sigma_px >= kMinWeightPx))
    throw Error("pixel noise " + std::to_string(sigma_px) + " px: method " + name +
                " needs at least 1e-6 px (it weighs every observation by it)");
  if (pixel_correlation > 0 && !modelsTrackerCorrelation(m)) {
    char phi[32];
    std::snprintf(phi, sizeof phi, "%.3g", pixel_correlation);
    throw Error("method " + name + " does not model correlated tracker errors (pixel-correlation " + phi +
                "): use window or refine, or 0");
  }
}

double pixelCorrelationOver(double phi, long gap)
{
  return phi > 0 && gap > 0 ? std::pow(phi, static_cast<double>(gap)) : 0.0;
}

const char *toString(MotionNoise m) { return m == MotionNoise::Absolute ? "absolute" : "increment"; }

MotionNoise motionNoiseFromString(const std::string &word)
{
  if (word == "increment")
    return MotionNoise::Increment;
  if (word == "absolute")
    return MotionNoise::Absolute;
  throw Error("motion noise must be increment or absolute, not '" + word + "'");
}

void GateOptions::validate() const
{
  checkSigma(min_baseline, "min-baseline");
  checkSigma(min_parallax_px, "min-parallax-px");
}

} // namespace yawdepth
