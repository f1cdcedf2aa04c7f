// WindowEstimator's factors: observations, increments (or poses), yaw readings and the prior; their
// cost and their Gauss-Newton system (window_impl.h's SchurSystem, or a dense one for the new frame).
#include "window_impl.h"

#include <cmath>

namespace yawdepth {

using namespace refine_detail;
using Impl = WindowState;

namespace {

/* Accumulate a whitened residual r with Jacobian J over the given columns (-1: not in the system)
   into g and, if H, into H, with weight w. Coefficient-based products: Eigen's blocked GEMM costs
   more than it saves on these small fixed sizes. */
template <int R, int C>
void accumulate(const Eigen::Matrix<double, R, 1> &r, const Eigen::Matrix<double, R, C> &J, const int *cols, double w,
                Eigen::MatrixXd *H, Eigen::VectorXd &g)
{
  const Eigen::Matrix<double, C, 1> Jtr = w * J.transpose().lazyProduct(r);
  Eigen::Matrix<double, C, C> JtJ;
  if (H)
    JtJ.noalias() = w * J.transpose().lazyProduct(J);
  for (int a = 0; a < C; ++a) {
    if (cols[a] < 0)
      continue;
    g(cols[a]) += Jtr(a);
    if (H)
      for (int b = 0; b < C; ++b)
        if (cols[b] >= 0)
          (*H)(cols[a], cols[b]) += JtJ(a, b);
  }
}

} // namespace

OdometryMeasurementGeneral Impl::increment(const Frame &prev, const Frame &cur) const
{
  OdometryMeasurementGeneral m = measuredIncrementGeneral(prev.row, cur.row, o.noise);
  const double distance = Eigen::Vector3d(m.d[0], m.d[1], m.d[2]).norm();
  const double angle = Eigen::AngleAxisd(m.dR).angle();
  m.inv_sigma_t = clampInv(incrementTranslationSigma(o.noise, distance));
  const Eigen::Vector3d sr = incrementRotationSigma(o.noise, six_dof, distance, angle);
  for (int i = 0; i < 3; ++i)
    m.inv_sigma_r[i] = clampInv(sr(i));
  return m;
}

/* Robust weight and cost of a squared whitened residual s. */
double Impl::weightOf(double s, Phase phase) const
{
  return phase == Phase::Robust ? 1.0 / (1.0 + s / (c_robust * c_robust)) : 1.0;
}
double Impl::costOf(double s, Phase phase) const
{
  return phase == Phase::Robust ? 0.5 * c_robust * c_robust * std::log1p(s / (c_robust * c_robust)) : 0.5 * s;
}

bool Impl::observationResidual(const Feature &ft, const Frame &f, const Obs &ob, Eigen::Vector2d &r,
                               Eigen::Matrix<double, 2, 10> *J)
{
  return window_detail::observationResidual(ft.Ra, ft.ca, ft.p, f.cam, ob.w, r, J);
}

/* The residual at the current values and the Jacobian at the first estimates of the feature and of
   the frame `fj` (the frame itself, or its copy at its first estimate): every factor and the prior
   agree on them, so that the prior cannot gain information by relinearisation. False: behind. */
bool Impl::observationJacobian(const Feature &ft, const Frame &f, const Frame *fj, const Obs &ob, Eigen::Vector2d &r,
                               Eigen::Matrix<double, 2, 10> &J) const
{
  const bool first_estimate = ft.has_fej || fj->has_fej;
  if (!first_estimate)
    return observationResidual(ft, f, ob, r, &J);
  if (!observationResidual(ft, f, ob, r, nullptr))
    return false;
  Eigen::Vector2d r_fej;
  if (!window_detail::observationResidual(ft.Ra, ft.ca, ft.has_fej ? ft.p_fej : ft.p, fj->cam, ob.w, r_fej, &J))
    observationResidual(ft, f, ob, r, &J);
  return true;
}

Impl::Frame Impl::fejFrame(const Frame &f) const
{
  Frame t = f;
  std::copy(f.x_fej, f.x_fej + kFrameDim, t.x);
  refreshCamera(t);
  return t;
}

/* Per window frame, the frame whose Jacobians the factors use: its copy at its first estimate when
   it is in the prior, else the frame itself. */
std::vector<Impl::Frame> Impl::fejFrames() const
{
  std::vector<Frame> out;
  out.reserve(frames.size());
  for (const Frame &f : frames)
    out.push_back(f.has_fej ? fejFrame(f) : f);
  return out;
}

/*
  Increments (or poses, for per-pose noise) and yaw readings: their cost and (fill) gradient and
  information over the columns offset[i] + local component of each window frame i (-1: not in the
  system). only_frame: -1 for every factor, else the factors that involve that window frame.
*/
double Impl::motionFactors(int only_frame, Fill fill, const std::vector<Frame> &fej, const std::vector<int> &offset,
                           Eigen::MatrixXd &H, Eigen::VectorXd &g) const
{
  Eigen::MatrixXd *Hp = fill == Fill::Full ? &H : nullptr;
  auto columns = [&](std::size_t i, int *cols) {
    for (int j = 0; j < kFrameDim; ++j)
      cols[j] = offset[i] < 0 || frames[i].local[j] < 0 ? -1 : offset[i] + frames[i].local[j];
  };
  double cost = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame &f = frames[i];
    const bool own = only_frame < 0 || static_cast<int>(i) == only_frame;
    const bool next = only_frame < 0 || static_cast<int>(i) + 1 == only_frame;
    int cols[2 * kFrameDim];
    columns(i, cols);
    if (yaws_free && own) {
      Eigen::Matrix<double, 1, 1> r, J;
      J(0, 0) = clampInv(o.noise.sigma_yaw);
      r(0) = (f.x[6] - f.row.yaw) * J(0, 0);
      cost += 0.5 * r.squaredNorm();
      if (fill != Fill::Cost)
        accumulate<1, 1>(r, J, &cols[6], 1.0, Hp, g);
    }
    if (!poses_free)
      continue;
    if (absolute && own) {
      const Eigen::Vector3d sr = poseRotationSigma(o.noise, six_dof);
      Eigen::Matrix<double, 6, 1> r;
      Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
      const double meas[3] = {f.row.x, f.row.y, f.row.z};
      for (int k = 0; k < 3; ++k) {
        J(k, k) = clampInv(o.noise.sigma_odom);
        r(k) = (f.x[k] - meas[k]) * J(k, k);
        J(3 + k, 3 + k) = clampInv(sr(k));
        r(3 + k) = f.x[3 + k] * J(3 + k, 3 + k);
      }
      cost += 0.5 * r.squaredNorm();
      if (fill != Fill::Cost)
        accumulate<6, 6>(r, J, cols, 1.0, Hp, g);
    } else if (!absolute && (own || next) && i + 1 < frames.size()) {
      const Frame &n = frames[i + 1];
      Eigen::Matrix<double, 6, 1> r, r_fej;
      window_detail::odometryResidual(f.x, f.cam, n.x, n.cam, n.from_prev, r, nullptr);
      cost += 0.5 * r.squaredNorm();
      if (fill == Fill::Cost)
        continue;
      Eigen::Matrix<double, 6, 14> J;
      window_detail::odometryResidual(fej[i].x, fej[i].cam, fej[i + 1].x, fej[i + 1].cam, n.from_prev, r_fej, &J);
      columns(i + 1, cols + kFrameDim);
      accumulate<6, 14>(r, J, cols, 1.0, Hp, g);
    }
  }
  return cost;
}

