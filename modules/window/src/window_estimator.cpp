// WindowEstimator: the sliding-window smoother (Eigen only, no Ceres). See window_estimator.h.
#include "information.h"
#include "window_model.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <yawdepth/error.h>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

using namespace refine_detail;

namespace {

using window_detail::kFrameDim; // x, y, z, dx, dy, dz, yaw
constexpr double kMaxInvSigma = 1e6;       // 1 um, 1 urad: a component this certain is still estimated


double clampInv(double sigma) { return sigma > 0 ? std::min(1.0 / sigma, kMaxInvSigma) : kMaxInvSigma; }

} // namespace

void WindowOptions::validate() const
{
  noise.validate();
  gates.validate();
  if (window < 2)
    throw Error("window estimator: the window must hold at least 2 frames (got " + std::to_string(window) + ")");
  if (!(noise.sigma_px >= kMinSigmaPx))
    throw Error("window estimator: the pixel noise must be at least 1e-6 px (it weighs every observation)");
  auto positive = [](double v, const char *what) {
    if (!(std::isfinite(v) && v > 0))
      throw Error(std::string("window estimator: ") + what + " must be finite and positive");
  };
  positive(robust_threshold_px, "robust_threshold_px");
  positive(outlier_threshold_px, "outlier_threshold_px");
  positive(prior_sigma_inverse_depth, "prior_sigma_inverse_depth");
  positive(convergence, "convergence");
  if (!std::isfinite(prior_inverse_depth))
    throw Error("window estimator: prior_inverse_depth must be finite");
  if (max_iterations < 1)
    throw Error("window estimator: max_iterations must be at least 1");
}

struct WindowEstimator::Impl {
  // ---- Types.
  struct Frame {
    MotionSample row;
    Eigen::Matrix3d Rref = Eigen::Matrix3d::Identity();
    double x[kFrameDim] = {0, 0, 0, 0, 0, 0, 0};
    bool gauge = false; // pose held (the first frame, increment noise)
    OdometryMeasurementGeneral from_prev;   // the measured increment from the previous row (if any)
    int local[kFrameDim] = {-1, -1, -1, -1, -1, -1, -1}; // index of each parameter among the free ones, or -1
    int dim = 0;                            // free parameters
    bool has_fej = false;                   // in the prior: Jacobians at its first estimate there
    double x_fej[kFrameDim] = {0, 0, 0, 0, 0, 0, 0};
    window_detail::CameraPose cam; // the camera at x, and its derivatives (refreshCamera())
  };
  struct Obs {
    long frame = 0;
    WhitenedObservation w;
    bool outlier = false;
  };
  struct Feature {
    long id = 0;
    bool in_state = false;
    Eigen::Matrix3d Ra = Eigen::Matrix3d::Identity(); // fixed anchor (a constant)
    Eigen::Vector3d ca = Eigen::Vector3d::Zero();
    double p[3] = {0, 0, 0}; // alpha, beta, rho
    std::vector<Obs> obs;    // observations in window frames, by frame
    long last_frame = 0;     // frame of the last observation (any flag)
    bool undistort_failed = false;
    bool young = true;       // none of its observations has been marginalised
    bool has_fej = false;    // an observation was marginalised: Jacobians at the estimate of then
    double p_fej[3] = {0, 0, 0};
    // Gate memory of marginalised inlier observations.
    int old_inliers = 0, old_outliers = 0;
    bool has_first = false;
    Eigen::Vector3d first_ray = Eigen::Vector3d::Zero(), first_centre = Eigen::Vector3d::Zero();
    Eigen::Vector3d last_centre = Eigen::Vector3d::Zero(); // of the last marginalised inlier
    double old_parallax = 0;
  };
  /* A variable of the dense prior: a frame (by frame number) or a feature (by id). */
  struct PriorVar {
    bool is_frame = false;
    long key = 0;
    int dim = 0;
    std::vector<double> x0; // linearisation point of its free components
  };
  /* Where each variable's free components sit in a dense system. */
  struct Layout {
    std::vector<int> frame_offset;      // per window frame (index in frames), -1 if absent
    std::vector<long> frame_numbers;    // the frames' numbers when the layout was made
    std::map<long, int> feature_offset; // by id
    int n = 0;
  };

  // ---- Data.
  CameraModel camera;
  YawRig rig;
  WindowOptions o;
  Mount mount;
  bool started = false, six_dof = false, absolute = false;
  bool poses_free = false, yaws_free = false;
  std::vector<int> pose_components; // free pose components (0..5) of a non-gauge frame
  std::deque<Frame> frames;
  std::map<long, Feature> features; // in the state or pending (seen once in the window)
  std::map<long, PointEstimate> finished;
  std::set<std::pair<long, long>> rejected; // (id, frame) flagged when its frame left the window
  std::vector<PriorVar> prior_vars;
  Eigen::MatrixXd Hp;
  Eigen::VectorXd gp;
  // Estimates of the state's features after the last frame (computed on demand).
  mutable bool cache_valid = false;
  mutable std::map<long, PointEstimate> cache;
  // Last solve.
  Layout layout;
  Eigen::LLT<Eigen::MatrixXd> llt;
  bool llt_ok = false;
  // Workspaces, kept between frames: the solves' sizes barely change from frame to frame, and a
  // fresh 150 kB matrix per solve (30 features, 10 frames) cost more in page faults than its
  // factorisation.
  struct Workspace {
    Eigen::MatrixXd H;
    Eigen::VectorXd g, g_new;
  };
  Workspace ws_state, ws_align, ws_marg; // the state's solves, the new frame's alignment, marginalisation
  Eigen::LLT<Eigen::MatrixXd> llt_align;
  double c_robust = 1;    // Cauchy scale in whitened units
  double c_outlier_sq = 4; // squared outlier threshold in whitened units

  Impl(const CameraModel &cam, const YawRig &r, const WindowOptions &opt) : camera(cam), rig(r), o(opt)
  {
    o.validate();
    mount.R0 = rig.cameraRotation();
    mount.t0 = rig.cameraOffset();
    c_robust = o.robust_threshold_px / o.noise.sigma_px;
    const double t = o.outlier_threshold_px / o.noise.sigma_px;
    c_outlier_sq = t * t;
  }

