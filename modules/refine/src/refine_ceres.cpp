// refineWindow() with Ceres: MAP refinement of the points with the odometry and yaw readings. The
// problem's assembly and solution; the cost functors are in costs/, the model in refine_model.h.
#include "costs/innovation_costs.h"
#include "costs/observation_costs.h"
#include "costs/odometry_costs.h"
#include "costs/prior_costs.h"
#include "information.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <ceres/ceres.h>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <yawdepth/error.h>
#include <yawdepth/estimation/two_view.h>
#include <yawdepth/refine/refine.h>

namespace yawdepth {

using namespace refine_detail;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

struct TrackData {
  std::vector<int> rows;
  std::vector<Eigen::Vector2d> uv;
  std::vector<WhitenedObservation> w;
  std::vector<bool> outlier;
  int anchor_row = 0, report_row = 0;
  Status status = Status::TooFewFrames;
  bool active = false; // in the optimisation
  double parallax = kNaN;
  std::array<double, 3> point{{0, 0, 1}};
};

/* Parameters of the motion: one block per motion-log row, (x, y, z, heading, yaw) (m, rad) for the
   planar chain, (x, y, z, dx, dy, dz, yaw) for the general one; one block per row rather than a
   pose and a yaw block keeps the Schur complement's block count low. */
struct State {
  std::vector<std::array<double, 7>> frames;
};

/* RefineOptions::progress after every solver iteration. */
class ProgressCallback : public ceres::IterationCallback {
public:
  ProgressCallback(const std::function<void(const RefineProgress &)> &report, const RefineProgress &base,
                   std::chrono::steady_clock::time_point start)
      : report_(report), base_(base), start_(start)
  {
  }
  ceres::CallbackReturnType operator()(const ceres::IterationSummary &summary) override
  {
    RefineProgress p = base_;
    p.iteration = summary.iteration;
    p.cost = summary.cost;
    p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    report_(p);
    return ceres::SOLVER_CONTINUE;
  }

private:
  const std::function<void(const RefineProgress &)> &report_;
  RefineProgress base_;
  std::chrono::steady_clock::time_point start_;
};

class Refiner {
public:
  Refiner(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
          const std::vector<PointEstimate> &initial, const RefineOptions &options)
      : camera_(camera), input_(input), motion_(input.motion()), tracks_(input.tracks()), initial_(initial),
        o_(options), t0v_(rig.cameraOffset()), rig_(rig)
  {
    std::copy(t0v_.data(), t0v_.data() + 3, t0_);
  }

  /* Values per frame block and the yaw's index in it. */
  int blockSize() const { return model_.general ? 7 : 5; }
  int yawIndex() const { return model_.general ? 6 : 4; }

  RefineResult run();

private:
  void prepare();
  void initialise();
  void gate(TrackData &t, bool inliers_only) const;
  void cameraAt(int row, Eigen::Matrix3d &R, Eigen::Vector3d &c) const;
  void anchored(int row_a, int row_k, const double *point, double *q) const;
  bool candidateScore(const TrackData &t, const std::array<double, 3> &p, double &score) const;
  bool anchorFromCamera(const TrackData &t, int row, const Eigen::Vector3d &c_P, std::array<double, 3> &p) const;
  void addMotionBlocks(ceres::Problem &problem, ceres::ParameterBlockOrdering &ordering);
  void addMotionPriors(ceres::Problem &problem);
  int addObservations(ceres::Problem &problem, ceres::ParameterBlockOrdering &ordering, bool robust);
  double chainCoefficient(int gap) const;
  void addObservation(ceres::Problem &problem, TrackData &t, std::size_t j, std::size_t prev,
                      ceres::LossFunction *loss);
  void chooseLinearSolver(ceres::Solver::Options &so) const;
  ceres::Solver::Options solverOptions(bool robust) const;
  ceres::Solver::Summary solve(bool robust, bool &solved);
  void flagOutliers();
  void checkOptions() const;
  void optimise(RefineResult &result);
  void gateRefined();
  void computeCovariances(std::vector<Eigen::Matrix3d> &cov, std::vector<int> &index);
  void writePoints(RefineResult &result, const std::vector<Eigen::Matrix3d> &cov, const std::vector<int> &index) const;
  void writeMotion(RefineResult &result) const;
  RefineProgress progressAt(RefineProgress::Stage stage) const;
  Eigen::Vector3d cameraPoint(const TrackData &t, int row) const;
  double pixelError(const TrackData &t, std::size_t j) const;

