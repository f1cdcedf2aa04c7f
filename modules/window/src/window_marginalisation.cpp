// WindowEstimator's prior: the oldest frame leaving the window, the features leaving with it, and
// the compression that keeps the prior free of feature-feature terms.
//
// When the oldest frame leaves, its factors (observations, its increment or pose, its yaw reading, and
// with correlated tracker errors the pair factor of each track's next observation) and the prior are
// linearised (first-estimate Jacobians) into a blanket system over the features in the state, the
// oldest frame, the frames it is linked to (by its increment and by those pairs), and the prior's
// auxiliary directions. The
// features that leave with the frame are eliminated exactly (Schur complement: they couple only to
// frames and auxiliary directions). Eliminating the oldest frame and the old auxiliary directions z
// exactly would couple every pair of features that saw them: the exact marginal is
//   F-F: D - G G',   F-K: E_K - G T' H_zK,   K-K: H_KK - H_Kz H_zz^+ H_zK,     G = E_z T, T T' = H_zz^+,
// (K: the frames kept in the prior, D: each feature's own block). The term G G' is carried instead
// by new auxiliary directions a, a Gaussian factor [[D, G_r], [G_r', I]] whose marginal over the
// features is D - G_r G_r': G_r = G W with W the leading right singular vectors of G, each feature's
// rows taken in units of its own information (A_i^-1/2 G_i; linear in the features). A direction
// whose normalised eigenvalue is below kAuxTolerance is dropped (as are those beyond kMaxAux): the
// prior then claims that much more of a feature's information than the exact marginal (dropping part
// of a subtracted term), at most 1 % of any feature's own information (1e-5 with correlated tracker
// errors: kAuxToleranceCorrelated says why).
#include "window_impl.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace yawdepth {

using Impl = WindowState;

namespace {

constexpr double kAuxTolerance = 1e-2; // normalised eigenvalues kept: above 1 % of a feature's information
/* With the tracker's correlated errors (pair factors, window_impl.h's ChainLink) a point's final
   information is a small difference of large terms: on test_window's AR(1) scenes (phi 0.9) dropping
   directions under 1e-2, 1e-4 and 1e-6 of the blanket's information left the depth's sigma at 0.65,
   0.99 and 1.00 of the exact marginalisation's. */
constexpr double kAuxToleranceCorrelated = 1e-5;
/* Most directions kept with correlated errors: at 64, bench_window's long sequence with AR(1) errors
   (--pixel-correlation 0.9, 600 frames, 4 trials) had NEES 5.97 and coverage 0.51; without a cap 1.71
   and 0.87 (the same sequence with independent errors and model: 2.29 and 0.79). */
constexpr int kMaxAuxCorrelated = 256;
constexpr int kMaxAux = 64;            // most directions kept (a bound on the cost; 36 to 39 on bench_window's long sequence)

/* T with M^+ = T T' (the pseudo-inverse: directions without information carry none). */
Eigen::MatrixXd pseudoInverseFactor(const Eigen::MatrixXd &M)
{
  if (M.rows() == 0)
    return Eigen::MatrixXd(0, 0);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (M + M.transpose()));
  const Eigen::VectorXd &ev = es.eigenvalues();
  const double tol = 1e-12 * std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
  std::vector<int> keep;
  for (int i = 0; i < ev.size(); ++i)
    if (ev(i) > tol)
      keep.push_back(i);
  Eigen::MatrixXd T(M.rows(), static_cast<Eigen::Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k)
    T.col(static_cast<Eigen::Index>(k)) = es.eigenvectors().col(keep[k]) / std::sqrt(ev(keep[k]));
  return T;
}

/* The leading eigenvectors W of G'G (the directions of G kept, see the file comment). */
Eigen::MatrixXd leadingDirections(const Eigen::MatrixXd &GtG, double tolerance, int most)
{
  if (GtG.rows() == 0)
    return Eigen::MatrixXd(0, 0);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(GtG);
  const Eigen::VectorXd &ev = es.eigenvalues(); // ascending
  int k = 0;
  while (k < ev.size() && k < most && ev(ev.size() - 1 - k) > tolerance)
    ++k;
  return es.eigenvectors().rightCols(k).rowwise().reverse();
}