/* The prior's dy (WindowPrior): each prior frame's free components minus x0, then the auxiliary values. */
Eigen::VectorXd Impl::priorDeltaY() const
{
  Eigen::VectorXd d(prior.dimY());
  int k = 0;
  for (const WindowPrior::FrameVar &v : prior.frames) {
    const Frame &f = frameOf(v.frame);
    for (int j = 0; j < kFrameDim; ++j)
      if (f.local[j] >= 0)
        d(k + f.local[j]) = f.x[j] - v.x0[static_cast<std::size_t>(f.local[j])];
    k += v.dim;
  }
  d.tail(prior.aux) = prior.a;
  return d;
}

/* Per window frame, the information and gradient of the observation factors over all 7 parameters
   (fixed-size blocks), and between two frames that a chain's pair factor couples; scattered into
   the system's free components at the end. */
struct FrameBlocks {
  using Mat7 = Eigen::Matrix<double, kFrameDim, kFrameDim>;
  using Vec7 = Eigen::Matrix<double, kFrameDim, 1>;
  std::size_t n = 0;
  std::vector<Mat7, Eigen::aligned_allocator<Mat7>> H, cross; // cross: n x n, (earlier, later)
  std::vector<Vec7, Eigen::aligned_allocator<Vec7>> g;
  FrameBlocks(std::size_t frames, bool pairs) : n(frames), H(frames, Mat7::Zero()), g(frames, Vec7::Zero())
  {
    if (pairs)
      cross.assign(frames * frames, Mat7::Zero());
  }
  void scatter(const std::deque<Impl::Frame> &frames, const SchurSystem &s, Eigen::MatrixXd &Hs, Eigen::VectorXd &gs,
               bool full) const
  {
    for (std::size_t a = 0; a < n; ++a) {
      const int oa = s.frame_offset[a];
      const int *la = frames[a].local;
      for (int i = 0; oa >= 0 && i < kFrameDim; ++i) {
        if (la[i] < 0)
          continue;
        gs(oa + la[i]) += g[a](i);
        for (int j = 0; full && j < kFrameDim; ++j)
          if (la[j] >= 0)
            Hs(oa + la[i], oa + la[j]) += H[a](i, j);
        for (std::size_t b = 0; full && !cross.empty() && b < n; ++b) {
          const int ob = s.frame_offset[b];
          const Mat7 &M = a < b ? cross[a * n + b] : cross[b * n + a];
          for (int j = 0; a != b && ob >= 0 && j < kFrameDim; ++j)
            if (frames[b].local[j] >= 0)
              Hs(oa + la[i], ob + frames[b].local[j]) += a < b ? M(i, j) : M(j, i);
        }
      }
    }
  }
};

