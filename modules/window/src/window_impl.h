#pragma once
/*
  Private to yawdepth::window: the state of WindowEstimator and the declarations of its parts, one
  file each:
  - window_factors.cpp:          the factors (observations, increments or poses, yaw readings, the
                                 prior), their cost and their Gauss-Newton system;
  - window_solve.cpp:            the solves (Schur complement of the points, Gauss-Newton, the new
                                 frame's alignment, outlier flags, the robust path);
  - window_features.cpp:         features entering the state, their starts and restarts;
  - window_marginalisation.cpp:  the prior: the oldest frame leaving, its compression, features leaving;
  - window_estimates.cpp:        each feature's point, covariance and status;
  - window_estimator.cpp:        the options, a frame's arrival, and the public class.

  Names: a frame's parameters x = (x, y, z, dx, dy, dz, yaw) (window_model.h); a feature's point
  p = (alpha, beta, rho), anchored in (Ra, ca). "Free" components are those estimated (a planar log
  frees x, y, z and the heading dy; a gauge frame none of its pose; yaw when it has noise).

  The Gauss-Newton system of the whole state has an arrow structure: each feature's 3 x 3 block
  couples only to the *reduced* variables y = (every window frame's free components, the prior's
  auxiliary directions a), never to another feature. So each solve eliminates the points (3 x 3
  Cholesky each: the Schur complement) and factorises only the reduced system: the cost is linear in
  the features. The prior keeps that structure (window_marginalisation.cpp says how).
*/
#include "information.h"
#include "refine_model.h"
#include "window_model.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <deque>
#include <limits>
#include <map>
#include <set>
#include <vector>
#include <yawdepth/window/window_estimator.h>

