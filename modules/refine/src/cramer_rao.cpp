// depthCramerRao(): the Fisher information of the refine model at the truth (Eigen only, no Ceres).
#include "information.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <yawdepth/error.h>
#include <yawdepth/geometry/track_inputs.h>
#include <yawdepth/refine/refine.h>

namespace yawdepth {

using namespace refine_detail;

namespace {

/* The inputs, validated (validateInputs()'s rules, and a true point per track). */
TracksByFrame checkInputs(const std::vector<MotionSample> &truth, const std::vector<Track> &tracks,
                          const std::vector<Eigen::Vector3d> &w_points, const NoiseModel &noise)
{
  noise.validate();
  if (w_points.size() != tracks.size())
    throw Error("depthCramerRao: one true point per track is needed");
  if (truth.empty())
    throw Error("depthCramerRao: the motion log is empty");
  return validateInputs(truth, tracks);
}

/* The model's motion at the truth, without points. */
Model truthMotionModel(const YawRig &rig, const std::vector<MotionSample> &truth, const NoiseModel &noise)
{
  Model m;
  setModelMotion(m, rig, truth, noise);
  for (const MotionSample &s : truth) {
    if (m.general)
      m.poses.push_back({s.x, s.y, s.z, 0.0, 0.0, 0.0}); // at the reference orientation, the truth's
    else
      m.poses.push_back({s.x, s.y, s.z, s.heading, 0.0, 0.0});
    m.yaws.push_back(s.yaw);
  }
  return m;
}

/* The camera's rotation and centre at a row. */
void cameraAt(const Model &m, const YawRig &rig, int row, Eigen::Matrix3d &R, Eigen::Vector3d &c)
{
  if (m.general) {
    double f[7];
    std::copy(m.poses[row].begin(), m.poses[row].end(), f);
    f[6] = m.yaws[row];
    cameraInWorldGeneral(f, m.Rref[row], m.mount, R, c);
  } else {
    cameraInWorld(m.poses[row].data(), m.yaws[row], rig.cameraOffset(), R, c);
  }
}

/* Noise of the observed pixel mapped to normalised coordinates at the true camera point P. */
WhitenedObservation whitenedAtTruth(const CameraModel &camera, const Eigen::Vector3d &P, double sigma_px)
{
  const Eigen::Vector2d mt = P.head<2>() / P.z();
  Eigen::Matrix2d Jd;
  camera.distortNormalized(mt, &Jd);
  const Eigen::Matrix2d K = Eigen::Vector2d(camera.kx(), camera.ky()).asDiagonal();
  const Eigen::Matrix2d J = (K * Jd).inverse(); // d(x, y) / d(u, v)
  return whitenObservation(mt, J, sigma_px);
}

/* Adds a track's true point and its observations at the truth to m, each after the first linked to
   the previous one by phi^gap (rows) when the tracker's errors are correlated (phi > 0, as refine's
   innovations); returns the point's index, or -1 when the track has fewer than two observations or
   the point is behind a camera. */
int addTruePoint(Model &m, const CameraModel &camera, const YawRig &rig, const TracksByFrame &input, std::size_t t,
                 const Eigen::Vector3d &w_point, double sigma_px, double phi)
{
  const Track &track = input.tracks()[t];
  if (track.observations.size() < 2)
    return -1;
  const int ra = static_cast<int>(input.row(t, 0));
  const int rk = static_cast<int>(input.row(t, track.observations.size() - 1));
  // The true point anchored in its first camera frame.
  Eigen::Matrix3d Ra;
  Eigen::Vector3d ca;
  cameraAt(m, rig, ra, Ra, ca);
  const Eigen::Vector3d Pa = Ra.transpose() * (w_point - ca);
  if (!(Pa.z() > 0))
    return -1;
  std::vector<ModelObservation> obs;
  for (std::size_t k = 0; k < track.observations.size(); ++k) {
    const int row = static_cast<int>(input.row(t, k));
    Eigen::Matrix3d R;
    Eigen::Vector3d c;
    cameraAt(m, rig, row, R, c);
    const Eigen::Vector3d P = R.transpose() * (w_point - c);
    if (!(P.z() > 0))
      return -1;
    ModelObservation mo;
    mo.point = static_cast<int>(m.points.size());
    mo.row = row;
    mo.w = whitenedAtTruth(camera, P, sigma_px);
    obs.push_back(mo);
  }
  const int point = static_cast<int>(m.points.size());
  m.points.push_back({Pa.x() / Pa.z(), Pa.y() / Pa.z(), 1.0 / Pa.z()});
  m.anchor_row.push_back(ra);
  m.report_row.push_back(rk);
  const std::size_t first = m.observations.size();
  m.observations.insert(m.observations.end(), obs.begin(), obs.end());
  for (std::size_t k = 1; phi > 0 && k < obs.size(); ++k)
    m.setChainLink(first + k, first + k - 1, pixelCorrelationOver(phi, obs[k].row - obs[k - 1].row));
  return point;
}

} // namespace

std::vector<double> depthCramerRao(const CameraModel &camera, const YawRig &rig, const std::vector<MotionSample> &truth,
                                   const std::vector<Track> &tracks, const std::vector<Eigen::Vector3d> &w_points,
                                   const NoiseModel &noise, bool joint)
{
  const TracksByFrame input = checkInputs(truth, tracks, w_points, noise);
  Model m = truthMotionModel(rig, truth, noise);
  std::vector<double> out(tracks.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<int> point_of_track(tracks.size(), -1);
  for (std::size_t t = 0; t < tracks.size(); ++t)
    point_of_track[t] = addTruePoint(m, camera, rig, input, t, w_points[t], noise.sigma_px, noise.pixel_correlation);

  std::vector<Eigen::Matrix3d> cov;
  std::vector<char> ok;
  pointCovariances(m, joint, cov, ok);
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    const int p = point_of_track[t];
    if (p >= 0 && ok[p])
      out[t] = std::sqrt(std::max(cov[p](2, 2), 0.0));
  }
  return out;
}

} // namespace yawdepth