/* A whitened factor r with Jacobians Jp (the point, row block i) and Jx (window frame fi) into the
   system and the frame blocks (inline: the inner loop of every solve). */
static inline void addFactor(SchurSystem &s, int i, const Impl::Frame &f, std::size_t fi, const Eigen::Matrix<double, 2, 3> &Jp,
                      const Eigen::Matrix<double, 2, kFrameDim> &Jx, const Eigen::Vector2d &r, double w, bool full,
                      FrameBlocks &fb)
{
  s.b.segment<3>(3 * i) += w * Jp.transpose() * r;
  fb.g[fi].noalias() += w * Jx.transpose() * r;
  if (!full)
    return;
  s.A.middleRows<3>(3 * i).noalias() += w * Jp.transpose() * Jp;
  fb.H[fi].noalias() += w * Jx.transpose() * Jx;
  const int off = s.frame_offset[fi];
  if (off < 0)
    return;
  const Eigen::Matrix<double, 3, kFrameDim> Ex = w * Jp.transpose() * Jx;
  for (int j = 0; j < kFrameDim; ++j)
    if (f.local[j] >= 0)
      s.E.block<3, 1>(3 * i, off + f.local[j]) += Ex.col(j);
}

/* phi^gap (window_impl.h's ChainLink), gap in window frames. */
double Impl::chainCoefficient(int gap) const { return pixelCorrelationOver(o.noise.pixel_correlation, gap); }

/* The observation before ft.obs[k] in its track's chain (outliers skipped in the inlier phase), or
   none: the chain starts at k. */
const Impl::Obs *Impl::chainPrevious(const Feature &ft, std::size_t k, Phase phase) const
{
  if (o.noise.pixel_correlation <= 0)
    return nullptr;
  for (std::size_t j = k; j-- > 0;) {
    const Obs &ob = ft.obs[j];
    if (ob.frame < ft.chain_frame)
      return nullptr;
    if (phase == Phase::Robust || !ob.outlier)
      return &ob;
  }
  return nullptr;
}

/* One feature's observation factors (each an AR(1) innovation of its chain: ChainLink) into its
   point block (row i of the system) and the frame blocks. */
