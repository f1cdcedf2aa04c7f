// WindowEstimator's solves: the Schur complement of the points, Gauss-Newton with chord steps, the
// new frame's alignment, outlier flags and the robust path.
#include "window_impl.h"

#include <algorithm>
#include <cmath>

namespace yawdepth {

using Impl = WindowState;

namespace {

/* A Cholesky factorisation; a direction without information (the priors should prevent it) is damped. */
template <typename Matrix, typename LLT> bool dampedCholesky(Matrix M, LLT &llt)
{
  llt.compute(M);
  if (llt.info() == Eigen::Success)
    return true;
  M.diagonal() += 1e-9 * M.diagonal().cwiseAbs() + Eigen::VectorXd::Constant(M.rows(), 1e-12);
  llt.compute(M);
  return llt.info() == Eigen::Success;
}

/*
  Gauss-Newton with step halving, on a problem with linearize(fill) -> cost, factor() -> bool,
  step(&gain) -> the step with the last factorisation and the current gradient, apply(dx, scale),
  save() and restore(). After each step the gradient at the new point and the last factorisation
  predict what another iteration would gain; below `convergence` it stops (the remainder is carried
  into the next frame's solve, or into the prior exactly, with its gradient). Chord steps reuse the
  last factorisation while they make fast progress. Returns the factorisations made.
*/
template <typename Problem> int gaussNewton(Problem &pb, int max_iterations, double convergence)
{
  using Fill = Impl::Fill;
  int factorisations = 0, chords = 0;
  bool refactor = true; // false: a chord step, with the last factorisation and the new gradient
  double cost = pb.linearize(Fill::Full);
  for (int it = 0; it < max_iterations + 2; ++it) {
    if (refactor) {
      if (it > 0)
        cost = pb.linearize(Fill::Full);
      ++factorisations;
      if (!pb.factor())
        return factorisations;
    }
    double predicted = 0;
    const Eigen::VectorXd dx = pb.step(&predicted);
    if (!dx.allFinite())
      return factorisations;
    const auto saved = pb.save();
    bool accepted = false;
    double scale = 1.0;
    for (int h = 0; h < (refactor ? 6 : 1); ++h, scale *= 0.5) {
      pb.apply(dx, scale);
      // The full step usually holds: its gradient comes with its cost, for the next prediction.
      const double c = pb.linearize(h == 0 ? Fill::Gradient : Fill::Cost);
      // A chord step must deliver most of what it promised; a full step only has to descend.
      if (std::isfinite(c) && c <= cost - (refactor ? 0.0 : 0.5 * predicted) + 1e-12 * std::abs(cost)) {
        accepted = true;
        cost = c;
        if (h > 0)
          pb.linearize(Fill::Gradient);
        break;
      }
      pb.restore(saved);
    }
    if (!accepted) {
      if (refactor)
        break;
      refactor = true; // the chord went astray: linearise afresh
      continue;
    }
    double next = 0; // what the next step would gain: 0.5 g' H^-1 g with the new gradient
    pb.step(&next);
    if (next < convergence || factorisations >= max_iterations)
      break;
    refactor = !(chords < 2 && next < 0.25 * predicted);
    chords += refactor ? 0 : 1;
  }
  return factorisations;
}

/* The whole state, through its Schur system. */
struct StateProblem {
  Impl &impl;
  SchurSystem &s;
  Impl::Phase phase;
  double linearize(Impl::Fill fill) { return impl.linearizeState(s, phase, fill); }
  bool factor() { return Impl::factor(s); }
  Eigen::VectorXd step(double *gain) const { return Impl::schurStep(s, gain); }
  void apply(const Eigen::VectorXd &dx, double scale) { impl.applyStep(s, dx, scale); }
  Impl::Saved save() const { return impl.save(s); }
  void restore(const Impl::Saved &saved) { impl.restore(s, saved); }
};

/* The newest frame alone (a dense system of its free components). */
struct NewFrameProblem {
  Impl &impl;
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  Eigen::LLT<Eigen::MatrixXd> llt;
  double linearize(Impl::Fill fill) { return impl.linearizeNewFrame(Impl::Phase::Robust, fill, H, g); }
  bool factor() { return dampedCholesky(H, llt); }
  Eigen::VectorXd step(double *gain) const
  {
    Eigen::VectorXd dx = llt.solve(-g);
    *gain = -0.5 * g.dot(dx);
    return dx;
  }
  void apply(const Eigen::VectorXd &dx, double scale)
  {
    Impl::Frame &f = impl.frames.back();
    for (int j = 0; j < kFrameDim; ++j)
      if (f.local[j] >= 0)
        f.x[j] += scale * dx(f.local[j]);
    impl.refreshCamera(f);
  }
  std::array<double, kFrameDim> save() const
  {
    std::array<double, kFrameDim> a;
    std::copy(impl.frames.back().x, impl.frames.back().x + kFrameDim, a.begin());
    return a;
  }
  void restore(const std::array<double, kFrameDim> &a)
  {
    std::copy(a.begin(), a.end(), impl.frames.back().x);
    impl.refreshCamera(impl.frames.back());
  }
};

} // namespace

/* Eliminate the points (a 3 x 3 Cholesky each) and factorise the reduced system. */
bool Impl::factor(SchurSystem &s)
{
  const int N = s.N();
  s.factored = false;
  s.L.resize(3 * N, 3);
  s.U.resize(3 * N, s.P);
  for (int i = 0; i < N; ++i) {
    Eigen::LLT<Eigen::Matrix3d> llt;
    if (!dampedCholesky(Eigen::Matrix3d(s.A.middleRows<3>(3 * i)), llt))
      return false;
    s.L.middleRows<3>(3 * i) = llt.matrixL().toDenseMatrix();
    if (s.P > 0)
      s.U.middleRows<3>(3 * i) = llt.matrixL().solve(s.E.middleRows<3>(3 * i));
  }
  if (s.P > 0) {
    Eigen::MatrixXd S = s.H;
    if (N > 0) // (Eigen's rank update divides by its inner size)
      S.selfadjointView<Eigen::Lower>().rankUpdate(s.U.transpose(), -1.0);
    if (!dampedCholesky(S, s.S))
      return false;
  }
  s.factored = true;
  return true;
}

/* The Gauss-Newton step -H^-1 (b, g) through the factorisation: the reduced variables first, then
   the points; *gain = 0.5 (b, g)' H^-1 (b, g). */
Eigen::VectorXd Impl::schurStep(const SchurSystem &s, double *gain)
{
  const int N = s.N();
  Eigen::VectorXd v(3 * N);
  for (int i = 0; i < N; ++i)
    v.segment<3>(3 * i) =
        Eigen::Matrix3d(s.L.middleRows<3>(3 * i)).triangularView<Eigen::Lower>().solve(Eigen::Vector3d(s.b.segment<3>(3 * i)));
  Eigen::VectorXd dx(s.P + 3 * N);
  double quad = v.squaredNorm();
  if (s.P > 0) {
    const Eigen::VectorXd rhs = s.g - s.U.transpose() * v;
    dx.head(s.P) = -s.S.solve(rhs);
    quad -= rhs.dot(dx.head(s.P));
  }
  for (int i = 0; i < N; ++i) {
    Eigen::Vector3d t = v.segment<3>(3 * i);
    if (s.P > 0)
      t += s.U.middleRows<3>(3 * i) * dx.head(s.P);
    dx.segment<3>(s.P + 3 * i) =
        -Eigen::Matrix3d(s.L.middleRows<3>(3 * i)).transpose().triangularView<Eigen::Upper>().solve(t);
  }
  *gain = 0.5 * quad;
  return dx;
}

void Impl::applyStep(const SchurSystem &s, const Eigen::VectorXd &dx, double scale)
{
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (s.frame_offset[i] < 0)
      continue;
    Frame &f = frames[i];
    for (int j = 0; j < kFrameDim; ++j)
      if (f.local[j] >= 0)
        f.x[j] += scale * dx(s.frame_offset[i] + f.local[j]);
    refreshCamera(f);
  }
  if (s.aux > 0)
    prior.a += scale * dx.segment(s.aux_offset, s.aux);
  for (int i = 0; i < s.N(); ++i) {
    Feature &ft = features.at(s.ids[static_cast<std::size_t>(i)]);
    for (int j = 0; j < 3; ++j)
      ft.p[j] += scale * dx(s.P + 3 * i + j);
  }
}