  const CameraModel &camera_;
  const TracksByFrame &input_;
  const std::vector<MotionSample> &motion_;
  const std::vector<Track> &tracks_;
  const std::vector<PointEstimate> &initial_;
  const RefineOptions &o_;
  Eigen::Vector3d t0v_;
  const YawRig &rig_;
  double t0_[3];
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  bool poses_free_ = false, yaws_free_ = false;
  Model model_; // the chain, mount, reference orientations and motion priors (refine_model.h)
  State state_;
  std::vector<TrackData> data_;
};

/* The camera's world rotation and centre at a row, with the current state. */
void Refiner::cameraAt(int row, Eigen::Matrix3d &R, Eigen::Vector3d &c) const
{
  const double *f = state_.frames[row].data();
  if (model_.general)
    cameraInWorldGeneral(f, model_.Rref[row], model_.mount, R, c);
  else
    cameraInWorld(f, f[4], t0v_, R, c);
}

/* rho times the camera-frame point at row_k of a point anchored at row_a, with the current state. */
void Refiner::anchored(int row_a, int row_k, const double *point, double *q) const
{
  const double *fa = state_.frames[row_a].data(), *fk = state_.frames[row_k].data();
  if (model_.general)
    anchoredPointGeneral(fa, model_.Rref[row_a], fk, model_.Rref[row_k], point, model_.mount, q);
  else
    anchoredPoint(fa, fa + 4, fk, fk + 4, point, t0_, q);
}

/* Camera-frame point of a track at a row, with the current state. */
Eigen::Vector3d Refiner::cameraPoint(const TrackData &t, int row) const
{
  double q[3];
  anchored(t.anchor_row, row, t.point.data(), q);
  return Eigen::Vector3d(q[0], q[1], q[2]) / t.point[2];
}

/* Reprojection error of observation j in observed (distorted) pixels; infinite behind the camera. */
double Refiner::pixelError(const TrackData &t, std::size_t j) const
{
  double q[3];
  anchored(t.anchor_row, t.rows[j], t.point.data(), q);
  if (!(q[2] > 0))
    return kInf;
  const Eigen::Vector2d uv = camera_.project(Eigen::Vector2d(q[0] / q[2], q[1] / q[2]));
  return (uv - t.uv[j]).norm();
}

void Refiner::prepare()
{
  if (motion_.empty())
    throw Error("refine: the motion log is empty");
  if (!initial_.empty() && initial_.size() != tracks_.size())
    throw Error("refine: one initial estimate per track is needed (or none)");

  const NoiseModel &n = o_.noise;
  setModelMotion(model_, rig_, motion_, n);
  poses_free_ = model_.poses_free;
  yaws_free_ = model_.yaws_free;
  for (const MotionSample &s : motion_) {
    if (model_.general) // at the reference orientation (the measured one)
      state_.frames.push_back({s.x, s.y, s.z, 0.0, 0.0, 0.0, s.yaw});
    else
      state_.frames.push_back({s.x, s.y, s.z, s.heading, s.yaw, 0.0, 0.0});
  }

  data_.resize(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const Track &tr = tracks_[i];
    TrackData &t = data_[i];
    t.outlier.assign(tr.observations.size(), false);
    bool undistorted = true;
    for (std::size_t j = 0; j < tr.observations.size(); ++j) {
      const Observation &ob = tr.observations[j];
      const int row = static_cast<int>(input_.row(i, j));
      t.rows.push_back(row);
      t.uv.emplace_back(ob.u, ob.v);
      Eigen::Vector2d m;
      Eigen::Matrix2d J;
      if (!std::isfinite(ob.u) || !std::isfinite(ob.v) || !camera_.undistort(t.uv.back(), m, &J)) {
        undistorted = false;
        t.w.emplace_back();
        continue;
      }
      t.w.push_back(whitenObservation(m, J, n.sigma_px));
    }
    if (tr.observations.size() < 2) {
      t.status = Status::TooFewFrames;
      continue;
    }
    t.anchor_row = t.rows.front();
    t.report_row = t.rows.back();
    if (!undistorted) {
      t.status = Status::UndistortFailed;
      continue;
    }
    t.status = Status::Ok;
    gate(t, false);
    t.active = t.status == Status::Ok;
  }
}

/* The no_motion and degenerate gates, on the inliers (or every observation) with the current state. */
void Refiner::gate(TrackData &t, bool inliers_only) const
{
  std::vector<std::size_t> use;
  for (std::size_t j = 0; j < t.rows.size(); ++j)
    if (!inliers_only || !t.outlier[j])
      use.push_back(j);
  if (use.size() < 2) {
    t.status = Status::TooFewFrames;
    return;
  }
  const std::size_t j0 = use.front();
  Eigen::Matrix3d R0, R;
  Eigen::Vector3d c0, c;
  cameraAt(t.rows[j0], R0, c0);
  cameraAt(t.rows[use.back()], R, c);
  if (!((c - c0).norm() >= o_.gates.min_baseline)) {
    t.status = Status::NoMotion;
    return;
  }
  const Eigen::Vector3d b0(t.w[j0].m[0], t.w[j0].m[1], 1.0);
  double parallax = 0;
  for (std::size_t u = 1; u < use.size(); ++u) {
    const std::size_t j = use[u];
    cameraAt(t.rows[j], R, c);
    const Eigen::Vector3d r = R.transpose() * (R0 * b0);
    const double p = r.z() > 1e-12 ? std::hypot(camera_.kx() * (t.w[j].m[0] - r.x() / r.z()),
                                                camera_.ky() * (t.w[j].m[1] - r.y() / r.z()))
                                   : kInf;
    parallax = std::max(parallax, p);
  }
  t.parallax = parallax;
  if (!(parallax >= o_.gates.min_parallax_px))
    t.status = Status::Degenerate;
}

bool Refiner::anchorFromCamera(const TrackData &t, int row, const Eigen::Vector3d &c_P, std::array<double, 3> &p) const
{
  Eigen::Matrix3d Rk, Ra;
  Eigen::Vector3d ck, ca;
  cameraAt(row, Rk, ck);
  cameraAt(t.anchor_row, Ra, ca);
  const Eigen::Vector3d Pa = Ra.transpose() * (Rk * c_P + ck - ca);
  if (!(Pa.z() > 0) || !Pa.allFinite())
    return false;
  p = {Pa.x() / Pa.z(), Pa.y() / Pa.z(), 1.0 / Pa.z()};
  return true;
}

/* Robust score of a candidate point against every observation (lower is better); false when the
   candidate is behind the camera in some frame. */
bool Refiner::candidateScore(const TrackData &t, const std::array<double, 3> &p, double &score) const
{
  constexpr double tau2 = 3.0 * 3.0; // px^2
  score = 0;
  for (std::size_t j = 0; j < t.rows.size(); ++j) {
    double q[3];
    anchored(t.anchor_row, t.rows[j], p.data(), q);
    if (!(q[2] > 0) || !(p[2] > 0))
      return false;
    const double ex = camera_.kx() * (q[0] / q[2] - t.w[j].m[0]);
    const double ey = camera_.ky() * (q[1] / q[2] - t.w[j].m[1]);
    score += std::log1p((ex * ex + ey * ey) / tau2);
  }
  return std::isfinite(score);
}

/* Initial points: the given estimate, `exact` on pairs of first/last observations, or the median
   depth of the others, whichever explains the observations best (robust to a gross error in the
   first or last observation). */
void Refiner::initialise()
{
  TwoViewOptions tv;
  tv.noise = o_.noise;
  tv.gates = o_.gates;
  tv.compute_covariance = false;
  std::vector<double> depths;
  std::vector<char> have(data_.size(), 0);
  for (std::size_t i = 0; i < data_.size(); ++i) {
    TrackData &t = data_[i];
    if (!t.active)
      continue;
    double best = kInf;
    auto consider = [&](const std::array<double, 3> &p) {
      double s;
      if (candidateScore(t, p, s) && s < best) {
        best = s;
        t.point = p;
      }
    };
    std::array<double, 3> p;
    if (!initial_.empty() && initial_[i].ok() && initial_[i].c_P.allFinite()) {
      const long row = rowOfFrame(motion_, initial_[i].frame);
      if (row >= 0 && anchorFromCamera(t, static_cast<int>(row), initial_[i].c_P, p))
        consider(p);
    }
    const std::size_t n = t.rows.size();
    const std::size_t firsts[2] = {0, 1}, lasts[2] = {n - 1, n - 2};
    for (std::size_t a : firsts)
      for (std::size_t b : lasts) {
        if (!(b > a))
          continue;
        tv.increments = t.rows[b] - t.rows[a];
        const PointEstimate e = estimateExact(camera_, rig_, motion_[t.rows[a]], motion_[t.rows[b]], t.uv[a], t.uv[b], tv);
        if (e.ok() && anchorFromCamera(t, t.rows[b], e.c_P, p))
          consider(p);
      }
    if (best < kInf) {
      have[i] = 1;
      depths.push_back(1.0 / t.point[2]);
    }
  }
  double median = 1.0;
  if (!depths.empty()) {
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
    median = depths[depths.size() / 2];
  }
  for (std::size_t i = 0; i < data_.size(); ++i) {
    TrackData &t = data_[i];
    if (!t.active || have[i])
      continue;
    double best = kInf, s;
    std::array<double, 3> p;
    for (std::size_t j : {std::size_t(0), t.rows.size() - 1}) {
      const Eigen::Vector3d c_P = median * Eigen::Vector3d(t.w[j].m[0], t.w[j].m[1], 1.0);
      if (anchorFromCamera(t, t.rows[j], c_P, p) && candidateScore(t, p, s) && s < best) {
        best = s;
        t.point = p;
      }
    }
    if (!(best < kInf)) {
      t.status = Status::Behind;
      t.active = false;
    }
  }
}

/* One parameter block per motion-log row, with the parts that are known held constant. */
void Refiner::addMotionBlocks(ceres::Problem &problem, ceres::ParameterBlockOrdering &ordering)
{
  const int rows = static_cast<int>(state_.frames.size());
  const int block = blockSize(), pose_dim = block - 1;
  for (int r = 0; r < rows; ++r) {
    double *f = state_.frames[r].data();
    problem.AddParameterBlock(f, block);
    ordering.AddElementToGroup(f, 1);
    // Known parts: frame 0's pose (the gauge, for increment noise), every pose or yaw whose noise is
    // not modelled (and for a planar log in the general chain, the rotation off the heading axis).
    std::vector<int> known;
    for (int j = 0; j < pose_dim; ++j)
      if (r < model_.firstFreeRow() || !poses_free_ || !model_.componentFree(j))
        known.push_back(j);
    if (!yaws_free_)
      known.push_back(pose_dim);
    if (static_cast<int>(known.size()) == block)
      problem.SetParameterBlockConstant(f);
    else if (!known.empty())
      problem.SetManifold(f, new ceres::SubsetManifold(block, known));
  }
}

/* The motion's priors: absolute poses or odometry increments, and the yaw readings, when free. */
void Refiner::addMotionPriors(ceres::Problem &problem)
{
  const int rows = static_cast<int>(state_.frames.size());
  if (poses_free_ && model_.absolute)
    for (int r = 0; r < rows; ++r)
      problem.AddResidualBlock(model_.general ? PosePriorCost<6, 7>::Create(model_.pose_priors[r])
                                              : PosePriorCost<4, 5>::Create(model_.pose_priors[r]),
                               nullptr, state_.frames[r].data());
  else if (poses_free_)
    for (int r = 1; r < rows; ++r)
      problem.AddResidualBlock(model_.general ? OdometryCostGeneral::Create(model_.odometry_general[r - 1])
                                              : OdometryCost::Create(model_.odometry[r - 1]),
                               nullptr, state_.frames[r - 1].data(), state_.frames[r].data());
  if (yaws_free_)
    for (int r = 0; r < rows; ++r)
      problem.AddResidualBlock(model_.general ? YawCost<7>::Create(motion_[r].yaw, 1.0 / o_.noise.sigma_yaw)
                                              : YawCost<5>::Create(motion_[r].yaw, 1.0 / o_.noise.sigma_yaw),
                               nullptr, state_.frames[r].data());
}

/* phi^gap for an observation gap motion-log rows after the previous one of its track's chain
   (NoiseModel::pixel_correlation, costs/innovation_costs.h); 0: independent errors. */
double Refiner::chainCoefficient(int gap) const { return pixelCorrelationOver(o_.noise.pixel_correlation, gap); }

/* Observation j of a track: its residual, or with correlated tracker errors (pixel_correlation > 0)
   the innovation on the chain's previous inlier prev (costs/innovation_costs.h; prev = j: j starts the chain).
   The anchor observation is the track's first (prepare()), so it is always its chain's first. */
void Refiner::addObservation(ceres::Problem &problem, TrackData &t, std::size_t j, std::size_t prev,
                             ceres::LossFunction *loss)
{
  const int a = t.anchor_row, k = t.rows[j], p = t.rows[prev];
  double *fa = state_.frames[a].data(), *fk = state_.frames[k].data(), *fp = state_.frames[p].data();
  double *point = t.point.data();
  const double c = prev < j ? chainCoefficient(k - p) : 0.0;
  if (k == a)
    problem.AddResidualBlock(AnchorCost::Create(t.w[j]), loss, point);
  else if (c == 0 && model_.general)
    problem.AddResidualBlock(ReprojectionCostGeneral::Create(t.w[j], model_.Rref[a], model_.Rref[k], model_.mount),
                             loss, fa, fk, point);
  else if (c == 0)
    problem.AddResidualBlock(ReprojectionCost::Create(t.w[j], t0_), loss, fa, fk, point);
  else if (p == a && model_.general)
    problem.AddResidualBlock(InnovationAfterAnchorCostGeneral::Create(t.w[prev], t.w[j], model_.Rref[a],
                                                                      model_.Rref[k], model_.mount,
                                                                      ChainCoefficient(c)),
                             loss, fa, fk, point);
  else if (p == a)
    problem.AddResidualBlock(InnovationAfterAnchorCost::Create(t.w[prev], t.w[j], t0_, ChainCoefficient(c)), loss, fa,
                             fk, point);
  else if (model_.general)
    problem.AddResidualBlock(InnovationCostGeneral::Create(t.w[prev], t.w[j], model_.Rref[a], model_.Rref[p],
                                                           model_.Rref[k], model_.mount, ChainCoefficient(c)),
                             loss, fa, fp, fk, point);
  else
    problem.AddResidualBlock(InnovationCost::Create(t.w[prev], t.w[j], t0_, ChainCoefficient(c)), loss, fa, fp, fk,
                             point);
}

/* The active points' blocks and their inlier observations (Cauchy loss when robust, on the
   innovation for correlated tracker errors); returns the number of observations added. */
int Refiner::addObservations(ceres::Problem &problem, ceres::ParameterBlockOrdering &ordering, bool robust)
{
  const double scale = o_.robust_threshold_px / std::max(o_.noise.sigma_px, kMinWeightPx);
  int observations = 0;
  for (TrackData &t : data_) {
    if (!t.active)
      continue;
    problem.AddParameterBlock(t.point.data(), 3);
    ordering.AddElementToGroup(t.point.data(), 0);
    std::size_t prev = t.rows.size(); // the chain's previous inlier: none yet
    for (std::size_t j = 0; j < t.rows.size(); ++j) {
      if (t.outlier[j])
        continue;
      ceres::LossFunction *loss = robust ? new ceres::CauchyLoss(scale) : nullptr;
      addObservation(problem, t, j, prev < j ? prev : j, loss);
      prev = j;
      ++observations;
    }
  }
  return observations;
}

/* The linear solver: dense Schur complement, or a sparse one for a long log whose points each see
   a part of it. */
void Refiner::chooseLinearSolver(ceres::Solver::Options &so) const
{
  so.linear_solver_type = ceres::DENSE_SCHUR;
  // (model_ holds the chain and priors, not the rows: count the blocks of the problem itself.)
  const int motion_parameters = static_cast<int>(state_.frames.size()) * blockSize();
  // Over 400 motion parameters (80 frames), the reduced system of a log whose points each see a
  // part of it is sparse: a sparse Cholesky (SuiteSparse when Ceres has it, else Eigen's) instead of
  // a dense one whose cost grows with frames^3. When the points span most of the log on average,
  // the reduced system is dense anyway and the dense Cholesky is the faster (measured: 1000 points
  // in 100 frames, 10.2 s against 11.7 s).
  long span_sum = 0, spans = 0;
  for (const TrackData &t : data_)
    if (t.active && !t.rows.empty()) {
      span_sum += *std::max_element(t.rows.begin(), t.rows.end()) - *std::min_element(t.rows.begin(), t.rows.end()) + 1;
      ++spans;
    }
  const bool sparse_reduced = spans > 0 && 2 * span_sum < spans * static_cast<long>(state_.frames.size());
  if (motion_parameters > 400 && sparse_reduced)
    for (const auto library : {ceres::SUITE_SPARSE, ceres::EIGEN_SPARSE, ceres::CX_SPARSE})
      if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(library)) {
        so.linear_solver_type = ceres::SPARSE_SCHUR;
        so.sparse_linear_algebra_library_type = library;
        break;
      }
}