double Impl::featureFactors(SchurSystem &s, int i, Phase phase, Fill fill, const std::vector<Frame> &fej,
                            int only_frame, FrameBlocks &fb) const
{
  const Feature &ft = features.at(s.ids[static_cast<std::size_t>(i)]);
  const bool pairs = o.noise.pixel_correlation > 0;
  double cost = 0;
  ChainLink prev;
  for (const Obs &ob : ft.obs) {
    if (ob.frame < ft.chain_frame || (phase == Phase::Inliers && ob.outlier))
      continue;
    ChainLink cur;
    cur.fi = frameIndex(ob.frame);
    const bool own = ob.frame != ft.chain_frame; // else its factor is in the prior
    const bool wanted = own && (only_frame < 0 || cur.fi == only_frame || (prev.valid && prev.fi == only_frame));
    if (!wanted && !pairs)
      continue;
    const Frame &f = frames[static_cast<std::size_t>(cur.fi)];
    cur.valid = fill == Fill::Cost ? observationResidual(ft, f, ob, cur.r, nullptr)
                                   : observationJacobian(ft, f, &fej[static_cast<std::size_t>(cur.fi)], ob, cur.r, cur.J);
    if (!wanted || !cur.valid) { // behind: a fixed penalty, no gradient
      cost += wanted && phase == Phase::Robust ? costOf(1e6, phase) : 0.0;
      if (pairs)
        prev = cur;
      continue;
    }
    const double a = prev.valid ? chainCoefficient(cur.fi - prev.fi) : 0.0;
    if (a == 0) { // the chain's first, or independent errors
      const double sq = cur.r.squaredNorm();
      cost += costOf(sq, phase);
      if (fill != Fill::Cost)
        addFactor(s, i, f, static_cast<std::size_t>(cur.fi), cur.J.rightCols<3>(), cur.J.leftCols<kFrameDim>(), cur.r,
                  weightOf(sq, phase), fill == Fill::Full, fb);
    } else {
      const double scale = 1.0 / std::sqrt(1.0 - a * a);
      const Eigen::Vector2d r = scale * (cur.r - a * prev.r);
      const double sq = r.squaredNorm();
      cost += costOf(sq, phase);
      if (fill != Fill::Cost)
        accumulatePair(s, i, f, prev, cur, a, scale, r, weightOf(sq, phase), fill == Fill::Full, fb);
    }
    if (pairs)
      prev = cur;
  }
  return cost;
}

/* A pair factor (cur's innovation given prev, a and scale as in ChainLink; r its whitened residual)
   into point block i, both frames' blocks and their coupling. */
void Impl::accumulatePair(SchurSystem &s, int i, const Frame &f, const ChainLink &prev, const ChainLink &cur, double a,
                          double scale, const Eigen::Vector2d &r, double w, bool full, FrameBlocks &fb) const
{
  const Eigen::Matrix<double, 2, 3> Jp = scale * (cur.J.rightCols<3>() - a * prev.J.rightCols<3>());
  const Eigen::Matrix<double, 2, kFrameDim> Jx = scale * cur.J.leftCols<kFrameDim>();
  const Eigen::Matrix<double, 2, kFrameDim> Jq = -a * scale * prev.J.leftCols<kFrameDim>();
  const std::size_t fi = static_cast<std::size_t>(cur.fi), pi = static_cast<std::size_t>(prev.fi);
  addFactor(s, i, f, fi, Jp, Jx, r, w, full, fb);
  fb.g[pi].noalias() += w * Jq.transpose() * r;
  if (!full)
    return;
  fb.H[pi].noalias() += w * Jq.transpose() * Jq;
  fb.cross[pi * fb.n + fi].noalias() += w * Jq.transpose() * Jx; // prev is the earlier frame
  const int off = s.frame_offset[pi];
  const Eigen::Matrix<double, 3, kFrameDim> Eq = w * Jp.transpose() * Jq;
  for (int j = 0; off >= 0 && j < kFrameDim; ++j)
    if (frames[pi].local[j] >= 0)
      s.E.block<3, 1>(3 * i, off + frames[pi].local[j]) += Eq.col(j);
}