Impl::Saved Impl::save(const SchurSystem &s) const
{
  Saved saved;
  for (const Frame &f : frames) {
    std::array<double, kFrameDim> a;
    std::copy(f.x, f.x + kFrameDim, a.begin());
    saved.frames.push_back(a);
  }
  for (long id : s.ids) {
    const Feature &ft = features.at(id);
    saved.points.push_back({ft.p[0], ft.p[1], ft.p[2]});
  }
  saved.aux = prior.a;
  return saved;
}

void Impl::restore(const SchurSystem &s, const Saved &saved)
{
  for (std::size_t i = 0; i < frames.size(); ++i) {
    std::copy(saved.frames[i].begin(), saved.frames[i].end(), frames[i].x);
    refreshCamera(frames[i]);
  }
  for (std::size_t i = 0; i < s.ids.size(); ++i)
    std::copy(saved.points[i].begin(), saved.points[i].end(), features.at(s.ids[i]).p);
  prior.a = saved.aux;
}

/* Gauss-Newton on the whole state; its system and factorisation are kept for the covariances. */
int Impl::solve(Phase phase)
{
  layoutSystem(sys);
  if (sys.dimension() == 0)
    return 0;
  StateProblem pb{*this, sys, phase};
  return gaussNewton(pb, o.max_iterations, o.convergence);
}