/* The solver's options for the robust or the final solve (without the ordering and callbacks). */
ceres::Solver::Options Refiner::solverOptions(bool robust) const
{
  ceres::Solver::Options so;
  chooseLinearSolver(so);
  so.max_num_iterations = o_.max_iterations;
  so.num_threads = std::max(1, o_.threads);
  // The robust solve only has to separate gross errors from inliers; its tail converges slowly
  // (Cauchy weights) and is not needed. The final solve stops when the cost changes by less than
  // 1e-7 of itself: a parameter error of order 1e-3 sigma, far below the noise.
  so.function_tolerance = robust ? 1e-4 : 1e-7;
  so.gradient_tolerance = 1e-10;
  so.parameter_tolerance = robust ? 1e-6 : 1e-8;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  return so;
}

ceres::Solver::Summary Refiner::solve(bool robust, bool &solved)
{
  ceres::Problem problem;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  addMotionBlocks(problem, *ordering);
  addMotionPriors(problem);
  const int observations = addObservations(problem, *ordering, robust);
  ceres::Solver::Summary summary;
  solved = observations > 0;
  if (!solved)
    return summary;

  ceres::Solver::Options so = solverOptions(robust);
  so.linear_solver_ordering = ordering;
  std::unique_ptr<ProgressCallback> callback;
  if (o_.progress) {
    callback = std::make_unique<ProgressCallback>(
        o_.progress, progressAt(robust ? RefineProgress::Stage::RobustSolve : RefineProgress::Stage::FinalSolve),
        start_);
    so.callbacks.push_back(callback.get());
  }
  ceres::Solve(so, &problem, &summary);
  return summary;
}