/* Rows `rows` and columns `cols` of M. */
Eigen::MatrixXd pick(const Eigen::MatrixXd &M, const std::vector<int> &rows, const std::vector<int> &cols)
{
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t a = 0; a < rows.size(); ++a)
    for (std::size_t b = 0; b < cols.size(); ++b)
      out(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = M(rows[a], cols[b]);
  return out;
}

} // namespace

/* Eliminate a feature from the prior (its information on the frames and auxiliary directions stays). */
void Impl::dropFromPrior(Feature &ft)
{
  if (!ft.in_prior)
    return;
  if (prior.dimY() > 0) {
    const Eigen::MatrixXd T = pseudoInverseFactor(ft.D);
    const Eigen::MatrixXd TB = T.transpose() * ft.B;
    prior.C -= TB.transpose() * TB;
    prior.C = 0.5 * (prior.C + prior.C.transpose()).eval();
    prior.gy -= TB.transpose() * (T.transpose() * ft.gp);
  }
  ft.in_prior = false;
  ft.D.setZero();
  ft.gp.setZero();
  ft.B.resize(0, 0);
  cache_valid = false;
}

/* Features in the state that no later window frame observed. */
std::vector<long> Impl::leavingFeatures(long frame0) const
{
  std::vector<long> leaving;
  for (const auto &kv : features) {
    const Feature &ft = kv.second;
    const bool later = std::any_of(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame != frame0; });
    if (ft.in_state && !later)
      leaving.push_back(kv.first);
  }
  return leaving;
}

/* The observation whose pair factor with frame0's observation of ft joins the prior with frame0
   (the next in the chain: window_impl.h's ChainLink), or none (no correlation, frame0's observation
   an outlier or frozen, or the last). */
const Impl::Obs *Impl::chainSuccessor(const Feature &ft, long frame0) const
{
  if (o.noise.pixel_correlation <= 0 || !ft.in_state || frame0 < ft.chain_frame)
    return nullptr;
  const auto at = std::find_if(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame == frame0; });
  if (at == ft.obs.end() || at->outlier)
    return nullptr;
  const auto next = std::find_if(std::next(at), ft.obs.end(), [](const Obs &ob) { return !ob.outlier; });
  return next == ft.obs.end() ? nullptr : &*next;
}

/* Frames and features that join the prior's non-trivial part now keep their current value as the
   point where every later Jacobian of theirs is evaluated. */
void Impl::setFirstEstimates(long frame0)
{
  for (int fi = 0; fi < (absolute ? 1 : 2) && fi < static_cast<int>(frames.size()); ++fi) { // per-pose noise: no link
    Frame &f = frames[static_cast<std::size_t>(fi)];
    if (!f.has_fej) {
      f.has_fej = true;
      std::copy(f.x, f.x + kFrameDim, f.x_fej);
    }
  }
  for (auto &kv : features) {
    Feature &ft = kv.second;
    if (const Obs *next = chainSuccessor(ft, frame0)) { // its frame is linked to frame0 through the pair
      Frame &f = frames[static_cast<std::size_t>(frameIndex(next->frame))];
      if (!f.has_fej) {
        f.has_fej = true;
        std::copy(f.x, f.x + kFrameDim, f.x_fej);
      }
    }
    if (!ft.in_state || ft.has_fej)
      continue;
    if (std::any_of(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame == frame0 && !ob.outlier; })) {
      ft.has_fej = true;
      std::copy(ft.p, ft.p + 3, ft.p_fej);
    }
  }
}

/* The blanket system's layout: the oldest frame, then the other frames it or the prior links, then
   the prior's auxiliary directions; every feature in the state. */
void Impl::blanketLayout(SchurSystem &s) const
{
  layoutSystem(s);
  std::vector<char> linked(frames.size(), 0);
  linked[0] = 1;
  if (frames.size() > 1 && !absolute)
    linked[1] = 1;
  for (const WindowPrior::FrameVar &v : prior.frames)
    linked[static_cast<std::size_t>(frameIndex(v.frame))] = 1;
  for (const auto &kv : features)
    if (const Obs *next = chainSuccessor(kv.second, frames.front().row.frame))
      linked[static_cast<std::size_t>(frameIndex(next->frame))] = 1;
  s.P = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    s.frame_offset[i] = linked[i] && frames[i].dim > 0 ? s.P : -1;
    s.P += s.frame_offset[i] >= 0 ? frames[i].dim : 0;
  }
  s.aux_offset = s.P;
  s.P += s.aux;
}