namespace yawdepth {

using window_detail::kFrameDim; // x, y, z, dx, dy, dz, yaw

/* Largest inverse sigma of a motion factor: 1 um, 1 urad (a component this certain is still estimated). */
constexpr double kMaxInvSigma = 1e6;
inline double clampInv(double sigma) { return sigma > 0 ? std::min(1.0 / sigma, kMaxInvSigma) : kMaxInvSigma; }

/*
  The marginalisation prior, a Gaussian factor on the features that ever entered it and on
  y = (frames still in the window that it links, then `aux` auxiliary directions):
    cost = sum_i [ g_i' df_i + df_i' D_i df_i / 2 + df_i' B_i dy ] + gy' dy + dy' C dy / 2,
  df_i = p_i - x0_i (the feature's block is in its Feature), dy = (each prior frame's free components
  minus x0, then the auxiliary values a; their linearisation point is 0). No feature-feature term:
  what the marginalised frames coupled between features is carried by the auxiliary directions.
*/
struct WindowPrior {
  struct FrameVar {
    long frame = 0;
    int dim = 0;
    std::vector<double> x0; // linearisation point of its free components
  };
  std::vector<FrameVar> frames;
  int aux = 0;
  Eigen::VectorXd a;   // auxiliary values (estimated with the state)
  Eigen::MatrixXd C;   // dimY x dimY
  Eigen::VectorXd gy;  // dimY
  int frameDims() const
  {
    int n = 0;
    for (const FrameVar &f : frames)
      n += f.dim;
    return n;
  }
  int dimY() const { return frameDims() + aux; }
};

/*
  The Gauss-Newton system of the state, with the points apart: per feature i (in `ids` order) the
  3 x 3 block A_i (rows 3i..3i+2 of A), its gradient b_i and its coupling E_i (3 x P) to the reduced
  variables; H, g over the reduced variables (frames' free components at frame_offset, then the
  prior's auxiliary directions at aux_offset). The factorisation: L_i (Cholesky of A_i), U_i = L_i^-1 E_i,
  and the Schur complement S = H - U'U factorised.
*/
struct SchurSystem {
  std::vector<int> frame_offset;   // per window frame, -1 when none of its components is free
  std::vector<long> frame_numbers; // the window's frames when the system was made
  int aux_offset = 0, aux = 0;
  int P = 0;                       // reduced dimension
  std::vector<long> ids;           // features in the state, in order
  Eigen::Matrix<double, Eigen::Dynamic, 3> A, L;
  Eigen::MatrixXd E, U, H;
  Eigen::VectorXd b, g;
  Eigen::LLT<Eigen::MatrixXd> S;
  bool factored = false;
  int N() const { return static_cast<int>(ids.size()); }
  int dimension() const { return P + 3 * N(); }
};

struct FrameBlocks; // window_factors.cpp

/* Feature::chain_frame when no observation of the track's chain is in the prior. */
constexpr long kNoChain = std::numeric_limits<long>::min();

/*
  The tracker's correlated errors (NoiseModel::pixel_correlation phi, window_factors.cpp): each
  observation's whitened residual r_k (Jacobian J_k) enters as the innovation of an AR(1) process
  along its track, r~ = (r_k - a r_prev) / sqrt(1 - a^2), a = phi^gap, r_prev the residual of the
  track's previous observation in the chain (gap: window frames between them); the first
  observation of a chain enters as r_k. A pair factor couples the point and two frames: the Schur
  structure is kept.
*/
struct ChainLink {
  Eigen::Vector2d r = Eigen::Vector2d::Zero();                            // read only when valid
  Eigen::Matrix<double, 2, 10> J = Eigen::Matrix<double, 2, 10>::Zero(); // (frame's 7, point's 3)
  int fi = -1;        // window frame index
  bool valid = false; // a residual (the point is in front)
};

/* The estimator's state and parts (WindowEstimator::Impl is this). */
struct WindowState {
  using ObservationResult = WindowEstimator::ObservationResult;
  // ---- Types.
  struct Frame {
    MotionSample row;
    Eigen::Matrix3d Rref = Eigen::Matrix3d::Identity();
    double x[kFrameDim] = {0, 0, 0, 0, 0, 0, 0};
    bool gauge = false;                                   // pose held (the first frame, increment noise)
    refine_detail::OdometryMeasurementGeneral from_prev;  // the measured increment from the previous row
    int local[kFrameDim] = {-1, -1, -1, -1, -1, -1, -1}; // index of each parameter among the free ones, or -1
    int dim = 0;                                          // free parameters
    bool has_fej = false;                                 // in the prior: Jacobians at its first estimate there
    double x_fej[kFrameDim] = {0, 0, 0, 0, 0, 0, 0};
    window_detail::CameraPose cam;                        // the camera at x, and its derivatives
  };
  struct Obs {
    long frame = 0;
    refine_detail::WhitenedObservation w;
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
    // Its block of the prior (WindowPrior's comment).
    bool in_prior = false;
    double x0[3] = {0, 0, 0};
    Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
    Eigen::Vector3d gp = Eigen::Vector3d::Zero();
    Eigen::MatrixXd B; // 3 x prior.dimY()
    // Gate memory of marginalised inlier observations.
    int old_inliers = 0, old_outliers = 0;
    bool has_first = false;
    Eigen::Vector3d first_ray = Eigen::Vector3d::Zero(), first_centre = Eigen::Vector3d::Zero();
    Eigen::Vector3d last_centre = Eigen::Vector3d::Zero(); // of the last marginalised inlier
    double old_parallax = 0;
    /* The tracker's correlated errors (NoiseModel::pixel_correlation): the observation at this
       frame ends the part of the track's chain already in the prior (its factor is there, it only
       conditions the next); observations before it are frozen (flags final, no factor). */
    long chain_frame = kNoChain;
  };
  enum class Phase { Robust, Inliers };
  enum class Fill { Cost, Gradient, Full }; // what a linearisation computes besides the cost
  struct Saved {
    std::vector<std::array<double, kFrameDim>> frames;
    std::vector<std::array<double, 3>> points; // of sys.ids
    Eigen::VectorXd aux;
  };

  // ---- Data.
  CameraModel camera;
  YawRig rig;
  WindowOptions o;
  refine_detail::Mount mount;
  bool started = false, six_dof = false, absolute = false;
  bool poses_free = false, yaws_free = false;
  std::vector<int> pose_components; // free pose components (0..5) of a non-gauge frame
  std::deque<Frame> frames;
  std::map<long, Feature> features; // in the state or pending (seen once in the window)
  std::map<long, PointEstimate> finished;
  std::set<std::pair<long, long>> rejected; // (id, frame) flagged when its frame left the window
  WindowPrior prior;
  SchurSystem sys; // the state's last system and factorisation (the covariances read it)
  // Estimates of the state's features after the last frame (computed on demand).
  mutable bool cache_valid = false;
  mutable std::map<long, PointEstimate> cache;
  double c_robust = 1;     // Cauchy scale in whitened units
  double c_outlier_sq = 4; // squared outlier threshold in whitened units

  WindowState(const CameraModel &cam, const YawRig &r, const WindowOptions &opt);