/* A progress report at the start of a stage: the problem's size and the time so far. */
RefineProgress Refiner::progressAt(RefineProgress::Stage stage) const
{
  RefineProgress p;
  p.stage = stage;
  p.frames = static_cast<int>(motion_.size());
  for (const TrackData &t : data_)
    p.points += t.active ? 1 : 0;
  p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return p;
}

/* An observation is an outlier when its reprojection error exceeds outlier_threshold_px. With
   correlated tracker errors (pixel_correlation > 0) this stays a test of the observation's own error,
   not of its innovation: the AR(1) process is stationary, each error's marginal 1-sigma is sigma_px
   whatever phi, so the threshold means the same; an innovation would also blame the observation
   after a gross error for it. */
void Refiner::flagOutliers()
{
  for (TrackData &t : data_) {
    if (!t.active)
      continue;
    int inliers = 0;
    for (std::size_t j = 0; j < t.rows.size(); ++j) {
      t.outlier[j] = !(pixelError(t, j) <= o_.outlier_threshold_px);
      inliers += t.outlier[j] ? 0 : 1;
    }
    if (inliers < 2) {
      t.status = Status::TooFewFrames;
      t.active = false;
    }
  }
}

void Refiner::checkOptions() const { o_.validate(); }

/* The robust solve, the outliers it shows, then the final solve on the inliers: the iterations,
   costs and convergence into result. */