  // ---- Variables.
  std::vector<int> freeComponents(const Frame &f) const
  {
    std::vector<int> c;
    if (!f.gauge)
      c = pose_components;
    if (yaws_free)
      c.push_back(6);
    return c;
  }
  int frameIndex(long frame) const
  {
    const auto it = std::lower_bound(frames.begin(), frames.end(), frame,
                                     [](const Frame &f, long k) { return f.row.frame < k; });
    return it != frames.end() && it->row.frame == frame ? static_cast<int>(it - frames.begin()) : -1;
  }
  /* The free parameters of a frame, cached in it. */
  void setComponents(Frame &f) const
  {
    const std::vector<int> c = freeComponents(f);
    std::fill(f.local, f.local + kFrameDim, -1);
    for (std::size_t k = 0; k < c.size(); ++k)
      f.local[c[k]] = static_cast<int>(k);
    f.dim = static_cast<int>(c.size());
  }
  Layout stateLayout() const
  {
    Layout l;
    l.frame_offset.assign(frames.size(), -1);
    for (const Frame &f : frames)
      l.frame_numbers.push_back(f.row.frame);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const int d = frames[i].dim;
      if (d > 0) {
        l.frame_offset[i] = l.n;
        l.n += d;
      }
    }
    for (const auto &kv : features)
      if (kv.second.in_state) {
        l.feature_offset[kv.first] = l.n;
        l.n += 3;
      }
    return l;
  }

  // ---- Camera of a frame and its derivatives with respect to the 7 frame parameters.
  void refreshCamera(Frame &f) const { window_detail::cameraPose(f.x, f.Rref, mount, f.cam); }
  void refreshCameras()
  {
    for (Frame &f : frames)
      refreshCamera(f);
  }

  /* Whitened reprojection residual of an observation and, if J is given, its Jacobian (2 x 10:
     the frame's 7 parameters, then alpha, beta, rho). False when the point is behind the camera. */
  static bool observationResidual(const Feature &ft, const Frame &f, const Obs &ob, Eigen::Vector2d &r,
                                  Eigen::Matrix<double, 2, 10> *J)
  {
    return window_detail::observationResidual(ft.Ra, ft.ca, ft.p, f.cam, ob.w, r, J);
  }

  /* A frame at its first estimate in the prior (its camera and derivatives there). */
  Frame fejFrame(const Frame &f) const
  {
    Frame t = f;
    std::copy(f.x_fej, f.x_fej + kFrameDim, t.x);
    refreshCamera(t);
    return t;
  }

  // ---- Factors other than observations.
  OdometryMeasurementGeneral increment(const Frame &prev, const Frame &cur) const
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

  /* Accumulate a whitened residual r with Jacobian J over the given global columns (-1: not in the
     system) into H and g, with weight w. */
  template <int R, int C>
  static void accumulate(const Eigen::Matrix<double, R, 1> &r, const Eigen::Matrix<double, R, C> &J, const int *cols,
                         double w, Eigen::MatrixXd *H, Eigen::VectorXd &g)
  {
    // Coefficient-based products: Eigen's blocked GEMM (its default above a few rows) costs more
    // than it saves on these small fixed sizes.
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

  /* Column of frame parameter j (0..6) in a layout, or -1. */
  int frameColumn(const Layout &l, int fi, int j) const
  {
    if (fi < 0 || fi >= static_cast<int>(l.frame_offset.size()) || l.frame_offset[fi] < 0)
      return -1;
    const int k = frames[static_cast<std::size_t>(fi)].local[j];
    return k < 0 ? -1 : l.frame_offset[fi] + k;
  }

  enum class Phase { Robust, Inliers };

  /* Robust weight and cost of a squared whitened residual s. */
  double weightOf(double s, Phase phase) const
  {
    return phase == Phase::Robust ? 1.0 / (1.0 + s / (c_robust * c_robust)) : 1.0;
  }
  double costOf(double s, Phase phase) const
  {
    return phase == Phase::Robust ? 0.5 * c_robust * c_robust * std::log1p(s / (c_robust * c_robust)) : 0.5 * s;
  }

  /*
    Cost of the factors selected, and (if g) their gradient and (if H too) their Gauss-Newton
    information over layout l.
    only_frame: -1 for every factor; else only the factors that involve that window frame (index),
    and the prior with the oldest frame (0: marginalisation; the newest: its alignment).
  */
  double linearize(const Layout &l, Phase phase, int only_frame, Eigen::MatrixXd *H, Eigen::VectorXd *g) const
  {
    if (g) {
      g->setZero(l.n);
      if (H)
        H->setZero(l.n, l.n);
    }
    double cost = 0;
    // Column tables of the frames.
    std::vector<std::array<int, kFrameDim>> fcols(frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i)
      for (int j = 0; j < kFrameDim; ++j)
        fcols[i][j] = frameColumn(l, static_cast<int>(i), j);
    // First-estimate copies of the frames in the prior (their Jacobians are evaluated there, so that
    // every factor and the prior agree on them: the prior cannot gain information by relinearisation).
    std::map<int, Frame> fej;
    if (g)
      for (std::size_t i = 0; i < frames.size(); ++i)
        if (frames[i].has_fej)
          fej.emplace(static_cast<int>(i), fejFrame(frames[i]));

    // Observations.
    for (const auto &kv : features) {
      const Feature &ft = kv.second;
      if (!ft.in_state)
        continue;
      const auto fo = l.feature_offset.find(ft.id);
      const int pcol = fo == l.feature_offset.end() ? -1 : fo->second;
      for (const Obs &ob : ft.obs) {
        if (phase == Phase::Inliers && ob.outlier)
          continue;
        const int fi = frameIndex(ob.frame);
        if (only_frame >= 0 && fi != only_frame)
          continue;
        Eigen::Vector2d r;
        Eigen::Matrix<double, 2, 10> J;
        const auto fe = fej.find(fi);
        const bool first_estimate = g && (ft.has_fej || fe != fej.end());
        if (!observationResidual(ft, frames[fi], ob, r, g && !first_estimate ? &J : nullptr)) {
          cost += phase == Phase::Robust ? costOf(1e6, phase) : 0.0; // behind: a fixed penalty, no gradient
          continue;
        }
        const double s = r.squaredNorm();
        cost += costOf(s, phase);
        if (first_estimate) {
          Eigen::Vector2d r_fej;
          if (!window_detail::observationResidual(ft.Ra, ft.ca, ft.has_fej ? ft.p_fej : ft.p,
                                                  (fe != fej.end() ? fe->second : frames[fi]).cam, ob.w, r_fej, &J))
            observationResidual(ft, frames[fi], ob, r, &J);
        }
        if (g) {
          int cols[10];
          for (int j = 0; j < kFrameDim; ++j)
            cols[j] = fcols[fi][j];
          for (int j = 0; j < 3; ++j)
            cols[7 + j] = pcol < 0 ? -1 : pcol + j;
          accumulate<2, 10>(r, J, cols, weightOf(s, phase), H, *g);
        }
      }
    }
    // Motion: increments (or poses) and yaw readings.
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Frame &f = frames[i];
      const bool own = only_frame < 0 || static_cast<int>(i) == only_frame;
      const bool next = only_frame < 0 || static_cast<int>(i) + 1 == only_frame;
      if (yaws_free && own) {
        const double inv = clampInv(o.noise.sigma_yaw);
        Eigen::Matrix<double, 1, 1> r;
        r(0) = (f.x[6] - f.row.yaw) * inv;
        cost += 0.5 * r.squaredNorm();
        if (g) {
          Eigen::Matrix<double, 1, 1> J;
          J(0, 0) = inv;
          const int col = fcols[i][6];
          accumulate<1, 1>(r, J, &col, 1.0, H, *g);
        }
      }
      if (!poses_free)
        continue;
      if (absolute && own) {
        const Eigen::Vector3d sr = poseRotationSigma(o.noise, six_dof);
        Eigen::Matrix<double, 6, 1> r;
        Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
        const double it = clampInv(o.noise.sigma_odom);
        const double meas[3] = {f.row.x, f.row.y, f.row.z};
        for (int k = 0; k < 3; ++k) {
          J(k, k) = it;
          r(k) = (f.x[k] - meas[k]) * it;
          J(3 + k, 3 + k) = clampInv(sr(k));
          r(3 + k) = f.x[3 + k] * J(3 + k, 3 + k);
        }
        cost += 0.5 * r.squaredNorm();
        if (g)
          accumulate<6, 6>(r, J, fcols[i].data(), 1.0, H, *g);
      } else if (!absolute && (own || next) && i + 1 < frames.size()) {
        const Frame &n = frames[i + 1];
        const OdometryMeasurementGeneral &m = n.from_prev;
        Eigen::Matrix<double, 6, 1> r;
        window_detail::odometryResidual(f.x, f.cam, n.x, n.cam, m, r, nullptr);
        if (!g) {
          cost += 0.5 * r.squaredNorm();
          continue;
        }
        Eigen::Matrix<double, 6, 14> J;
        const auto fp = fej.find(static_cast<int>(i)), fn = fej.find(static_cast<int>(i) + 1);
        const Frame &jf = fp != fej.end() ? fp->second : f, &jn = fn != fej.end() ? fn->second : n;
        Eigen::Matrix<double, 6, 1> r_fej;
        window_detail::odometryResidual(jf.x, jf.cam, jn.x, jn.cam, m, r_fej, &J);
        cost += 0.5 * r.squaredNorm();
        if (g) {
          int cols[14];
          for (int j = 0; j < kFrameDim; ++j) {
            cols[j] = fcols[i][j];
            cols[kFrameDim + j] = fcols[i + 1][j];
          }
          accumulate<6, 14>(r, J, cols, 1.0, H, *g);
        }
      }
    }
    // The prior (marginalised frames, observations and the features' inverse-depth priors).
    if (!prior_vars.empty() && only_frame <= 0) {
      const Eigen::VectorXd dx = priorDelta();
      cost += gp.dot(dx) + 0.5 * dx.dot(Hp * dx);
      if (g) {
        const std::vector<int> cols = priorColumns(l);
        const Eigen::VectorXd grad = gp + Hp * dx;
        for (std::size_t a = 0; a < cols.size(); ++a) {
          if (cols[a] < 0)
            continue;
          (*g)(cols[a]) += grad(static_cast<Eigen::Index>(a));
          for (std::size_t b = 0; H && b < cols.size(); ++b)
            if (cols[b] >= 0)
              (*H)(cols[a], cols[b]) += Hp(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
        }
      }
    }
    return cost;
  }

  /* Current values of the prior's variables minus its linearisation point. */
  Eigen::VectorXd priorDelta() const
  {
    Eigen::VectorXd d(Hp.rows());
    int k = 0;
    for (const PriorVar &v : prior_vars) {
      if (v.is_frame) {
        const Frame &f = frames[static_cast<std::size_t>(frameIndex(v.key))];
        for (int j = 0; j < kFrameDim; ++j)
          if (f.local[j] >= 0)
            d(k + f.local[j]) = f.x[j] - v.x0[static_cast<std::size_t>(f.local[j])];
      } else {
        const Feature &ft = features.at(v.key);
        for (int j = 0; j < 3; ++j)
          d(k + j) = ft.p[j] - v.x0[static_cast<std::size_t>(j)];
      }
      k += v.dim;
    }
    return d;
  }
  /* Global column of each prior component in layout l (-1 when absent). */
  std::vector<int> priorColumns(const Layout &l) const
  {
    std::vector<int> cols;
    for (const PriorVar &v : prior_vars) {
      int off = -1;
      if (v.is_frame) {
        const int fi = frameIndex(v.key);
        off = fi >= 0 && fi < static_cast<int>(l.frame_offset.size()) ? l.frame_offset[fi] : -1;
      } else {
        const auto it = l.feature_offset.find(v.key);
        off = it == l.feature_offset.end() ? -1 : it->second;
      }
      for (int j = 0; j < v.dim; ++j)
        cols.push_back(off < 0 ? -1 : off + j);
    }
    return cols;
  }

  // ---- Solve.
  void applyStep(const Layout &l, const Eigen::VectorXd &dx, double scale)
  {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (l.frame_offset[i] < 0)
        continue;
      Frame &f = frames[i];
      for (int j = 0; j < kFrameDim; ++j)
        if (f.local[j] >= 0)
          f.x[j] += scale * dx(l.frame_offset[i] + f.local[j]);
      refreshCamera(f);
    }
    for (const auto &kv : l.feature_offset) {
      Feature &ft = features.at(kv.first);
      for (int j = 0; j < 3; ++j)
        ft.p[j] += scale * dx(kv.second + j);
    }
  }
  struct Saved {
    std::vector<std::array<double, kFrameDim>> frames;
    std::map<long, std::array<double, 3>> points;
  };
  Saved save() const
  {
    Saved s;
    for (const Frame &f : frames) {
      std::array<double, kFrameDim> a;
      std::copy(f.x, f.x + kFrameDim, a.begin());
      s.frames.push_back(a);
    }
    for (const auto &kv : features)
      if (kv.second.in_state)
        s.points[kv.first] = {kv.second.p[0], kv.second.p[1], kv.second.p[2]};
    return s;
  }
  void restore(const Saved &s)
  {
    for (std::size_t i = 0; i < frames.size(); ++i)
      std::copy(s.frames[i].begin(), s.frames[i].end(), frames[i].x);
    for (const auto &kv : s.points)
      std::copy(kv.second.begin(), kv.second.end(), features.at(kv.first).p);
    refreshCameras();
  }

  /*
    Gauss-Newton with step halving over layout l (the state, or a part of it; only_frame as for
    linearize()). After each step the gradient at the new point and the last factorisation predict
    what another iteration would gain; below options.convergence the solve stops (the remainder is carried
    into the next frame's solve, or into the prior exactly, with its gradient). Returns the
    factorisations made; `L` keeps the last one and `L_ok` says whether it holds one.
  */
  int gaussNewton(const Layout &l, Phase phase, int only_frame, Workspace &ws, Eigen::LLT<Eigen::MatrixXd> &L,
                  bool &L_ok)
  {
    L_ok = false;
    if (l.n == 0)
      return 0;
    Eigen::MatrixXd &H = ws.H;
    Eigen::VectorXd &g = ws.g;
    Eigen::VectorXd &g_new = ws.g_new;
    int factorisations = 0;
    bool refactor = true; // false: a chord step, with the last factorisation and the new gradient
    int chords = 0;
    double cost = linearize(l, phase, only_frame, &H, &g);
    for (int it = 0; it < o.max_iterations + 2; ++it) {
      if (refactor) {
        if (it > 0)
          cost = linearize(l, phase, only_frame, &H, &g);
        L.compute(H);
        ++factorisations;
        if (L.info() != Eigen::Success) {
          // A direction without information (the priors should prevent it): damp it.
          H.diagonal() += 1e-9 * H.diagonal().cwiseAbs() + Eigen::VectorXd::Constant(l.n, 1e-12);
          L.compute(H);
          if (L.info() != Eigen::Success)
            return factorisations;
        }
        L_ok = true;
      }
      const Eigen::VectorXd dx = L.solve(-g);
      if (!dx.allFinite())
        return factorisations;
      const double predicted = -0.5 * g.dot(dx);
      const Saved s = save();
      double scale = 1.0;
      bool accepted = false;
      for (int h = 0; h < (refactor ? 6 : 1); ++h, scale *= 0.5) {
        applyStep(l, dx, scale);
        // The full step usually holds: its gradient comes with its cost, for the next prediction.
        const double c = linearize(l, phase, only_frame, nullptr, h == 0 ? &g_new : nullptr);
        // A chord step must deliver most of what it promised; a full step only has to descend.
        if (std::isfinite(c) && c <= cost - (refactor ? 0.0 : 0.5 * predicted) + 1e-12 * std::abs(cost)) {
          accepted = true;
          cost = c;
          if (h > 0)
            linearize(l, phase, only_frame, nullptr, &g_new);
          break;
        }
        restore(s);
      }
      if (!accepted) {
        if (refactor)
          break;
        refactor = true; // the chord went astray: linearise afresh
        continue;
      }
      // What would the next step gain? 0.5 g^T H^-1 g with the new gradient and the last factorisation.
      g.swap(g_new);
      const double next = 0.5 * g.dot(L.solve(g));
      if (next < o.convergence || factorisations >= o.max_iterations)
        break;
      // Cheap chord steps while the last factorisation still predicts fast progress (the remainder
      // shrank at least fourfold); else a full iteration.
      refactor = !(chords < 2 && next < 0.25 * predicted);
      chords += refactor ? 0 : 1;
    }
    return factorisations;
  }

  /* Gauss-Newton on the whole state; the layout and factorisation are kept for the covariances. */
  int solve(Phase phase)
  {
    layout = stateLayout();
    return gaussNewton(layout, phase, -1, ws_state, llt, llt_ok);
  }

  /* The new frame alone against the state (a 7-parameter solve): a start that the full solve
     then refines in one or two iterations. */
  void alignNewFrame()
  {
    Layout l;
    l.frame_offset.assign(frames.size(), -1);
    for (const Frame &f : frames)
      l.frame_numbers.push_back(f.row.frame);
    const int d = static_cast<int>(freeComponents(frames.back()).size());
    if (d == 0 || frames.size() < 2)
      return;
    l.frame_offset.back() = 0;
    l.n = d;
    bool aligned = false;
    gaussNewton(l, Phase::Robust, static_cast<int>(frames.size()) - 1, ws_align, llt_align, aligned);
    llt_ok = false; // the state's last factorisation no longer matches it (a new frame)
  }

  /* Flag every observation of the state's features by its reprojection error; true if a flag changed. */
  bool flagOutliers()
  {
    bool changed = false;
    for (auto &kv : features) {
      Feature &ft = kv.second;
      if (!ft.in_state)
        continue;
      for (Obs &ob : ft.obs) {
        Eigen::Vector2d r;
        const bool front = observationResidual(ft, frames[static_cast<std::size_t>(frameIndex(ob.frame))], ob, r, nullptr);
        const bool outlier = !front || r.squaredNorm() > c_outlier_sq;
        changed = changed || outlier != ob.outlier;
        ob.outlier = outlier;
      }
    }
    return changed;
  }

  // ---- Features.
  /* Triangulate from two observations (midpoint of the common perpendicular); false if not in front. */
  bool triangulate(const Obs &a, const Obs &b, Eigen::Vector3d &P) const
  {
    const Frame &fa = frames.at(static_cast<std::size_t>(frameIndex(a.frame)));
    const Frame &fb = frames.at(static_cast<std::size_t>(frameIndex(b.frame)));
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
  static bool anchorParameters(const Feature &ft, const Eigen::Vector3d &P, double *p)
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
  double featureCost(Feature &ft, const double *p) const
  {
    double saved[3];
    std::copy(ft.p, ft.p + 3, saved);
    std::copy(p, p + 3, ft.p);
    double cost = 0;
    for (const Obs &ob : ft.obs) {
      Eigen::Vector2d r;
      const bool front = observationResidual(ft, frames.at(static_cast<std::size_t>(frameIndex(ob.frame))), ob, r, nullptr);
      cost += costOf(front ? r.squaredNorm() : 1e6, Phase::Robust);
    }
    std::copy(saved, saved + 3, ft.p);
    return cost;
  }
  /* Start (or restart) a feature's point from the best two-view pair of its observations. */
  /* A few robust Gauss-Newton iterations on a feature's point alone (the poses held), from p. */
  void refinePointAlone(const Feature &ft, double *p) const
  {
    for (int it = 0; it < 6; ++it) {
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      for (const Obs &ob : ft.obs) {
        Eigen::Vector2d r;
        Eigen::Matrix<double, 2, 10> J;
        const Frame &f = frames[static_cast<std::size_t>(frameIndex(ob.frame))];
        if (!window_detail::observationResidual(ft.Ra, ft.ca, p, f.cam, ob.w, r, &J))
          continue;
        const double w = weightOf(r.squaredNorm(), Phase::Robust);
        const Eigen::Matrix<double, 2, 3> Jp = J.rightCols<3>();
        H += w * Jp.transpose() * Jp;
        g += w * Jp.transpose() * r;
      }
      const double info = 1.0 / (o.prior_sigma_inverse_depth * o.prior_sigma_inverse_depth);
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
  void initialisePoint(Feature &ft, bool keep_current)
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
      const Frame &fi = frames[static_cast<std::size_t>(frameIndex(oi.frame))];
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
  void enterState(Feature &ft)
  {
    const Frame &fa = frames.at(static_cast<std::size_t>(frameIndex(ft.obs.front().frame)));
    ft.Ra = fa.cam.R;
    ft.ca = fa.cam.c;
    ft.p[0] = ft.obs.front().w.m[0];
    ft.p[1] = ft.obs.front().w.m[1];
    ft.p[2] = o.prior_inverse_depth;
    initialisePoint(ft, false);
    ft.in_state = true;
    // The weak inverse-depth prior joins the dense prior (it is linear: exact at any point).
    PriorVar v;
    v.key = ft.id;
    v.dim = 3;
    v.x0.assign(ft.p, ft.p + 3);
    const Eigen::Index n = Hp.rows();
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n + 3, n + 3);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n + 3);
    H.topLeftCorner(n, n) = Hp;
    g.head(n) = gp;
    const double info = 1.0 / (o.prior_sigma_inverse_depth * o.prior_sigma_inverse_depth);
    H(n + 2, n + 2) = info;
    g(n + 2) = info * (ft.p[2] - o.prior_inverse_depth);
    Hp = std::move(H);
    gp = std::move(g);
    prior_vars.push_back(v);
  }

  // ---- Marginalisation.
  /* Schur-complement the prior components in `drop` (indices into the stacked prior) out of (H, g). */
  static void schur(Eigen::MatrixXd &H, Eigen::VectorXd &g, const std::vector<int> &drop)
  {
    const int n = static_cast<int>(H.rows());
    std::vector<char> is_drop(static_cast<std::size_t>(n), 0);
    for (int d : drop)
      is_drop[static_cast<std::size_t>(d)] = 1;
    std::vector<int> keep;
    for (int i = 0; i < n; ++i)
      if (!is_drop[static_cast<std::size_t>(i)])
        keep.push_back(i);
    const int m = static_cast<int>(drop.size()), k = static_cast<int>(keep.size());
    Eigen::MatrixXd Hmm(m, m), Hkm(k, m), Hkk(k, k);
    Eigen::VectorXd gm(m), gk(k);
    for (int a = 0; a < m; ++a) {
      gm(a) = g(drop[a]);
      for (int b = 0; b < m; ++b)
        Hmm(a, b) = H(drop[a], drop[b]);
    }
    for (int a = 0; a < k; ++a) {
      gk(a) = g(keep[a]);
      for (int b = 0; b < m; ++b)
        Hkm(a, b) = H(keep[a], drop[b]);
      for (int b = 0; b < k; ++b)
        Hkk(a, b) = H(keep[a], keep[b]);
    }
    if (m > 0) {
      // A pseudo-inverse of the dropped block: directions without information carry none.
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Hmm + Hmm.transpose()));
      const Eigen::VectorXd &ev = es.eigenvalues();
      const double tol = 1e-12 * std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
      Eigen::VectorXd inv(m);
      for (int i = 0; i < m; ++i)
        inv(i) = ev(i) > tol ? 1.0 / ev(i) : 0.0;
      const Eigen::MatrixXd Hinv = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
      Hkk -= Hkm * Hinv * Hkm.transpose();
      gk -= Hkm * (Hinv * gm);
    }
    H = 0.5 * (Hkk + Hkk.transpose());
    g = gk;
  }

  /* Schur-complement out of (H, g), whose rows are `vars` stacked in order, the variables for which
     gone(v) holds; returns the others, in order. */
  template <typename Gone>
  static std::vector<PriorVar> schurOut(Eigen::MatrixXd &H, Eigen::VectorXd &g, const std::vector<PriorVar> &vars,
                                        Gone gone)
  {
    std::vector<int> drop;
    std::vector<PriorVar> kept;
    int off = 0;
    for (const PriorVar &v : vars) {
      const bool out = gone(v);
      for (int j = 0; j < v.dim; ++j)
        if (out)
          drop.push_back(off + j);
      if (!out)
        kept.push_back(v);
      off += v.dim;
    }
    schur(H, g, drop);
    return kept;
  }

  /* Drop the oldest frame (and the features no later window frame saw) into the prior. */
  void marginaliseOldest()
  {
    Frame &f0 = frames.front();
    const long frame0 = f0.row.frame;
    // Features leaving with this frame: in the state, no observation in a later window frame.
    std::vector<long> leaving;
    for (auto &kv : features) {
      Feature &ft = kv.second;
      const bool later = std::any_of(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame != frame0; });
      if (ft.in_state && !later)
        leaving.push_back(kv.first);
    }
    if (!leaving.empty())
      ensureCache();
    for (long id : leaving)
      finished[id] = cache.at(id);

    // The blanket system: every variable of the prior, the oldest frame, the frame after it, and
    // every feature observed in the oldest frame; the factors touching the oldest frame, and the prior.
    Layout l;
    l.frame_offset.assign(frames.size(), -1);
    for (const Frame &f : frames)
      l.frame_numbers.push_back(f.row.frame);
    std::vector<PriorVar> vars;
    auto addFrameVar = [&](int fi) {
      if (l.frame_offset[static_cast<std::size_t>(fi)] >= 0)
        return;
      const std::vector<int> comps = freeComponents(frames[static_cast<std::size_t>(fi)]);
      if (comps.empty())
        return;
      l.frame_offset[static_cast<std::size_t>(fi)] = l.n;
      PriorVar v;
      v.is_frame = true;
      v.key = frames[static_cast<std::size_t>(fi)].row.frame;
      v.dim = static_cast<int>(comps.size());
      for (int c : comps)
        v.x0.push_back(frames[static_cast<std::size_t>(fi)].x[c]);
      vars.push_back(v);
      l.n += v.dim;
    };
    auto addFeatureVar = [&](long id) {
      if (l.feature_offset.count(id))
        return;
      l.feature_offset[id] = l.n;
      PriorVar v;
      v.key = id;
      v.dim = 3;
      const Feature &ft = features.at(id);
      v.x0.assign(ft.p, ft.p + 3);
      vars.push_back(v);
      l.n += 3;
    };
    addFrameVar(0);
    if (frames.size() > 1 && !absolute)
      addFrameVar(1);
    for (const PriorVar &v : prior_vars) {
      if (v.is_frame)
        addFrameVar(frameIndex(v.key));
      else
        addFeatureVar(v.key);
    }
    for (const auto &kv : features)
      if (kv.second.in_state)
        for (const Obs &ob : kv.second.obs)
          if (ob.frame == frame0 && !ob.outlier)
            addFeatureVar(kv.first);
    // Variables that join the prior's non-trivial part now keep their current value as the point
    // where every later Jacobian of theirs is evaluated.
    for (int fi = 0; fi < (absolute ? 1 : 2) && fi < static_cast<int>(frames.size()); ++fi) // per-pose noise: no link to the next frame
      if (!frames[static_cast<std::size_t>(fi)].has_fej) {
        Frame &f = frames[static_cast<std::size_t>(fi)];
        f.has_fej = true;
        std::copy(f.x, f.x + kFrameDim, f.x_fej);
      }
    for (auto &kv : features) {
      Feature &ft = kv.second;
      if (!ft.in_state || ft.has_fej)
        continue;
      if (std::any_of(ft.obs.begin(), ft.obs.end(), [&](const Obs &ob) { return ob.frame == frame0 && !ob.outlier; })) {
        ft.has_fej = true;
        std::copy(ft.p, ft.p + 3, ft.p_fej);
      }
    }
    Eigen::MatrixXd &H = ws_marg.H;
    Eigen::VectorXd &g = ws_marg.g;
    linearize(l, Phase::Inliers, 0, &H, &g);

    // Drop the oldest frame's components and the leaving features'.
    prior_vars = schurOut(H, g, vars, [&](const PriorVar &v) {
      return (v.is_frame && v.key == frame0) ||
             (!v.is_frame && std::find(leaving.begin(), leaving.end(), v.key) != leaving.end());
    });
    Hp.swap(H); // the old prior's storage is the next blanket system's
    gp.swap(g);

    // Observations of the oldest frame leave the window: their flags are final; gates remember them.
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
    for (long id : leaving)
      features.erase(id);
    for (auto it = features.begin(); it != features.end();)
      it = it->second.obs.empty() && !it->second.in_state ? features.erase(it) : std::next(it);
    frames.pop_front();
    cache_valid = false;
    // The last factorisation stays valid for the remaining variables: the marginal covariance of
    // what is kept is the same with the dropped variables in the system or Schur-complemented out.
  }

  /* Rotation-compensated parallax (px) of an observation against a world ray. */
  double parallaxPx(const Eigen::Vector3d &ray_w, const Frame &f, const Obs &ob) const
  {
    const Eigen::Vector3d q = f.cam.R.transpose() * ray_w;
    if (!(q.z() > 0))
      return std::numeric_limits<double>::infinity(); // the point at infinity is behind: all parallax
    return std::hypot(camera.kx() * (q.x() / q.z() - ob.w.m[0]), camera.ky() * (q.y() / q.z() - ob.w.m[1]));
  }

  // ---- Estimates.
  /*
    The feature's estimate. With Jt_out (and a factorisation), its status is provisional: the point's
    Jacobian over the state goes into columns jt_col..jt_col+2 for ensureCache() to give it its
    covariance and depth gate; for a point at non-positive inverse depth, the unit column of that
    inverse depth goes into jt_col and *rho_column is set, for the gate that tells `behind` from
    an unresolved depth.
  */
  PointEstimate estimateOf(const Feature &ft, Eigen::MatrixXd *Jt_out = nullptr, int jt_col = 0,
                           bool *rho_column = nullptr) const
  {
    PointEstimate e;
    e.frame = ft.last_frame;
    if (ft.undistort_failed && !ft.in_state) {
      e.status = Status::UndistortFailed;
      return e;
    }
    if (!ft.in_state) {
      e.status = Status::TooFewFrames;
      return e;
    }
    const int fl = frameIndex(ft.last_frame);
    if (fl < 0) { // cannot happen: a feature in the state has its last observation in the window
      e.status = Status::TooFewFrames;
      return e;
    }
    // Gates on the inlier observations.
    int inliers = ft.old_inliers, outliers = ft.old_outliers;
    bool has_first = ft.has_first;
    Eigen::Vector3d first_ray = ft.first_ray, first_centre = ft.first_centre, last_centre = ft.last_centre;
    double parallax = ft.old_parallax;
    bool behind = false;
    for (const Obs &ob : ft.obs) {
      if (ob.outlier) {
        ++outliers;
        continue;
      }
      const Frame &f = frames[static_cast<std::size_t>(frameIndex(ob.frame))];
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
    {
      Obs last;
      last.frame = ft.last_frame;
      behind = behind || !observationResidual(ft, frames[static_cast<std::size_t>(fl)], last, r_last, nullptr);
    }
    e.parallax_px = parallax;
    // Two observations always agree on a point: with an outlier among them, two inliers cannot
    // tell which were the outliers.
    if (inliers < 2 || (outliers > 0 && inliers < 3)) {
      e.status = Status::TooFewFrames;
      return e;
    }
    if ((last_centre - first_centre).norm() < o.gates.min_baseline) {
      e.status = Status::NoMotion;
      return e;
    }
    if (parallax < o.gates.min_parallax_px) {
      e.status = Status::Degenerate;
      return e;
    }
    if (behind) {
      e.status = Status::Behind;
      return e;
    }
    // The point at the last frame, and its Jacobian over (frame 7, point 3).
    const Frame &f = frames[static_cast<std::size_t>(fl)];
    const Eigen::Vector3d m(ft.p[0], ft.p[1], 1.0);
    const double rho = ft.p[2];
    const Eigen::Vector3d dca = ft.ca - f.cam.c;
    const Eigen::Vector3d u = ft.Ra * m + rho * dca;
    const Eigen::Vector3d q = f.cam.R.transpose() * u;
    if (!(rho > 0)) {
      e.status = Status::Behind;
      const auto it = layout.feature_offset.find(ft.id);
      if (Jt_out && llt_ok && rho_column && it != layout.feature_offset.end()) {
        (*Jt_out)(it->second + 2, jt_col) = 1.0;
        *rho_column = true;
      }
      return e;
    }
    e.c_P = q / rho;
    e.v_P = rig.visionPoint(f.x[6], e.c_P);
    if (Jt_out && llt_ok) {
      Eigen::Matrix<double, 3, 10> Jq;
      for (int j = 0; j < kFrameDim; ++j)
        Jq.col(j) = f.cam.dR[j].transpose() * u - rho * (f.cam.R.transpose() * f.cam.dc[j]);
      Jq.col(7) = f.cam.R.transpose() * ft.Ra.col(0);
      Jq.col(8) = f.cam.R.transpose() * ft.Ra.col(1);
      Jq.col(9) = f.cam.R.transpose() * dca;
      Eigen::Matrix<double, 3, 10> J = Jq / rho;
      J.col(9) -= q / (rho * rho);
      const auto li = std::find(layout.frame_numbers.begin(), layout.frame_numbers.end(), f.row.frame);
      const int off = li == layout.frame_numbers.end()
                          ? -1
                          : layout.frame_offset[static_cast<std::size_t>(li - layout.frame_numbers.begin())];
      if (off >= 0) {
        const std::vector<int> comps = freeComponents(f);
        for (std::size_t k = 0; k < comps.size(); ++k)
          Jt_out->block<1, 3>(off + static_cast<int>(k), jt_col) += J.col(comps[k]).transpose();
      }
      const auto it = layout.feature_offset.find(ft.id);
      if (it != layout.feature_offset.end())
        for (int j = 0; j < 3; ++j)
          Jt_out->block<1, 3>(it->second + j, jt_col) += J.col(7 + j).transpose();
      e.status = Status::Ok; // the covariance is filled by the caller
    } else {
      e.status = Status::Degenerate; // no information to give it a covariance
    }
    return e;
  }

  /* Every state feature's estimate, with the covariances from one triangular solve. */
  void ensureCache() const
  {
    if (cache_valid)
      return;
    cache.clear();
    std::vector<long> ids;
    for (const auto &kv : features)
      if (kv.second.in_state)
        ids.push_back(kv.first);
    Eigen::MatrixXd Jt = Eigen::MatrixXd::Zero(layout.n, 3 * static_cast<Eigen::Index>(ids.size()));
    std::vector<int> col(ids.size(), -1);
    std::vector<char> rho_only(ids.size(), 0);
    for (std::size_t i = 0; i < ids.size(); ++i) {
      bool rho_column = false;
      PointEstimate e = estimateOf(features.at(ids[i]), &Jt, 3 * static_cast<int>(i), &rho_column);
      if (e.ok() || rho_column)
        col[i] = 3 * static_cast<int>(i);
      rho_only[i] = rho_column ? 1 : 0;
      cache[ids[i]] = e;
    }
    if (llt_ok && Jt.cols() > 0) {
      llt.matrixL().solveInPlace(Jt);
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (col[i] < 0)
          continue;
        PointEstimate &e = cache[ids[i]];
        if (rho_only[i]) {
          // Beyond infinity: behind the camera only if the inverse depth's 2-sigma range stays
          // below zero; else the depth is not resolved.
          const double sigma_rho = Jt.col(col[i]).norm();
          if (features.at(ids[i]).p[2] + 2.0 * sigma_rho > 0)
            e.status = Status::Degenerate;
          continue;
        }
        const auto X = Jt.middleCols<3>(col[i]);
        e.c_cov = X.transpose() * X;
        // As `fused`: a depth without a bounded 2-sigma interval is not a measurement.
        if (!e.c_cov.allFinite() || !std::isfinite(inverseDepthInterval(std::sqrt(e.c_cov(2, 2)) / e.c_P.z())))
          e.status = Status::Degenerate;
      }
    }
    cache_valid = true;
  }

  // ---- A frame.
  std::vector<ObservationResult> addFrame(const MotionSample &row, const std::vector<FeatureObservation> &observations)
  {
    if (started) {
      if (!(row.frame > frames.back().row.frame))
        throw Error("window estimator: frame " + std::to_string(row.frame) + " after frame " +
                    std::to_string(frames.back().row.frame) + " (frames must increase)");
      if (row.six_dof != six_dof)
        throw Error("window estimator: a motion log must be all planar or all 6-DoF rows");
    }
    for (std::size_t i = 0; i < observations.size(); ++i)
      for (std::size_t j = i + 1; j < observations.size(); ++j)
        if (observations[i].id == observations[j].id)
          throw Error("window estimator: feature " + std::to_string(observations[i].id) + " observed twice in frame " +
                      std::to_string(row.frame));
    Frame f;
    f.row = row;
    f.Rref = row.rotation();
    f.x[6] = row.yaw;
    if (!started) {
      started = true;
      six_dof = row.six_dof;
      absolute = o.noise.motion_noise == MotionNoise::Absolute;
      const Eigen::Vector3d sr = incrementRotationSigma(o.noise, six_dof, 1.0, 1.0);
      poses_free = incrementTranslationSigma(o.noise, 1.0) > 0 || sr.maxCoeff() > 0 ||
                   (absolute && (o.noise.sigma_odom > 0 || poseRotationSigma(o.noise, six_dof).maxCoeff() > 0));
      yaws_free = o.noise.sigma_yaw > 0;
      pose_components.clear();
      if (poses_free) {
        pose_components = {0, 1, 2};
        if (six_dof)
          pose_components.insert(pose_components.end(), {3, 4, 5});
        else
          pose_components.push_back(4);
      }
      f.gauge = !absolute;
      f.x[0] = row.x;
      f.x[1] = row.y;
      f.x[2] = row.z;
    } else if (absolute) {
      f.x[0] = row.x;
      f.x[1] = row.y;
      f.x[2] = row.z;
    } else {
      // Dead reckoning from the previous frame's estimate.
      const Frame &p = frames.back();
      const Eigen::Matrix3d Vp = p.Rref * expSO3<double>(Eigen::Vector3d(p.x[3], p.x[4], p.x[5]));
      const Eigen::Vector3d pos = Eigen::Vector3d(p.x[0], p.x[1], p.x[2]) +
                                  Vp * p.Rref.transpose() * (row.position() - p.row.position());
      const Eigen::Matrix3d V = Vp * p.Rref.transpose() * f.Rref;
      const Eigen::Vector3d d = logSO3(f.Rref.transpose() * V);
      for (int k = 0; k < 3; ++k) {
        f.x[k] = pos(k);
        f.x[3 + k] = d(k);
      }
      if (!six_dof) { // exactly a heading offset
        f.x[3] = 0;
        f.x[5] = 0;
      }
    }
    setComponents(f);
    if (!frames.empty())
      f.from_prev = increment(frames.back(), f);
    refreshCamera(f);
    frames.push_back(f);

    std::vector<ObservationResult> results;
    const double s2 = o.noise.sigma_px;
    for (const FeatureObservation &fo : observations) {
      ObservationResult res;
      res.id = fo.id;
      Eigen::Vector2d m;
      Eigen::Matrix2d J;
      Feature &ft = features[fo.id];
      ft.id = fo.id;
      ft.last_frame = row.frame;
      if (!std::isfinite(fo.u) || !std::isfinite(fo.v) || !camera.undistort(Eigen::Vector2d(fo.u, fo.v), m, &J)) {
        res.undistorted = false;
        res.inlier = false;
        ft.undistort_failed = true;
        results.push_back(res);
        continue;
      }
      Obs ob;
      ob.frame = row.frame;
      ob.w = whitenObservation(m, J, s2);
      ft.obs.push_back(ob);
      results.push_back(res);
    }
    // Features seen once or not at all this frame but without any window observation: forget.
    for (auto it = features.begin(); it != features.end();)
      it = it->second.obs.empty() && !it->second.in_state ? features.erase(it) : std::next(it);
    // A second observation brings a feature into the state.
    for (auto &kv : features)
      if (!kv.second.in_state && kv.second.obs.size() >= 2)
        enterState(kv.second);

    alignNewFrame();
    // Least squares on the inliers (a gross error barely moves the motion that 30 features pin
    // down, so it stands out after it); if any flag changes, the robust path.
    solve(Phase::Inliers);
    const bool suspicious = flagOutliers();
    if (suspicious)
      robustSolve();
    cache_valid = false;

    for (ObservationResult &res : results)
      if (res.undistorted) {
        const Feature &ft = features.at(res.id);
        for (const Obs &ob : ft.obs)
          if (ob.frame == row.frame)
            res.inlier = !ob.outlier;
      }
    while (static_cast<int>(frames.size()) > o.window)
      marginaliseOldest();
    return results;
  }

  /* Robust phase, re-start of young features whose observations disagree, flags, then least squares. */
  /* Marginalise a feature out of the prior (the information the prior held on it is dropped). */
  void dropFromPrior(long id)
  {
    prior_vars = schurOut(Hp, gp, prior_vars, [id](const PriorVar &v) { return !v.is_frame && v.key == id; });
    cache_valid = false;
  }

  /* A feature that went wrong (most of its window observations disagree with it, e.g. after a gross
     error at its start): it starts again from its window observations, with what the prior held
     on it dropped (that came from the same wrong point). */
  void restartFeature(Feature &ft)
  {
    dropFromPrior(ft.id);
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

  void robustSolve()
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
};