/* The observations of the state's features (every frame's factors, or only those that involve
   window frame only_frame), over the point blocks and the frames' free components. */
double Impl::observationFactors(SchurSystem &s, Phase phase, Fill fill, const std::vector<Frame> &fej,
                                int only_frame) const
{
  FrameBlocks fb(frames.size(), o.noise.pixel_correlation > 0 && fill == Fill::Full);
  double cost = 0;
  for (int i = 0; i < s.N(); ++i)
    cost += featureFactors(s, i, phase, fill, fej, only_frame, fb);
  if (fill != Fill::Cost)
    fb.scatter(frames, s, s.H, s.g, fill == Fill::Full);
  return cost;
}

/* The prior (WindowPrior) over the system's columns: each prior frame's, then the auxiliary ones. */
double Impl::priorFactor(SchurSystem &s, Fill fill) const
{
  const int nY = prior.dimY();
  std::vector<int> ycols;
  for (const WindowPrior::FrameVar &v : prior.frames) {
    const int off = s.frame_offset[static_cast<std::size_t>(frameIndex(v.frame))];
    for (int j = 0; j < v.dim; ++j)
      ycols.push_back(off < 0 ? -1 : off + j);
  }
  for (int k = 0; k < prior.aux; ++k)
    ycols.push_back(s.aux == prior.aux ? s.aux_offset + k : -1);
  const Eigen::VectorXd dy = priorDeltaY();
  double cost = prior.gy.dot(dy) + 0.5 * dy.dot(prior.C * dy);
  Eigen::VectorXd gy = prior.gy + prior.C * dy;
  for (int i = 0; i < s.N(); ++i) {
    const Feature &ft = features.at(s.ids[static_cast<std::size_t>(i)]);
    if (!ft.in_prior)
      continue;
    const Eigen::Vector3d df(ft.p[0] - ft.x0[0], ft.p[1] - ft.x0[1], ft.p[2] - ft.x0[2]);
    const Eigen::Vector3d Bdy = nY > 0 ? Eigen::Vector3d(ft.B * dy) : Eigen::Vector3d::Zero();
    cost += ft.gp.dot(df) + 0.5 * df.dot(ft.D * df) + df.dot(Bdy);
    if (fill == Fill::Cost)
      continue;
    s.b.segment<3>(3 * i) += ft.gp + ft.D * df + Bdy;
    if (nY > 0)
      gy += ft.B.transpose() * df;
    if (fill == Fill::Full) {
      s.A.middleRows<3>(3 * i) += ft.D;
      for (int k = 0; k < nY; ++k)
        if (ycols[static_cast<std::size_t>(k)] >= 0)
          s.E.block<3, 1>(3 * i, ycols[static_cast<std::size_t>(k)]) += ft.B.col(k);
    }
  }
  if (fill == Fill::Cost)
    return cost;
  for (int a = 0; a < nY; ++a) {
    const int ca = ycols[static_cast<std::size_t>(a)];
    if (ca < 0)
      continue;
    s.g(ca) += gy(a);
    for (int b = 0; fill == Fill::Full && b < nY; ++b)
      if (ycols[static_cast<std::size_t>(b)] >= 0)
        s.H(ca, ycols[static_cast<std::size_t>(b)]) += prior.C(a, b);
  }
  return cost;
}

/* Zero the system's parts that `fill` computes (the matrices keep their storage between solves). */
static void clearSystem(SchurSystem &s, Impl::Fill fill)
{
  s.b.setZero(3 * s.N());
  s.g.setZero(s.P);
  if (fill != Impl::Fill::Full)
    return;
  s.A.setZero(3 * s.N(), 3);
  s.E.setZero(3 * s.N(), s.P);
  s.H.setZero(s.P, s.P);
}

double Impl::linearizeState(SchurSystem &s, Phase phase, Fill fill) const
{
  if (fill != Fill::Cost)
    clearSystem(s, fill);
  const std::vector<Frame> fej = fill == Fill::Cost ? std::vector<Frame>() : fejFrames();
  double cost = observationFactors(s, phase, fill, fej, -1);
  cost += motionFactors(-1, fill, fej, s.frame_offset, s.H, s.g);
  return cost + priorFactor(s, fill);
}