void Refiner::optimise(RefineResult &result)
{
  bool solved = false;
  const ceres::Solver::Summary robust = solve(true, solved);
  if (solved)
    result.iterations += robust.num_successful_steps + robust.num_unsuccessful_steps;
  flagOutliers();
  const ceres::Solver::Summary final_summary = solve(false, solved);

  if (solved) {
    result.iterations += final_summary.num_successful_steps + final_summary.num_unsuccessful_steps;
    result.initial_cost = final_summary.initial_cost;
    result.final_cost = final_summary.final_cost;
    result.converged = final_summary.termination_type == ceres::CONVERGENCE;
  }
}

/* Gates on the refined motion and inliers. */
void Refiner::gateRefined()
{
  for (TrackData &t : data_) {
    if (!t.active)
      continue;
    gate(t, true);
    if (t.status == Status::Ok && (!(t.point[2] > 0) || !(cameraPoint(t, t.report_row).z() > 0)))
      t.status = Status::Behind;
  }
}

/* Covariance of every active point in the final problem (cov[index[i]] for track i, index -1 for
   an inactive one), with the final problem's AR(1) links between a track's inliers when the
   tracker's errors are correlated (Model::chain_prev); an Ok point whose covariance fails becomes
   Degenerate. */
void Refiner::computeCovariances(std::vector<Eigen::Matrix3d> &cov, std::vector<int> &index)
{
  if (o_.progress)
    o_.progress(progressAt(RefineProgress::Stage::Covariance));
  Model m = model_;
  for (const auto &f : state_.frames) {
    m.poses.push_back({f[0], f[1], f[2], f[3], model_.general ? f[4] : 0.0, model_.general ? f[5] : 0.0});
    m.yaws.push_back(f[yawIndex()]);
  }
  for (std::size_t i = 0; i < data_.size(); ++i) {
    const TrackData &t = data_[i];
    if (!t.active)
      continue;
    index[i] = static_cast<int>(m.points.size());
    int prev_row = -1; // the chain's previous inlier (addObservations' innovations)
    for (std::size_t j = 0; j < t.rows.size(); ++j)
      if (!t.outlier[j]) {
        const double c = prev_row >= 0 ? chainCoefficient(t.rows[j] - prev_row) : 0.0;
        if (c > 0)
          m.setChainLink(m.observations.size(), m.observations.size() - 1, c);
        m.observations.push_back({index[i], t.rows[j], t.w[j]});
        prev_row = t.rows[j];
      }
    m.points.push_back(t.point);
    m.anchor_row.push_back(t.anchor_row);
    m.report_row.push_back(t.report_row);
  }
  std::vector<char> ok;
  pointCovariances(m, true, cov, ok);
  for (std::size_t i = 0; i < data_.size(); ++i)
    if (index[i] >= 0 && !ok[index[i]] && data_[i].status == Status::Ok)
      data_[i].status = Status::Degenerate;
}