WindowEstimator::WindowEstimator(const CameraModel &camera, const YawRig &rig, const Options &options)
    : impl_(std::make_unique<Impl>(camera, rig, options))
{
}
WindowEstimator::~WindowEstimator() = default;
WindowEstimator::WindowEstimator(WindowEstimator &&) noexcept = default;
WindowEstimator &WindowEstimator::operator=(WindowEstimator &&) noexcept = default;

std::vector<WindowEstimator::ObservationResult> WindowEstimator::addFrame(const MotionSample &row,
                                                                          const std::vector<FeatureObservation> &obs)
{
  return impl_->addFrame(row, obs);
}

PointEstimate WindowEstimator::estimate(long id) const
{
  const auto it = impl_->features.find(id);
  if (it != impl_->features.end() && it->second.in_state) {
    impl_->ensureCache();
    return impl_->cache.at(id);
  }
  const auto fin = impl_->finished.find(id);
  if (fin != impl_->finished.end())
    return fin->second;
  if (it != impl_->features.end())
    return impl_->estimateOf(it->second);
  PointEstimate e;
  e.status = Status::TooFewFrames;
  return e;
}

bool WindowEstimator::isOutlier(long id, long frame) const
{
  if (impl_->rejected.count({id, frame}))
    return true;
  const auto it = impl_->features.find(id);
  if (it == impl_->features.end())
    return false;
  for (const Impl::Obs &ob : it->second.obs)
    if (ob.frame == frame)
      return ob.outlier;
  return false;
}