/* Eliminate the leaving features from the blanket system (exactly: they couple to no other feature). */
void Impl::eliminateFeatures(SchurSystem &s, const std::vector<long> &leaving) const
{
  for (int i = 0; s.P > 0 && i < s.N(); ++i) { // without frames or directions, nothing to carry
    if (std::find(leaving.begin(), leaving.end(), s.ids[static_cast<std::size_t>(i)]) == leaving.end())
      continue;
    const Eigen::MatrixXd T = pseudoInverseFactor(Eigen::Matrix3d(s.A.middleRows<3>(3 * i)));
    const Eigen::MatrixXd TE = T.transpose() * s.E.middleRows<3>(3 * i);
    s.H -= TE.transpose() * TE;
    s.g -= TE.transpose() * (T.transpose() * s.b.segment<3>(3 * i));
  }
}

/* The new prior from the blanket system (the file comment): the oldest frame and the old auxiliary
   directions z eliminated, the feature-feature term carried by new auxiliary directions. */
void Impl::condensePrior(const SchurSystem &s, const std::vector<long> &leaving)
{
  std::vector<int> zc, kc; // columns eliminated (the oldest frame, the old auxiliary directions), kept
  std::vector<WindowPrior::FrameVar> kept_frames;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const int off = s.frame_offset[i];
    for (int j = 0; off >= 0 && j < frames[i].dim; ++j)
      (i == 0 ? zc : kc).push_back(off + j);
    if (i > 0 && off >= 0) {
      WindowPrior::FrameVar v{frames[i].row.frame, frames[i].dim, {}};
      for (int j = 0; j < kFrameDim; ++j)
        if (frames[i].local[j] >= 0)
          v.x0.push_back(frames[i].x[j]);
      kept_frames.push_back(v);
    }
  }
  for (int k = 0; k < s.aux; ++k)
    zc.push_back(s.aux_offset + k);
  const std::vector<int> one{0};
  const Eigen::MatrixXd T = pseudoInverseFactor(pick(s.H, zc, zc));
  const Eigen::MatrixXd TtHzK = T.transpose() * pick(s.H, zc, kc);
  const Eigen::VectorXd Ttgz = T.transpose() * pick(s.g, zc, one);
  // Kept features: G_i = E_z,i T, their coupling to the kept frames and their gradient.
  std::vector<int> rows;
  for (int i = 0; i < s.N(); ++i)
    if (std::find(leaving.begin(), leaving.end(), s.ids[static_cast<std::size_t>(i)]) == leaving.end())
      for (int j = 0; j < 3; ++j)
        rows.push_back(3 * i + j);
  const Eigen::MatrixXd G = pick(s.E, rows, zc) * T;
  const Eigen::MatrixXd EK = pick(s.E, rows, kc) - G * TtHzK;
  const Eigen::VectorXd bK = pick(s.b, rows, one) - G * Ttgz;
  // The directions kept: the leading right singular vectors of G with each feature's rows in units of
  // its own information (A_i^-1/2 G_i), so that a dropped direction's part of the feature-feature term
  // is at most kAuxTolerance of any feature's own information.
  Eigen::MatrixXd GtG = Eigen::MatrixXd::Zero(G.cols(), G.cols());
  for (std::size_t k = 0; G.cols() > 0 && k < rows.size(); k += 3) {
    const Eigen::MatrixXd Ti = pseudoInverseFactor(Eigen::Matrix3d(s.A.middleRows<3>(rows[k])));
    const Eigen::MatrixXd Gi = Ti.transpose() * G.middleRows(static_cast<Eigen::Index>(k), 3);
    GtG.noalias() += Gi.transpose() * Gi;
  }
  const bool correlated = o.noise.pixel_correlation > 0;
  const Eigen::MatrixXd Gr = G * leadingDirections(GtG, correlated ? kAuxToleranceCorrelated : kAuxTolerance,
                                                   correlated ? kMaxAuxCorrelated : kMaxAux);
  // The new prior.
  const int nK = static_cast<int>(kc.size()), r = static_cast<int>(Gr.cols());
  prior.frames = kept_frames;
  prior.aux = r;
  prior.a.setZero(r);
  prior.C.setZero(nK + r, nK + r);
  prior.C.topLeftCorner(nK, nK) = pick(s.H, kc, kc) - TtHzK.transpose() * TtHzK;
  prior.C.bottomRightCorner(r, r).setIdentity();
  prior.gy.setZero(nK + r);
  prior.gy.head(nK) = pick(s.g, kc, one) - TtHzK.transpose() * Ttgz;
  for (std::size_t k = 0; k < rows.size(); k += 3) {
    Feature &ft = features.at(s.ids[static_cast<std::size_t>(rows[k] / 3)]);
    const Eigen::Index row = static_cast<Eigen::Index>(k);
    ft.in_prior = true;
    std::copy(ft.p, ft.p + 3, ft.x0);
    ft.D = s.A.middleRows<3>(rows[k]);
    ft.gp = bK.segment<3>(row);
    ft.B.resize(3, nK + r); // (a block of a matrix without columns has no data: not taken)
    if (nK > 0)
      ft.B.leftCols(nK) = EK.middleRows<3>(row);
    if (r > 0)
      ft.B.rightCols(r) = Gr.middleRows<3>(row);
  }
}