/* Every track's estimate and outlier flags into result (cov and index from computeCovariances). */
void Refiner::writePoints(RefineResult &result, const std::vector<Eigen::Matrix3d> &cov,
                          const std::vector<int> &index) const
{
  result.points.resize(data_.size());
  result.outliers.resize(data_.size());
  for (std::size_t i = 0; i < data_.size(); ++i) {
    const TrackData &t = data_[i];
    PointEstimate &e = result.points[i];
    e.status = t.status;
    e.frame = tracks_[i].observations.empty() ? 0 : tracks_[i].observations.back().frame;
    e.parallax_px = t.parallax;
    result.outliers[i] = t.outlier;
    if (t.status != Status::Ok)
      continue;
    e.c_P = cameraPoint(t, t.report_row);
    e.v_P = rig_.visionPoint(state_.frames[t.report_row][yawIndex()], e.c_P);
    if (index[i] >= 0)
      e.c_cov = cov[index[i]];
  }
}

/* The motion log with the refined poses and yaws. */
void Refiner::writeMotion(RefineResult &result) const
{
  result.motion = motion_;
  for (std::size_t r = 0; r < motion_.size(); ++r) {
    const auto &f = state_.frames[r];
    MotionSample &s = result.motion[r];
    s.x = f[0];
    s.y = f[1];
    s.z = f[2];
    s.yaw = f[yawIndex()];
    if (!model_.general)
      s.heading = f[3];
    else if (s.six_dof)
      s.theta_u = logSO3(model_.Rref[r] * expSO3<double>(Eigen::Vector3d(f[3], f[4], f[5])));
    else
      s.heading += f[4]; // a planar log in the general chain: only dy is free
  }
}

RefineResult Refiner::run()
{
  checkOptions();
  prepare();
  initialise();

  RefineResult result;
  result.available = true;
  optimise(result);
  gateRefined();

  std::vector<Eigen::Matrix3d> cov;
  std::vector<int> index(data_.size(), -1);
  if (o_.compute_covariance)
    computeCovariances(cov, index);

  writePoints(result, cov, index);
  writeMotion(result);
  return result;
}

} // namespace

bool refineAvailable() { return true; }

RefineResult refineWindow(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                          const std::vector<PointEstimate> &initial, const RefineOptions &options)
{
  Refiner refiner(camera, rig, input, initial, options);
  return refiner.run();
}

} // namespace yawdepth