std::vector<long> WindowEstimator::ids() const
{
  std::vector<long> out;
  for (const auto &kv : impl_->features)
    if (kv.second.in_state)
      out.push_back(kv.first);
  return out;
}

void WindowEstimator::forget(long id)
{
  impl_->finished.erase(id);
  auto &rej = impl_->rejected; // its final outlier flags too
  rej.erase(rej.lower_bound({id, std::numeric_limits<long>::min()}),
            rej.upper_bound({id, std::numeric_limits<long>::max()}));
  const auto it = impl_->features.find(id);
  if (it == impl_->features.end())
    return;
  if (it->second.in_state)
    impl_->dropFromPrior(id); // its window observations are dropped with it
  impl_->features.erase(it);
  impl_->cache_valid = false;
}

long WindowEstimator::frame() const { return impl_->frames.empty() ? 0 : impl_->frames.back().row.frame; }

int WindowEstimator::windowFrames() const { return static_cast<int>(impl_->frames.size()); }

MotionSample WindowEstimator::motion(long frame) const
{
  const int fi = impl_->frameIndex(frame);
  if (fi < 0)
    throw Error("window estimator: frame " + std::to_string(frame) + " is not in the window");
  const Impl::Frame &f = impl_->frames[static_cast<std::size_t>(fi)];
  MotionSample s = f.row;
  s.x = f.x[0];
  s.y = f.x[1];
  s.z = f.x[2];
  s.yaw = f.x[6];
  if (s.six_dof)
    s.theta_u = logSO3(f.Rref * expSO3<double>(Eigen::Vector3d(f.x[3], f.x[4], f.x[5])));
  else
    s.heading = f.row.heading + f.x[4];
  return s;
}

