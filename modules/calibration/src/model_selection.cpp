// Camera calibration: the distortion model, given or chosen among K4, K5, K8 (and the fisheye model)
// by the expected error over the image (held-out error and projection uncertainty).
#include "camera_calibration_impl.h"
#include "text.h"

#include <cmath>
#include <sstream>
#include <yawdepth/error.h>

namespace yawdepth {
namespace calibration_detail {

namespace {

/* The number of distortion coefficients of a model. */
int coefficientsOf(Distortion d) { return d == Distortion::K8 ? 8 : d == Distortion::K5 ? 5 : 4; }

/* A model fitted on the usable views and scored: RMS, held-out RMS, projection uncertainty over
   the image and their combination (or why the model is not usable). */
DistortionModelScore scoreModel(const CameraFit &fit, const std::vector<std::size_t> &usable, Distortion d)
{
  DistortionModelScore m;
  m.name = modelName(d);
  m.coefficients = coefficientsOf(d);
  m.fisheye = d == Distortion::Fisheye;
  const OpenCvSolution s = fit.solve(usable, d);
  double sse = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < usable.size(); ++k) {
    const std::vector<cv::Point2f> proj = projectView(fit.object[usable[k]], s.rvecs[k], s.tvecs[k], s.K, s.dist, d);
    addSquaredErrors(proj, fit.image[usable[k]], sse);
    n += proj.size();
  }
  m.rms_px = std::sqrt(sse / static_cast<double>(n));
  m.heldout_rms_px = fit.heldOut(usable, d, s);
  m.inadmissible = fit.admissibility(s, d, usable);
  if (m.inadmissible.empty()) {
    CameraCalibration tmp;
    tmp.camera = cameraOf(s, d, fit.width, fit.height);
    fit.intrinsicsCovariance(usable, s, d, tmp.intrinsics_covariance);
    double u2 = 0;
    for (double u : uncertaintyGrid(tmp, fit.width, fit.height))
      u2 += u * u / 48.0;
    m.image_uncertainty_px = std::sqrt(u2);
    m.score_px = std::hypot(m.heldout_rms_px, m.image_uncertainty_px);
    if (!std::isfinite(m.score_px))
      m.inadmissible = m.name + ": its projection cannot be computed over the whole image";
  }
  return m;
}

/* Why model `pick` was chosen among the scored ones (`best`: the least score). */
std::string modelReason(const std::vector<DistortionModelScore> &models, std::size_t pick, std::size_t best,
                        double simpler_within)
{
  std::ostringstream why;
  why << models[pick].name << ": expected error over the image " << fixed(models[pick].score_px, 4) << " px";
  bool first = true;
  for (std::size_t i = 0; i < models.size(); ++i)
    if (i != pick) {
      why << (first ? " against " : ", ")
          << (models[i].inadmissible.empty() ? fixed(models[i].score_px, 4) : std::string("not usable")) << " ("
          << (models[i].fisheye ? std::string("fisheye") : std::to_string(models[i].coefficients) + " coefficients")
          << ")";
      first = false;
    }
  if (pick != best)
    why << "; the simpler model is within " << fixed(100 * simpler_within, 0) << " % of the best";
  return why.str();
}

/* Among the scored K4, K5, K8 and (when tried) the fisheye model, in this order: the simplest
   usable one within `simpler_within` of the best score, marked chosen; the reason into `reason`.
   Throws when none is usable. */
Distortion pickModel(std::vector<DistortionModelScore> &models, double simpler_within, std::string &reason)
{
  std::size_t best = models.size();
  for (std::size_t i = 0; i < models.size(); ++i)
    if (models[i].inadmissible.empty() && std::isfinite(models[i].score_px) &&
        (best == models.size() || models[i].score_px < models[best].score_px))
      best = i;
  if (best == models.size()) {
    std::string why;
    for (const auto &m : models)
      why += (why.empty() ? "" : "; ") + m.name + ": " +
             (m.inadmissible.empty() ? std::string("its calibration failed on views left out") : m.inadmissible);
    throw Error("no distortion model gives a usable camera (" + why +
                "): take views whose corners reach the image's corners and edges");
  }
  std::size_t pick = best;
  for (std::size_t i = 0; i < best; ++i) // the simplest within the margin
    if (models[i].inadmissible.empty() && models[i].score_px <= (1 + simpler_within) * models[best].score_px) {
      pick = i;
      break;
    }
  models[pick].chosen = true;
  reason = modelReason(models, pick, best, simpler_within);
  return pick == 0 ? Distortion::K4 : pick == 1 ? Distortion::K5 : pick == 2 ? Distortion::K8 : Distortion::Fisheye;
}

} // namespace

/* The distortion model: given, or chosen by the held-out error (result.models, model_reason). */
Distortion chooseModel(const CameraFit &fit, const std::vector<std::size_t> &usable, CameraCalibration &result)
{
  Distortion model = fit.options.distortion;
  if (model == Distortion::Auto && fit.options.estimate_k3)
    model = Distortion::K5;
  if (model != Distortion::Auto) {
    DistortionModelScore m;
    m.name = modelName(model);
    m.coefficients = coefficientsOf(model);
    m.fisheye = model == Distortion::Fisheye;
    m.chosen = true;
    result.models.push_back(m);
    result.model_reason = modelName(model) + ": as asked";
    return model;
  }
  if (usable.size() < 4) {
    model = Distortion::K4;
    result.model_reason = "k1 k2 p1 p2: too few views (" + std::to_string(usable.size()) +
                          ") to compare models on views left out";
    DistortionModelScore m;
    m.name = modelName(model);
    m.coefficients = 4;
    m.chosen = true;
    result.models.push_back(m);
    return model;
  }
  for (Distortion d : {Distortion::K4, Distortion::K5, Distortion::K8})
    result.models.push_back(scoreModel(fit, usable, d));
  if (fit.options.try_fisheye) {
    try {
      result.models.push_back(scoreModel(fit, usable, Distortion::Fisheye));
    } catch (const Error &e) { // cv::fisheye failed (or cannot keep the aspect ratio): not usable
      DistortionModelScore m;
      m.name = modelName(Distortion::Fisheye);
      m.coefficients = 4;
      m.fisheye = true;
      m.inadmissible = m.name + ": " + e.what();
      result.models.push_back(m);
    }
  }
  return pickModel(result.models, fit.options.simpler_within, result.model_reason);
}

} // namespace calibration_detail
} // namespace yawdepth