/* The blanket of the oldest frame: its observations and motion factors, and the prior. */
double Impl::linearizeOldest(SchurSystem &s) const
{
  clearSystem(s, Fill::Full);
  const std::vector<Frame> fej = fejFrames();
  double cost = observationFactors(s, Phase::Inliers, Fill::Full, fej, 0);
  cost += motionFactors(0, Fill::Full, fej, s.frame_offset, s.H, s.g);
  return cost + priorFactor(s, Fill::Full);
}

/* The newest frame alone (the state's features and the other frames held): its observations and
   motion factors, over its free components (a dense system). */
double Impl::linearizeNewFrame(Phase phase, Fill fill, Eigen::MatrixXd &H, Eigen::VectorXd &g) const
{
  const int last = static_cast<int>(frames.size()) - 1;
  const Frame &f = frames.back();
  std::vector<int> offset(frames.size(), -1);
  offset.back() = 0;
  if (fill != Fill::Cost) {
    g.setZero(f.dim);
    if (fill == Fill::Full)
      H.setZero(f.dim, f.dim);
  }
  int cols[10];
  for (int j = 0; j < kFrameDim; ++j)
    cols[j] = f.local[j];
  std::fill(cols + kFrameDim, cols + 10, -1);
  double cost = 0;
  for (const auto &kv : features) {
    const Feature &ft = kv.second;
    if (!ft.in_state)
      continue;
    for (std::size_t k = 0; k < ft.obs.size(); ++k) {
      const Obs &ob = ft.obs[k];
      if (ob.frame != f.row.frame || (phase == Phase::Inliers && ob.outlier))
        continue;
      Eigen::Vector2d r, r_prev;
      Eigen::Matrix<double, 2, 10> J;
      if (!observationResidual(ft, f, ob, r, fill == Fill::Cost ? nullptr : &J)) {
        cost += phase == Phase::Robust ? costOf(1e6, phase) : 0.0;
        continue;
      }
      const Obs *prev = chainPrevious(ft, k, phase); // the chain's innovation (ChainLink), the others held
      if (prev && observationResidual(ft, frameOf(prev->frame), *prev, r_prev, nullptr)) {
        const double a = chainCoefficient(last - frameIndex(prev->frame));
        const double scale = 1.0 / std::sqrt(1.0 - a * a);
        r = scale * (r - a * r_prev);
        if (fill != Fill::Cost)
          J *= scale;
      }
      cost += costOf(r.squaredNorm(), phase);
      if (fill != Fill::Cost)
        accumulate<2, 10>(r, J, cols, weightOf(r.squaredNorm(), phase), fill == Fill::Full ? &H : nullptr, g);
    }
  }
  const std::vector<Frame> fej(frames.begin(), frames.end()); // the new frame is in no prior
  Eigen::MatrixXd Hm;
  Eigen::VectorXd gm;
  Eigen::MatrixXd &Hr = fill == Fill::Cost ? Hm : H;
  Eigen::VectorXd &gr = fill == Fill::Cost ? gm : g;
  if (fill == Fill::Cost) {
    Hm.setZero(f.dim, f.dim);
    gm.setZero(f.dim);
  }
  return cost + motionFactors(last, fill, fej, offset, Hr, gr);
}

/* The state's system: its layout (every window frame's free components, the prior's auxiliary
   directions, the features in the state); its matrices keep their storage. */
void Impl::layoutSystem(SchurSystem &s) const
{
  s.frame_offset.assign(frames.size(), -1);
  s.frame_numbers.clear();
  s.P = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    s.frame_numbers.push_back(frames[i].row.frame);
    if (frames[i].dim > 0) {
      s.frame_offset[i] = s.P;
      s.P += frames[i].dim;
    }
  }
  s.aux_offset = s.P;
  s.aux = prior.aux;
  s.P += prior.aux;
  s.ids.clear();
  for (const auto &kv : features)
    if (kv.second.in_state)
      s.ids.push_back(kv.first);
  s.factored = false;
}

} // namespace yawdepth