int WindowEstimator::stateDimension() const { return impl_->stateLayout().n; }

std::vector<PointEstimate> windowTracks(const CameraModel &camera, const YawRig &rig,
                                        const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                        const WindowOptions &options, std::vector<std::vector<bool>> *outliers)
{
  for (std::size_t i = 1; i < motion.size(); ++i)
    if (!(motion[i].frame > motion[i - 1].frame))
      throw Error("window estimator: motion-log frames must be strictly increasing");
  std::map<long, std::size_t> track_of;
  std::map<long, std::vector<FeatureObservation>> by_frame;
  std::set<long> logged;
  for (const MotionSample &s : motion)
    logged.insert(s.frame);
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    if (!track_of.emplace(tracks[t].id, t).second)
      throw Error("window estimator: feature id " + std::to_string(tracks[t].id) + " appears in two tracks");
    for (const Observation &ob : tracks[t].observations) {
      if (!logged.count(ob.frame))
        throw Error("window estimator: frame " + std::to_string(ob.frame) + " of feature " +
                    std::to_string(tracks[t].id) + " is not in the motion log");
      FeatureObservation fo;
      fo.id = tracks[t].id;
      fo.u = ob.u;
      fo.v = ob.v;
      by_frame[ob.frame].push_back(fo);
    }
  }
  std::vector<PointEstimate> out(tracks.size());
  if (outliers) {
    outliers->assign(tracks.size(), {});
    for (std::size_t t = 0; t < tracks.size(); ++t)
      (*outliers)[t].assign(tracks[t].observations.size(), false);
  }
  if (motion.empty())
    return out;
  WindowEstimator est(camera, rig, options);
  auto collect = [&](std::size_t t) {
    out[t] = est.estimate(tracks[t].id);
    if (out[t].frame != tracks[t].observations.back().frame) { // restarted after a gap, not yet re-estimated
      out[t] = PointEstimate();
      out[t].frame = tracks[t].observations.back().frame;
    }
    if (outliers)
      for (std::size_t k = 0; k < tracks[t].observations.size(); ++k)
        (*outliers)[t][k] = est.isOutlier(tracks[t].id, tracks[t].observations[k].frame);
  };
  for (const MotionSample &row : motion) {
    const auto it = by_frame.find(row.frame);
    est.addFrame(row, it == by_frame.end() ? std::vector<FeatureObservation>() : it->second);
  }
  // Estimates of features that left the state were kept when they left; the others are read now.
  for (std::size_t t = 0; t < tracks.size(); ++t)
    if (!tracks[t].observations.empty())
      collect(t);
  return out;
}

} // namespace yawdepth