/* The pair factors of frame0's observations are in the prior now: each chain's link moves to the
   successor (window_impl.h's Feature::chain_frame); a chain that ends there starts anew. */
void Impl::advanceChains(long frame0)
{
  for (auto &kv : features) {
    Feature &ft = kv.second;
    if (o.noise.pixel_correlation <= 0 || !ft.in_state || frame0 < ft.chain_frame)
      continue;
    const auto at = std::find_if(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame == frame0; });
    if (at == ft.obs.end() || at->outlier)
      continue; // nothing of its chain left with frame0
    const Obs *next = chainSuccessor(ft, frame0);
    ft.chain_frame = next ? next->frame : kNoChain;
  }
}

/* Observations of the oldest frame leave the window: their flags are final; the gates remember them. */
void Impl::retireObservations(long frame0)
{
  const Frame &f0 = frames.front();
  for (auto &kv : features) {
    Feature &ft = kv.second;
    for (const Obs &ob : ft.obs) {
      if (ob.frame != frame0)
        continue;
      ft.young = false;
      if (ob.outlier) {
        rejected.insert({ft.id, frame0});
        ++ft.old_outliers;
        continue;
      }
      if (!ft.in_state)
        continue;
      const Eigen::Vector3d ray = f0.cam.R * Eigen::Vector3d(ob.w.m[0], ob.w.m[1], 1.0);
      ft.last_centre = f0.cam.c;
      if (!ft.has_first) {
        ft.has_first = true;
        ft.first_ray = ray;
        ft.first_centre = f0.cam.c;
      } else {
        ft.old_parallax = std::max(ft.old_parallax, parallaxPx(ft.first_ray, f0, ob));
      }
      ++ft.old_inliers;
    }
    ft.obs.erase(std::remove_if(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame == frame0; }),
                 ft.obs.end());
  }
}

/* Drop the oldest frame (and the features no later window frame saw) into the prior. The state's
   last factorisation stays valid for the remaining variables: the marginal covariance of what is
   kept is the same with the dropped variables in the system or eliminated. */
void Impl::marginaliseOldest()
{
  const long frame0 = frames.front().row.frame;
  const std::vector<long> leaving = leavingFeatures(frame0);
  if (!leaving.empty())
    ensureCache();
  for (long id : leaving)
    finished[id] = cache.at(id);
  setFirstEstimates(frame0);
  SchurSystem blanket;
  blanketLayout(blanket);
  linearizeOldest(blanket);
  eliminateFeatures(blanket, leaving);
  condensePrior(blanket, leaving);
  advanceChains(frame0);
  retireObservations(frame0);
  for (long id : leaving)
    features.erase(id);
  for (auto it = features.begin(); it != features.end();)
    it = it->second.obs.empty() && !it->second.in_state ? features.erase(it) : std::next(it);
  frames.pop_front();
  cache_valid = false;
}

} // namespace yawdepth
