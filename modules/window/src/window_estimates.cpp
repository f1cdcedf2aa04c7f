// WindowEstimator's estimates: each feature's point at its last observed frame, its gates, and its
// covariance from the last solve's factorisation (linear in the features: the Schur complement).
#include "window_impl.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <yawdepth/estimation/depth_filter.h>

namespace yawdepth {

using Impl = WindowState;

/* Rotation-compensated parallax (px) of an observation against a world ray. */
double Impl::parallaxPx(const Eigen::Vector3d &ray_w, const Frame &f, const Obs &ob) const
{
  const Eigen::Vector3d q = f.cam.R.transpose() * ray_w;
  if (!(q.z() > 0))
    return std::numeric_limits<double>::infinity(); // the point at infinity is behind: all parallax
  return std::hypot(camera.kx() * (q.x() / q.z() - ob.w.m[0]), camera.ky() * (q.y() / q.z() - ob.w.m[1]));
}

/*
  A feature's estimate with the gates that need no covariance (window_estimator.h). Status Ok here is
  provisional: ensureCache() gives the point its covariance and the depth gate. A point at a
  non-positive inverse depth (seen in front of every camera) comes back `behind` with *rho_only set,
  for ensureCache() to tell `behind` from an unresolved depth.
*/
PointEstimate Impl::gatedEstimate(const Feature &ft, bool *rho_only) const
{
  *rho_only = false;
  PointEstimate e;
  e.frame = ft.last_frame;
  if (!ft.in_state || frameIndex(ft.last_frame) < 0) {
    e.status = ft.undistort_failed && !ft.in_state ? Status::UndistortFailed : Status::TooFewFrames;
    return e;
  }
  int inliers = ft.old_inliers, outliers = ft.old_outliers;
  bool has_first = ft.has_first, behind = false;
  Eigen::Vector3d first_ray = ft.first_ray, first_centre = ft.first_centre, last_centre = ft.last_centre;
  double parallax = ft.old_parallax;
  for (const Obs &ob : ft.obs) {
    if (ob.outlier) {
      ++outliers;
      continue;
    }
    const Frame &f = frameOf(ob.frame);
    ++inliers;
    last_centre = f.cam.c;
    const Eigen::Vector3d ray = f.cam.R * Eigen::Vector3d(ob.w.m[0], ob.w.m[1], 1.0);
    if (!has_first) {
      has_first = true;
      first_ray = ray;
      first_centre = f.cam.c;
      Eigen::Vector2d r;
      behind = behind || !observationResidual(ft, f, ob, r, nullptr);
    } else {
      parallax = std::max(parallax, parallaxPx(first_ray, f, ob));
    }
  }
  Eigen::Vector2d r_last;
  behind = behind || !observationResidual(ft, frameOf(ft.last_frame), Obs{ft.last_frame, {}, false}, r_last, nullptr);
  e.parallax_px = parallax;
  // Two observations always agree on a point: with an outlier among them, two inliers cannot tell
  // which were the outliers.
  if (inliers < 2 || (outliers > 0 && inliers < 3))
    e.status = Status::TooFewFrames;
  else if ((last_centre - first_centre).norm() < o.gates.min_baseline)
    e.status = Status::NoMotion;
  else if (parallax < o.gates.min_parallax_px)
    e.status = Status::Degenerate;
  else if (behind || !(ft.p[2] > 0)) {
    e.status = Status::Behind;
    *rho_only = !behind;
  }
  else
    e.status = Status::Ok;
  if (!e.ok())
    return e;
  const Frame &f = frameOf(ft.last_frame);
  const Eigen::Vector3d u = ft.Ra * Eigen::Vector3d(ft.p[0], ft.p[1], 1.0) + ft.p[2] * (ft.ca - f.cam.c);
  e.c_P = f.cam.R.transpose() * u / ft.p[2];
  e.v_P = rig.visionPoint(f.x[6], e.c_P);
  return e;
}

/*
  The Jacobian of the point at its last frame (c_P) by the feature's parameters (Jf) and by the
  reduced variables of the last solve (JY: its last frame's free components), or false when that
  frame or feature was not in the solve.
*/
bool Impl::pointJacobian(const Feature &ft, Eigen::Matrix3d &Jf, Eigen::MatrixXd &JY) const
{
  const auto li = std::find(sys.frame_numbers.begin(), sys.frame_numbers.end(), ft.last_frame);
  if (li == sys.frame_numbers.end())
    return false;
  const int off = sys.frame_offset[static_cast<std::size_t>(li - sys.frame_numbers.begin())];
  const Frame &f = frameOf(ft.last_frame);
  const double rho = ft.p[2];
  const Eigen::Vector3d dca = ft.ca - f.cam.c;
  const Eigen::Vector3d u = ft.Ra * Eigen::Vector3d(ft.p[0], ft.p[1], 1.0) + rho * dca;
  const Eigen::Vector3d q = f.cam.R.transpose() * u;
  Jf.col(0) = f.cam.R.transpose() * ft.Ra.col(0) / rho;
  Jf.col(1) = f.cam.R.transpose() * ft.Ra.col(1) / rho;
  Jf.col(2) = f.cam.R.transpose() * dca / rho - q / (rho * rho);
  JY.setZero(3, sys.P);
  for (int j = 0; off >= 0 && j < kFrameDim; ++j)
    if (f.local[j] >= 0)
      JY.col(off + f.local[j]) = (q.cross(f.cam.w[j]) - rho * f.cam.Rt_dc[j]) / rho;
  return true;
}

/*
  Every state feature's estimate, with covariances from the last factorisation: for the point's
  Jacobian (Jf, JY), cov = Jf A^-1 Jf' + Q S^-1 Q', Q = Jf A^-1 E - JY (A, E the feature's block and
  coupling, S the Schur complement), all Q in one triangular solve.
*/
void Impl::ensureCache() const
{
  if (cache_valid)
    return;
  cache.clear();
  std::map<long, int> index;
  for (int i = 0; i < sys.N(); ++i)
    index[sys.ids[static_cast<std::size_t>(i)]] = i;
  struct Pending {
    long id;
    int i;
    Eigen::Matrix3d Jf, Ainv;
    bool rho_only;
  };
  std::vector<Pending> pending;
  Eigen::MatrixXd Qt(sys.P, 0);
  std::vector<Eigen::MatrixXd> Qs;
  for (const auto &kv : features) {
    const Feature &ft = kv.second;
    if (!ft.in_state)
      continue;
    bool rho_only = false;
    PointEstimate e = gatedEstimate(ft, &rho_only);
    cache[kv.first] = e;
    const auto it = index.find(kv.first);
    if (!(e.ok() || rho_only))
      continue;
    Pending p{kv.first, it == index.end() ? -1 : it->second, Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero(), rho_only};
    Eigen::MatrixXd JY = Eigen::MatrixXd::Zero(3, sys.P);
    if (!sys.factored || p.i < 0 || (!rho_only && !pointJacobian(ft, p.Jf, JY))) {
      if (e.ok())
        cache[kv.first].status = Status::Degenerate; // no information to give it a covariance
      continue;
    }
    if (rho_only)
      p.Jf(2, 2) = 1.0;
    const Eigen::Matrix3d L = sys.L.middleRows<3>(3 * p.i);
    const Eigen::Matrix3d Linv = L.triangularView<Eigen::Lower>().solve(Eigen::Matrix3d::Identity());
    p.Ainv = Linv.transpose() * Linv;
    if (sys.P > 0) // Q = Jf A^-1 E - JY = Jf L^-T U - JY
      Qs.emplace_back(p.Jf * (Linv.transpose() * sys.U.middleRows<3>(3 * p.i)) - JY);
    pending.push_back(p);
  }
  Eigen::MatrixXd Z(sys.P, 3 * static_cast<Eigen::Index>(Qs.size()));
  for (std::size_t k = 0; k < Qs.size(); ++k)
    Z.middleCols<3>(3 * static_cast<Eigen::Index>(k)) = Qs[k].transpose();
  if (sys.P > 0 && Z.cols() > 0)
    sys.S.matrixL().solveInPlace(Z);
  for (std::size_t k = 0; k < pending.size(); ++k) {
    const Pending &p = pending[k];
    Eigen::Matrix3d cov = p.Jf * p.Ainv * p.Jf.transpose();
    if (sys.P > 0) {
      const auto X = Z.middleCols<3>(3 * static_cast<Eigen::Index>(k));
      cov += X.transpose() * X;
    }
    PointEstimate &e = cache[p.id];
    if (p.rho_only) {
      // Beyond infinity: behind the camera only if the inverse depth's 2-sigma range stays below
      // zero; else the depth is not resolved.
      if (features.at(p.id).p[2] + 2.0 * std::sqrt(std::max(cov(2, 2), 0.0)) > 0)
        e.status = Status::Degenerate;
      continue;
    }
    e.c_cov = cov;
    // As `fused`: a depth without a bounded 2-sigma interval is not a measurement.
    if (!e.c_cov.allFinite() || !inverseDepthBounded(std::sqrt(e.c_cov(2, 2)) / e.c_P.z()))
      e.status = Status::Degenerate;
  }
  cache_valid = true;
}

} // namespace yawdepth
