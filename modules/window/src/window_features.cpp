// WindowEstimator's features: entering the state (anchor, start from the best of candidate points)
// and restarting when their observations disagree.
#include "window_impl.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace yawdepth {

using Impl = WindowState;

/* Triangulate from two observations (midpoint of the common perpendicular); false if not in front. */
bool Impl::triangulate(const Obs &a, const Obs &b, Eigen::Vector3d &P) const
{
  const Frame &fa = frameOf(a.frame);
  const Frame &fb = frameOf(b.frame);
  const Eigen::Vector3d da = fa.cam.R * Eigen::Vector3d(a.w.m[0], a.w.m[1], 1.0);
  const Eigen::Vector3d db = fb.cam.R * Eigen::Vector3d(b.w.m[0], b.w.m[1], 1.0);
  Eigen::Matrix2d A;
  A << da.dot(da), -da.dot(db), -da.dot(db), db.dot(db);
  const Eigen::Vector3d w = fb.cam.c - fa.cam.c;
  const Eigen::Vector2d rhs(da.dot(w), -db.dot(w));
  const double det = A.determinant();
  if (!(std::abs(det) > 1e-14 * A.cwiseAbs().maxCoeff() * A.cwiseAbs().maxCoeff()))
    return false;
  const Eigen::Vector2d st = A.inverse() * rhs;
  if (!(st(0) > 0 && st(1) > 0) || !st.allFinite())
    return false;
  P = 0.5 * (fa.cam.c + st(0) * da + fb.cam.c + st(1) * db);
  return true;
}

/* The anchored parameters of a world point (false if behind the anchor). */
bool Impl::anchorParameters(const Feature &ft, const Eigen::Vector3d &P, double *p)
{
  const Eigen::Vector3d q = ft.Ra.transpose() * (P - ft.ca);
  if (!(q.z() > 0) || !q.allFinite())
    return false;
  p[0] = q.x() / q.z();
  p[1] = q.y() / q.z();
  p[2] = 1.0 / q.z();
  return true;
}

/* Robust (Cauchy) cost of a feature's window observations at parameters p. */
double Impl::featureCost(Feature &ft, const double *p) const
{
  double saved[3];
  std::copy(ft.p, ft.p + 3, saved);
  std::copy(p, p + 3, ft.p);
  double cost = 0;
  for (const Obs &ob : ft.obs) {
    Eigen::Vector2d r;
    const bool front = observationResidual(ft, frameOf(ob.frame), ob, r, nullptr);
    cost += costOf(front ? r.squaredNorm() : 1e6, Phase::Robust);
  }
  std::copy(saved, saved + 3, ft.p);
  return cost;
}

/* A few robust Gauss-Newton iterations on a feature's point alone (the poses held), from p. */
void Impl::refinePointAlone(const Feature &ft, double *p) const
{
  const double info = 1.0 / (o.prior_sigma_inverse_depth * o.prior_sigma_inverse_depth);
  for (int it = 0; it < 6; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (const Obs &ob : ft.obs) {
      Eigen::Vector2d r;
      Eigen::Matrix<double, 2, 10> J;
      if (!window_detail::observationResidual(ft.Ra, ft.ca, p, frameOf(ob.frame).cam, ob.w, r, &J))
        continue;
      const double w = weightOf(r.squaredNorm(), Phase::Robust);
      const Eigen::Matrix<double, 2, 3> Jp = J.rightCols<3>();
      H += w * Jp.transpose() * Jp;
      g += w * Jp.transpose() * r;
    }
    H(2, 2) += info;
    g(2) += info * (p[2] - o.prior_inverse_depth);
    const Eigen::Vector3d dx = H.ldlt().solve(-g);
    if (!dx.allFinite())
      return;
    for (int j = 0; j < 3; ++j)
      p[j] += dx(j);
    if (dx.squaredNorm() < 1e-14)
      return;
  }
}

/* Start (or restart) a feature's point: candidates from the pairs of (up to five of) its
   observations that triangulate and from their rays at the prior's depth, each refined alone with
   the robust loss and scored robustly against all its observations; the best one wins (with
   keep_current, the current point competes too). */