/* The new frame alone against the state (a solve of its free components): a start that the full
   solve then refines in one or two iterations. */
void Impl::alignNewFrame()
{
  sys.factored = false; // the state's last factorisation no longer matches it (a new frame)
  if (frames.size() < 2 || frames.back().dim == 0)
    return;
  NewFrameProblem pb{*this, {}, {}, {}};
  gaussNewton(pb, o.max_iterations, o.convergence);
}

/* Flag every observation of the state's features by its reprojection error; true if a flag changed. */
bool Impl::flagOutliers()
{
  bool changed = false;
  for (auto &kv : features) {
    Feature &ft = kv.second;
    if (!ft.in_state)
      continue;
    for (Obs &ob : ft.obs) {
      if (ob.frame <= ft.chain_frame)
        continue; // its factor or its chain's link is in the prior: the flag is final
      Eigen::Vector2d r;
      const bool front = observationResidual(ft, frameOf(ob.frame), ob, r, nullptr);
      const bool outlier = !front || r.squaredNorm() > c_outlier_sq;
      changed = changed || outlier != ob.outlier;
      ob.outlier = outlier;
    }
  }
  return changed;
}

/* The robust phase, a restart of the features whose observations disagree, flags, then least
   squares on the inliers. */
void Impl::robustSolve()
{
  solve(Phase::Robust);
  flagOutliers();
  bool restarted = false;
  for (auto &kv : features) {
    Feature &ft = kv.second;
    if (!ft.in_state)
      continue;
    const long flagged = std::count_if(ft.obs.begin(), ft.obs.end(), [](const Obs &ob) { return ob.outlier; });
    if (flagged == 0)
      continue;
    if (ft.young) {
      const double before[3] = {ft.p[0], ft.p[1], ft.p[2]};
      initialisePoint(ft, true);
      restarted = restarted || !std::equal(before, before + 3, ft.p);
    } else if (flagged >= 3 && 2 * flagged > static_cast<long>(ft.obs.size()) && ft.obs.size() >= 2) {
      restartFeature(ft);
      restarted = true;
    }
  }
  if (restarted) {
    solve(Phase::Robust);
    flagOutliers();
  }
  solve(Phase::Inliers);
  if (flagOutliers())
    solve(Phase::Inliers);
}

} // namespace yawdepth