  // ---- Frames (window_estimator.cpp).
  std::vector<int> freeComponents(const Frame &f) const;
  int frameIndex(long frame) const;
  const Frame &frameOf(long frame) const { return frames[static_cast<std::size_t>(frameIndex(frame))]; }
  void setComponents(Frame &f) const;
  void refreshCamera(Frame &f) const { window_detail::cameraPose(f.x, f.Rref, mount, f.cam); }
  Frame fejFrame(const Frame &f) const;
  void startLog(const MotionSample &row, Frame &f);
  void deadReckon(const MotionSample &row, Frame &f) const;
  std::vector<ObservationResult> addObservations(const MotionSample &row,
                                                 const std::vector<FeatureObservation> &observations);
  std::vector<ObservationResult> addFrame(const MotionSample &row, const std::vector<FeatureObservation> &observations);

  // ---- Factors (window_factors.cpp).
  refine_detail::OdometryMeasurementGeneral increment(const Frame &prev, const Frame &cur) const;
  double weightOf(double s, Phase phase) const;
  double costOf(double s, Phase phase) const;
  static bool observationResidual(const Feature &ft, const Frame &f, const Obs &ob, Eigen::Vector2d &r,
                                  Eigen::Matrix<double, 2, 10> *J);
  bool observationJacobian(const Feature &ft, const Frame &f, const Frame *fj, const Obs &ob, Eigen::Vector2d &r,
                           Eigen::Matrix<double, 2, 10> &J) const;
  Eigen::VectorXd priorDeltaY() const;
  double motionFactors(int only_frame, Fill fill, const std::vector<Frame> &fej_frames, const std::vector<int> &offset,
                       Eigen::MatrixXd &H, Eigen::VectorXd &g) const;
  std::vector<Frame> fejFrames() const;
  double linearizeState(SchurSystem &s, Phase phase, Fill fill) const;
  double observationFactors(SchurSystem &s, Phase phase, Fill fill, const std::vector<Frame> &fej,
                            int only_frame) const;
  double featureFactors(SchurSystem &s, int i, Phase phase, Fill fill, const std::vector<Frame> &fej, int only_frame,
                        FrameBlocks &fb) const;
  void accumulatePair(SchurSystem &s, int i, const Frame &f, const ChainLink &prev, const ChainLink &cur, double a,
                      double scale, const Eigen::Vector2d &r, double w, bool full, FrameBlocks &fb) const;
  double linearizeOldest(SchurSystem &s) const;
  double priorFactor(SchurSystem &s, Fill fill) const;
  double linearizeNewFrame(Phase phase, Fill fill, Eigen::MatrixXd &H, Eigen::VectorXd &g) const;
  double chainCoefficient(int gap) const;
  const Obs *chainPrevious(const Feature &ft, std::size_t k, Phase phase) const;
  const Obs *chainSuccessor(const Feature &ft, long frame0) const;
  void layoutSystem(SchurSystem &s) const;

  // ---- Solves (window_solve.cpp).
  static bool factor(SchurSystem &s);
  static Eigen::VectorXd schurStep(const SchurSystem &s, double *gain);
  void applyStep(const SchurSystem &s, const Eigen::VectorXd &dx, double scale);
  Saved save(const SchurSystem &s) const;
  void restore(const SchurSystem &s, const Saved &saved);
  int solve(Phase phase);
  void alignNewFrame();
  bool flagOutliers();
  void robustSolve();

  // ---- Features (window_features.cpp).
  bool triangulate(const Obs &a, const Obs &b, Eigen::Vector3d &P) const;
  static bool anchorParameters(const Feature &ft, const Eigen::Vector3d &P, double *p);
  double featureCost(Feature &ft, const double *p) const;
  void refinePointAlone(const Feature &ft, double *p) const;
  void initialisePoint(Feature &ft, bool keep_current);
  void enterState(Feature &ft);
  void restartFeature(Feature &ft);

  // ---- The prior (window_marginalisation.cpp).
  void dropFromPrior(Feature &ft);
  void marginaliseOldest();
  std::vector<long> leavingFeatures(long frame0) const;
  void setFirstEstimates(long frame0);
  void retireObservations(long frame0);
  void blanketLayout(SchurSystem &s) const;
  void eliminateFeatures(SchurSystem &s, const std::vector<long> &leaving) const;
  void condensePrior(const SchurSystem &s, const std::vector<long> &leaving);
  void advanceChains(long frame0);

  // ---- Estimates (window_estimates.cpp).
  double parallaxPx(const Eigen::Vector3d &ray_w, const Frame &f, const Obs &ob) const;
  PointEstimate gatedEstimate(const Feature &ft, bool *rho_only) const;
  bool pointJacobian(const Feature &ft, Eigen::Matrix3d &Jf, Eigen::MatrixXd &JY) const;
  void ensureCache() const;
};

struct WindowEstimator::Impl : WindowState {
  using WindowState::WindowState;
};

} // namespace yawdepth