void Impl::initialisePoint(Feature &ft, bool keep_current)
{
  double best[3] = {ft.p[0], ft.p[1], ft.p[2]};
  double best_cost = keep_current ? featureCost(ft, ft.p) : std::numeric_limits<double>::infinity();
  auto consider = [&](double *p) {
    refinePointAlone(ft, p);
    if (!(p[2] > 0) || !std::isfinite(p[0] + p[1] + p[2]))
      return;
    const double c = featureCost(ft, p);
    if (c < best_cost) {
      best_cost = c;
      std::copy(p, p + 3, best);
    }
  };
  // At most five observations, spread over the window, seed the candidates (15 at most).
  const std::size_t n = ft.obs.size(), m = std::min<std::size_t>(n, 5);
  std::vector<std::size_t> seeds;
  for (std::size_t k = 0; k < m; ++k)
    seeds.push_back(m == 1 ? 0 : k * (n - 1) / (m - 1));
  for (std::size_t a = 0; a < seeds.size(); ++a) {
    const Obs &oi = ft.obs[seeds[a]];
    const Frame &fi = frameOf(oi.frame);
    const Eigen::Vector3d ray = fi.cam.R * Eigen::Vector3d(oi.w.m[0], oi.w.m[1], 1.0);
    double p[3];
    if (anchorParameters(ft, fi.cam.c + ray / o.prior_inverse_depth, p))
      consider(p);
    for (std::size_t b = a + 1; b < seeds.size(); ++b) {
      Eigen::Vector3d P;
      if (triangulate(oi, ft.obs[seeds[b]], P) && anchorParameters(ft, P, p))
        consider(p);
    }
  }
  if (!std::isfinite(best_cost)) { // nothing in front of the cameras: the prior's depth
    best[0] = ft.obs.front().w.m[0];
    best[1] = ft.obs.front().w.m[1];
    best[2] = o.prior_inverse_depth;
  }
  std::copy(best, best + 3, ft.p);
}

/* A feature enters the state at its second window observation: anchored at the camera of its first,
   started from the best candidate, with the weak inverse-depth prior as its block of the prior (it
   is linear: exact at any point). */
void Impl::enterState(Feature &ft)
{
  const Frame &fa = frameOf(ft.obs.front().frame);
  ft.Ra = fa.cam.R;
  ft.ca = fa.cam.c;
  ft.p[0] = ft.obs.front().w.m[0];
  ft.p[1] = ft.obs.front().w.m[1];
  ft.p[2] = o.prior_inverse_depth;
  initialisePoint(ft, false);
  ft.in_state = true;
  const double info = 1.0 / (o.prior_sigma_inverse_depth * o.prior_sigma_inverse_depth);
  ft.in_prior = true;
  std::copy(ft.p, ft.p + 3, ft.x0);
  ft.D.setZero();
  ft.D(2, 2) = info;
  ft.gp = Eigen::Vector3d(0, 0, info * (ft.p[2] - o.prior_inverse_depth));
  ft.B.setZero(3, prior.dimY());
}

/* A feature that went wrong (most of its window observations disagree with it, e.g. after a gross
   error at its start): it starts again from its window observations, with what the prior held on it
   dropped (that came from the same wrong point). */
void Impl::restartFeature(Feature &ft)
{
  dropFromPrior(ft);
  // The observations up to its chain's link in the prior are in the prior's frame information still
  // (dropFromPrior keeps that): they leave, or the restart would count them again.
  ft.obs.erase(std::remove_if(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame <= ft.chain_frame; }),
               ft.obs.end());
  ft.chain_frame = kNoChain;
  for (Obs &ob : ft.obs)
    ob.outlier = false;
  ft.in_state = false;
  ft.young = true;
  ft.has_fej = false;
  ft.has_first = false;
  ft.old_inliers = 0;
  ft.old_outliers = 0;
  ft.old_parallax = 0;
  enterState(ft);
}

} // namespace yawdepth
