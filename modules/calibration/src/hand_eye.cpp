/*!
  \file hand_eye.cpp
  \brief Hand-eye calibration: PnP per view, ViSP's vpHandEyeCalibration for a start, then the joint
  Levenberg–Marquardt refinement of X and Y on the reprojection error (see hand_eye.h).
*/
#include <yawdepth/calibration/hand_eye.h>

#include "board_pose.h"
#include "reprojection.h"
#include "text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>
#include <Eigen/Dense>
#include <visp3/core/vpPoseVector.h>
#include <visp3/vision/vpHandEyeCalibration.h>
#include "quiet_visp.h"
#include <yawdepth/error.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

namespace {

using calibration_detail::fixed;
using calibration_detail::kDeg;
using calibration_detail::num;

constexpr int kPoseParams = 12; // X: translation (3), rotation vector (3); Y: the same; then 6 per view

using Iso = Eigen::Isometry3d;

Iso toIso(const vpHomogeneousMatrix &M) { return toIsometry(M); }
vpHomogeneousMatrix toHom(const Iso &T) { return toVisp(T.linear(), T.translation()); }

/* A pose moved by a parameter increment: translation added in the parent frame, rotation on the
   right (about the pose's own axes). */
Iso perturbed(const Iso &T0, const double *p)
{
  Iso T = Iso::Identity();
  T.linear() = T0.linear() * expSO3<double>(Eigen::Vector3d(p[3], p[4], p[5]));
  T.translation() = T0.translation() + Eigen::Vector3d(p[0], p[1], p[2]);
  return T;
}

/* The views' board points, pixels and pixel residual count (BoardObservations), the hand poses,
   and the whitened residuals of increments p about X0, Y0, E0 (and S0, the board's scale, when
   free_scale: the board's points are S0 + p[12] times the given ones). */
struct HandEyeProblem : calibration_detail::BoardObservations {
  const CameraModel *camera = nullptr;
  bool in_hand = true;
  bool free_scale = false;                            // the board's scale is a 13th global parameter
  std::vector<Iso> rMe;                               // per view: the measured hand pose
  std::vector<Iso> A;                                 // per view: eMr (eye-in-hand) or rMe (eye-to-hand)
  Iso X0 = Iso::Identity(), Y0 = Iso::Identity();     // linearisation points of the parameters
  double S0 = 1.0;                                    // the board's scale (1: as given)
  std::vector<Iso> E0;                                // per view: the estimated hand pose (starts at rMe)
  double inv_px = 1, inv_t = 1, inv_r = 1;            // whitening

  /* X, Y, then the scale when free; then 6 per view. */
  int globals() const { return kPoseParams + (free_scale ? 1 : 0); }
  int params() const { return globals() + 6 * static_cast<int>(A.size()); }
  double scale(const Eigen::VectorXd &p) const { return free_scale ? S0 + p[kPoseParams] : S0; }
  /* The hand pose of view i, moved by its kinematic error (about the hand's own axes). */
  Iso hand(const Eigen::VectorXd &p, std::size_t i) const
  {
    const double *d = p.data() + globals() + 6 * i;
    Iso T = Iso::Identity();
    T.linear() = expSO3<double>(Eigen::Vector3d(d[3], d[4], d[5]));
    T.translation() = Eigen::Vector3d(d[0], d[1], d[2]);
    return E0[i] * T;
  }
  /* cMo of view i: X^-1 A_i Y. */
  Iso cMo(const Eigen::VectorXd &p, std::size_t i) const
  {
    const Iso H = hand(p, i);
    return perturbed(X0, p.data()).inverse() * (in_hand ? H.inverse() : H) * perturbed(Y0, p.data() + 6);
  }
  /* View i's departure of its hand pose from the measured one over the kinematics' sigmas
     (translation in the hand frame, rotation vector), into r from k on. */
  void priorResiduals(const Eigen::VectorXd &p, std::size_t i, Eigen::VectorXd &r, Eigen::Index &k) const
  {
    const Iso D = rMe[i].inverse() * hand(p, i);
    const Eigen::Vector3d t = D.translation(), w = logSO3(D.linear());
    for (int a = 0; a < 3; ++a)
      r[k++] = t(a) * inv_t;
    for (int a = 0; a < 3; ++a)
      r[k++] = w(a) * inv_r;
  }
  /* Whitened residuals: the pixels over sigma_px, then each hand pose's prior. */
  Eigen::VectorXd residual(const Eigen::VectorXd &p) const
  {
    Eigen::VectorXd r(static_cast<Eigen::Index>(residuals + 6 * A.size()));
    Eigen::Index k = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      pixelResiduals(*camera, cMo(p, i), i, inv_px, r, k, scale(p));
    for (std::size_t i = 0; i < A.size(); ++i)
      priorResiduals(p, i, r, k);
    return r;
  }
  /* View i's residuals alone: its pixels, then its prior. */
  Eigen::VectorXd viewResidual(const Eigen::VectorXd &p, std::size_t i) const
  {
    Eigen::VectorXd r(static_cast<Eigen::Index>(2 * points[i].size() + 6));
    Eigen::Index k = 0;
    pixelResiduals(*camera, cMo(p, i), i, inv_px, r, k, scale(p));
    priorResiduals(p, i, r, k);
    return r;
  }
  /* The pixel part of a residual vector, in pixels. */
  double pixelSse(const Eigen::VectorXd &r) const
  {
    return r.head(static_cast<Eigen::Index>(residuals)).squaredNorm() / (inv_px * inv_px);
  }
  /* The Gauss-Newton normal equations at zero increments, H = J^T J and g = J^T r, by central
     differences (step 1e-7 m and rad: well above round-off, far below the noise) view by view: a
     hand pose moves its own view's residuals only, so its columns cost one view's residuals (the
     same numbers as the whole Jacobian's, without its zeros). */
  void normalEquations(Eigen::MatrixXd &H, Eigen::VectorXd &g) const
  {
    const int ng = globals(), np = params();
    const std::size_t n = A.size();
    constexpr double h = 1e-7;
    H = Eigen::MatrixXd::Zero(np, np);
    g = Eigen::VectorXd::Zero(np);
    std::vector<Eigen::MatrixXd> Jg(n), Jh(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Index rows = static_cast<Eigen::Index>(2 * points[i].size() + 6);
      Jg[i].resize(rows, ng);
      Jh[i].resize(rows, 6);
    }
    Eigen::VectorXd q = Eigen::VectorXd::Zero(np);
    for (int c = 0; c < ng; ++c) {
      q[c] = h;
      std::vector<Eigen::VectorXd> plus(n);
      for (std::size_t i = 0; i < n; ++i)
        plus[i] = viewResidual(q, i);
      q[c] = -h;
      for (std::size_t i = 0; i < n; ++i)
        Jg[i].col(c) = (plus[i] - viewResidual(q, i)) / (2 * h);
      q[c] = 0;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const int first = ng + 6 * static_cast<int>(i);
      for (int c = 0; c < 6; ++c) {
        q[first + c] = h;
        const Eigen::VectorXd plus = viewResidual(q, i);
        q[first + c] = -h;
        Jh[i].col(c) = (plus - viewResidual(q, i)) / (2 * h);
        q[first + c] = 0;
      }
      const Eigen::VectorXd r = viewResidual(q, i);
      H.topLeftCorner(ng, ng) += Jg[i].transpose() * Jg[i];
      H.block(0, first, ng, 6) = Jg[i].transpose() * Jh[i];
      H.block(first, 0, 6, ng) = H.block(0, first, ng, 6).transpose();
      H.block(first, first, 6, 6) = Jh[i].transpose() * Jh[i];
      g.head(ng) += Jg[i].transpose() * r;
      g.segment(first, 6) = Jh[i].transpose() * r;
    }
  }
  double viewRms(const Eigen::VectorXd &p, std::size_t i) const
  {
    const Iso M = cMo(p, i);
    double se = 0;
    for (std::size_t j = 0; j < points[i].size(); ++j) {
      const Eigen::Vector3d P = M * (scale(p) * points[i][j]);
      const Eigen::Vector2d uv = camera->project(Eigen::Vector2d(P.x() / P.z(), P.y() / P.z()));
      se += (uv - pixels[i][j]).squaredNorm();
    }
    return std::sqrt(se / (2.0 * points[i].size()));
  }
};

/* The best Y for a given X: the average over views of X cMo_i's board pose seen through A_i
   (Y_i = A_i^-1 X cMo_i), rotations averaged by their rotation vectors about the first. */
Iso averageY(const Iso &X, const std::vector<Iso> &A, const std::vector<Iso> &cMo)
{
  const Iso Y_ref = A[0].inverse() * X * cMo[0];
  Eigen::Vector3d t = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < A.size(); ++i) {
    const Iso Yi = A[i].inverse() * X * cMo[i];
    t += Yi.translation();
    w += logSO3(Y_ref.linear().transpose() * Yi.linear());
  }
  Iso Y = Iso::Identity();
  Y.translation() = t / static_cast<double>(A.size());
  Y.linear() = Y_ref.linear() * expSO3<double>(Eigen::Vector3d(w / static_cast<double>(A.size())));
  return Y;
}

/* A robot pose, refused when not finite or its rotation not a rotation matrix. */
void checkRobotPose(const vpHomogeneousMatrix &rMe, const std::string &name)
{
  for (unsigned a = 0; a < 3; ++a)
    for (unsigned b = 0; b < 4; ++b)
      if (!std::isfinite(rMe[a][b]))
        throw Error(name + ": the robot pose is not finite");
  if (!rMe.isAnHomogeneousMatrix(1e-6))
    throw Error(name + ": the robot pose's rotation is not a rotation matrix");
}

/* One view whose board pose PnP finds: its board points and pixels, the pose, its input's index. */
struct BoardView {
  std::size_t input = 0;
  Iso cMo = Iso::Identity();
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  std::string name;
};

/* The views (features and names) whose board pose PnP finds; the others into skipped, with the
   reason. */
std::vector<BoardView> boardViews(const CameraModel &camera, const BoardLayout &board,
                                  const std::vector<const std::vector<FeatureObservation> *> &features,
                                  const std::vector<std::string> &names, int min_points,
                                  std::vector<std::string> &skipped)
{
  const std::map<long, Eigen::Vector3d> pts = calibration_detail::boardPoints(board);
  std::vector<BoardView> out;
  for (std::size_t i = 0; i < features.size(); ++i) {
    BoardView v;
    v.input = i;
    v.name = names[i];
    if (!calibration_detail::boardPoseByPnP(camera, pts, *features[i], min_points, v.cMo, v.points, v.pixels)) {
      skipped.push_back(names[i] + ": " + std::to_string(v.points.size()) + " usable features, or no board pose");
      continue;
    }
    out.push_back(std::move(v));
  }
  return out;
}

/* Refused when the rotations between the poses turn about a single axis (they must turn about at
   least two different ones). */
void checkTwoRotationAxes(const std::vector<Iso> &A)
{
  const std::size_t n = A.size();
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (std::size_t i = 1; i < n; ++i) {
    const Eigen::Vector3d w = logSO3(A[0].linear().transpose() * A[i].linear());
    S += w * w.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
  const double second = std::sqrt(std::max(0.0, es.eigenvalues()(1)) / static_cast<double>(n - 1));
  if (!(second > 2 * kDeg))
    throw Error("the robot poses turn about a single axis (second rotation spread " + fixed(second / kDeg, 2) +
                " deg): the hand-eye pose is not determined; rotate the hand about two different axes");
}

/* The start of X: ViSP's closed form (and its own refinement of AX = XB). */
vpHomogeneousMatrix vispHandEyeStart(const std::vector<vpHomogeneousMatrix> &visp_cMo,
                                     const std::vector<vpHomogeneousMatrix> &visp_B)
{
  vpHomogeneousMatrix X_visp;
  int visp_status = 0;
  {
    const detail::QuietVisp quiet(true); // vpHandEyeCalibration prints its iterations with printf
    visp_status = vpHandEyeCalibration::calibrate(visp_cMo, visp_B, X_visp);
  }
  if (visp_status != 0)
    throw Error("vpHandEyeCalibration failed on these poses (degenerate or inconsistent robot poses)");
  return X_visp;
}

/* Levenberg–Marquardt on X, Y (the scale when free) and the hand poses, relinearising after each
   accepted step (pb's X0, Y0, S0 and E0 move, the parameters stay zero); r and cost: the residuals
   at zero and their squared norm, then at the solution. */
void refineHandEye(HandEyeProblem &pb, Eigen::VectorXd &r, double &cost)
{
  double lambda = 1e-3;
  for (int it = 0; it < 100; ++it) {
    Eigen::MatrixXd H;
    Eigen::VectorXd g;
    pb.normalEquations(H, g);
    bool accepted = false;
    double step = 0;
    for (int k = 0; k < 20 && !accepted; ++k) {
      const Eigen::VectorXd dx = calibration_detail::dampedStep(H, g, lambda);
      const Eigen::VectorXd r_new = pb.residual(dx);
      const double c_new = r_new.squaredNorm();
      if (std::isfinite(c_new) && c_new < cost) {
        for (std::size_t i = 0; i < pb.E0.size(); ++i)
          pb.E0[i] = pb.hand(dx, i);
        pb.X0 = perturbed(pb.X0, dx.data());
        pb.Y0 = perturbed(pb.Y0, dx.data() + 6);
        pb.S0 = pb.scale(dx);
        r = r_new;
        step = (cost - c_new) / cost;
        cost = c_new;
        lambda = std::max(lambda / 3, 1e-9);
        accepted = true;
      } else {
        lambda *= 10;
      }
    }
    if (!accepted || step < 1e-12)
      break;
  }
}

/* The largest correction of a measured hand pose into out (mm, deg); refused when one is beyond
   options.max_pose_correction_sigmas of the kinematics, or the RMS beyond options.max_rms_px. */
void checkHandPoses(const HandEyeProblem &pb, const HandEyeOptions &options, HandEyeCalibration &out)
{
  double worst_sigmas = 0;
  for (std::size_t i = 0; i < pb.rMe.size(); ++i) {
    const Iso D = pb.rMe[i].inverse() * pb.E0[i];
    out.pose_correction_mm = std::max(out.pose_correction_mm, 1e3 * D.translation().norm());
    out.pose_correction_deg = std::max(out.pose_correction_deg, Eigen::AngleAxisd(D.linear()).angle() / kDeg);
    worst_sigmas = std::max({worst_sigmas, D.translation().cwiseAbs().maxCoeff() * pb.inv_t,
                             logSO3(D.linear()).cwiseAbs().maxCoeff() * pb.inv_r});
  }
  if (!(worst_sigmas <= options.max_pose_correction_sigmas))
    throw Error("the hand-eye fit failed: a hand pose had to move by " + fixed(out.pose_correction_mm, 1) + " mm and " +
                fixed(out.pose_correction_deg, 2) + " deg (" + fixed(worst_sigmas, 0) +
                " sigma of the kinematics) to fit its image: check that the robot poses belong to these images, "
                "are in metres and radians, and that the setup (eye-in-hand or eye-to-hand) is right");
  if (!(out.rms_px <= options.max_rms_px))
    throw Error("the hand-eye fit failed: reprojection RMS " + fixed(out.rms_px, 2) + " px (more than " +
                fixed(options.max_rms_px, 1) + "): check that the robot poses belong to these images, are in metres "
                "and radians, and that the setup (eye-in-hand or eye-to-hand) is right");
}

/* Covariance at the solution (parameters are increments about it): (J^T J)^-1 of the whitened
   problem, scaled by the variance factor when the residuals are larger than the noise model. */
Eigen::MatrixXd handEyeCovariance(const HandEyeProblem &pb, double cost)
{
  const int np = pb.params();
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  pb.normalEquations(H, g);
  const double dof = static_cast<double>(pb.residuals) - pb.globals();
  const double s2 = std::max(1.0, cost / dof);
  return H.ldlt().solve(Eigen::MatrixXd::Identity(np, np)) * s2;
}

/* The 1-sigma of X and Y into out, refused when not finite. */
void storeHandEyeSigmas(const HandEyeProblem &pb, double cost, HandEyeCalibration &out)
{
  const Eigen::MatrixXd cov = handEyeCovariance(pb, cost);
  for (int k = 0; k < 6; ++k) {
    out.camera_pose_sigma(k) = std::sqrt(std::max(0.0, cov(k, k)));
    out.target_pose_sigma(k) = std::sqrt(std::max(0.0, cov(6 + k, 6 + k)));
  }
  if (!out.camera_pose_sigma.allFinite() || !out.target_pose_sigma.allFinite())
    throw Error("the hand-eye pose is not determined by these views (singular information)");
}

/* The problem without views [from, to). */
HandEyeProblem withoutViews(const HandEyeProblem &pb, std::size_t from, std::size_t to)
{
  HandEyeProblem out = pb;
  out.points.clear();
  out.pixels.clear();
  out.residuals = 0;
  out.rMe.clear();
  out.A.clear();
  out.E0.clear();
  for (std::size_t i = 0; i < pb.A.size(); ++i) {
    if (i >= from && i < to)
      continue;
    std::vector<Eigen::Vector3d> P = pb.points[i];
    std::vector<Eigen::Vector2d> uv = pb.pixels[i];
    out.add(std::move(P), std::move(uv));
    out.rMe.push_back(pb.rMe[i]);
    out.A.push_back(pb.A[i]);
    out.E0.push_back(pb.E0[i]);
  }
  return out;
}

/* The board's scale as the solution's views see it: the same fit from it with the scale free
   (the hand poses' metric motion tells it; X, Y and every hand pose move with it); the problem
   itself is left as it is (the result keeps the size given). Its 1-sigma: the larger of the
   covariance's and a delete-a-group jackknife's over up to kGroups blocks of views. The
   covariance trusts the kinematics' prior; an arm's kinematic errors are larger and systematic
   (the franka's hand poses move by up to 5.7 mm for a prior of 1 mm), and they move the scale
   together: the jackknife measures that spread. */
BoardScaleCheck boardScaleOf(const HandEyeProblem &solved, const BoardLayout &board, const HandEyeOptions &options)
{
  HandEyeProblem pb = solved;
  pb.free_scale = true;
  pb.S0 = 1.0;
  Eigen::VectorXd r = pb.residual(Eigen::VectorXd::Zero(pb.params()));
  double cost = r.squaredNorm();
  refineHandEye(pb, r, cost);
  // The covariance with the worse of the two variance factors: the corners' (as handEyeCovariance())
  // and the kinematics' own, from the hand poses' corrections (Förstner's variance component: their
  // whitened squares over their redundancy, 6n minus the prior rows' share of the hat matrix). The
  // scale is told by the hand's motion, so by the kinematics' real errors, not the assumed ones.
  const int np = pb.params(), ng = pb.globals();
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  pb.normalEquations(H, g);
  const Eigen::MatrixXd Hinv = H.ldlt().solve(Eigen::MatrixXd::Identity(np, np));
  const std::size_t n = pb.A.size();
  const Eigen::Index prior_rows = static_cast<Eigen::Index>(6 * n);
  const double prior_chi2 = r.tail(prior_rows).squaredNorm();
  double hat = 0; // the prior rows' share: sum over the hand parameters of (d r / d p)^2 Hinv (about the solution, d r / d p = the whitening)
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 6; ++a) {
      const double w = a < 3 ? pb.inv_t : pb.inv_r;
      const Eigen::Index c = ng + static_cast<Eigen::Index>(6 * i) + a;
      hat += w * w * Hinv(c, c);
    }
  const double redundancy = static_cast<double>(prior_rows) - hat;
  const double f_kin = redundancy > 1 ? prior_chi2 / redundancy : 1.0;
  const double f_px = (cost - prior_chi2) / std::max(1.0, static_cast<double>(pb.residuals) - ng);
  double sigma = std::sqrt(std::max(0.0, Hinv(kPoseParams, kPoseParams)) * std::max({1.0, f_px, f_kin}));
  if (!std::isfinite(sigma) || !std::isfinite(pb.S0))
    return BoardScaleCheck(); // not determined by these views
  constexpr std::size_t kGroups = 10;
  const std::size_t groups = std::min(n, kGroups);
  std::vector<double> estimates;
  for (std::size_t g = 0; g < groups && n > 3; ++g) {
    HandEyeProblem part = withoutViews(pb, g * n / groups, (g + 1) * n / groups);
    Eigen::VectorXd rp = part.residual(Eigen::VectorXd::Zero(part.params()));
    double cp = rp.squaredNorm();
    refineHandEye(part, rp, cp);
    if (std::isfinite(part.S0))
      estimates.push_back(part.S0);
  }
  sigma = std::max(sigma, calibration_detail::jackknifeSigma(estimates));
  // The resolution: what tells the scale from a shift of the camera along its axis is how the
  // camera's distance to the board differs between the views (all at one distance, the two are
  // the same). An arm's kinematics err by sigma_pose_translation in a way that varies smoothly over
  // its workspace, not independently per pose: an error that grows with the distance by that much
  // over the distances' spread is a scale error of sigma_pose_translation / spread, which neither
  // the covariance nor a jackknife over a few poses sees (measured on the franka set: 1.13 +- 0.02
  // with the size printed, 1.07 with 25 mm typed; its 8 views span a few centimetres of distance).
  std::vector<double> distance;
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d &P : pb.points[i])
      centre += P / static_cast<double>(pb.points[i].size());
    distance.push_back((pb.cMo(Eigen::VectorXd::Zero(pb.params()), i) * (pb.S0 * centre)).norm());
  }
  double mean = 0, spread = 0;
  for (double d : distance)
    mean += d / static_cast<double>(n);
  for (double d : distance)
    spread += (d - mean) * (d - mean) / static_cast<double>(n);
  spread = std::sqrt(spread);
  const double resolution = options.sigma_pose_translation / std::max(spread, 1e-9);
  BoardScaleCheck c = checkBoardScale(pb.S0, std::max(sigma, resolution), board, options.board_scale);
  c.distance_spread = spread;
  return c;
}

/* One hand-eye solve over the board views with their hand poses rMe: the calibration, and the
   whitened cost (pixels and priors) with its size. `final`: the refusals, the sigmas and the
   board scale check (a profile over time offsets only wants the cost). */
struct HandEyeSolve {
  HandEyeCalibration cal;
  double cost = 0;          // whitened sum of squares (pixels over sigma_px, the priors)
  double residuals = 0;     // its number of terms
  double parameters = 0;    // X, Y and the hand poses
};

HandEyeSolve solveHandEye(const CameraModel &camera, const BoardLayout &board, const std::vector<BoardView> &views,
                          const std::vector<vpHomogeneousMatrix> &robot, const HandEyeOptions &options, bool final,
                          const HandEyeSolve *start = nullptr)
{
  HandEyeSolve res;
  HandEyeCalibration &out = res.cal;
  out.setup = options.setup;
  HandEyeProblem pb;
  pb.camera = &camera;
  std::vector<Iso> cMo0;
  std::vector<vpHomogeneousMatrix> visp_cMo, visp_B;
  for (std::size_t k = 0; k < views.size(); ++k) {
    const BoardView &v = views[k];
    checkRobotPose(robot[k], v.name);
    const Iso rMe = toIso(robot[k]);
    // cMo_i = X^-1 A_i Y; ViSP's solver takes B_i X cMo_i = const with B_i = A_i^-1.
    const Iso A = options.setup == HandEyeSetup::EyeInHand ? rMe.inverse() : rMe;
    cMo0.push_back(v.cMo);
    pb.A.push_back(A);
    pb.rMe.push_back(rMe);
    visp_cMo.push_back(toHom(v.cMo));
    visp_B.push_back(toHom(A.inverse()));
    std::vector<Eigen::Vector3d> P = v.points;
    std::vector<Eigen::Vector2d> uv = v.pixels;
    pb.add(std::move(P), std::move(uv));
    out.view_names.push_back(v.name);
  }
  const std::size_t n = pb.A.size();
  if (n < 3)
    throw Error("too few views: the board was usable in " + std::to_string(n) +
                " image(s); a hand-eye calibration needs at least 3 (better 8 or more) robot poses");
  checkTwoRotationAxes(pb.A);

  // The start: ViSP's closed form, or (a profile over time offsets) the solution at a neighbouring
  // offset, which the same minimum is a few iterations from.
  const vpHomogeneousMatrix X_visp =
      start != nullptr ? start->cal.initial_camera_pose : vispHandEyeStart(visp_cMo, visp_B);
  out.initial_camera_pose = X_visp;
  pb.X0 = toIso(start != nullptr ? start->cal.camera_pose : X_visp);
  pb.Y0 = start != nullptr ? toIso(start->cal.target_pose) : averageY(pb.X0, pb.A, cMo0);
  pb.E0 = pb.rMe;
  pb.in_hand = options.setup == HandEyeSetup::EyeInHand;
  pb.inv_px = 1.0 / std::max(options.sigma_px, 1e-6);
  pb.inv_t = 1.0 / std::max(options.sigma_pose_translation, 1e-9);
  pb.inv_r = 1.0 / std::max(options.sigma_pose_rotation, 1e-9);
  if (pb.residuals <= static_cast<std::size_t>(kPoseParams))
    throw Error("too few points for a hand-eye calibration");

  const Eigen::VectorXd p = Eigen::VectorXd::Zero(pb.params()); // increments about X0, Y0, E0
  Eigen::VectorXd r = pb.residual(p);
  out.initial_rms_px = std::sqrt(pb.pixelSse(r) / static_cast<double>(pb.residuals));
  double cost = r.squaredNorm();
  refineHandEye(pb, r, cost);
  out.points = static_cast<int>(pb.residuals / 2);
  out.views = static_cast<int>(n);
  out.rms_px = std::sqrt(pb.pixelSse(r) / static_cast<double>(pb.residuals));
  out.camera_pose = toHom(pb.X0);
  out.target_pose = toHom(pb.Y0);
  res.cost = cost;
  res.residuals = static_cast<double>(r.size());
  res.parameters = pb.params();
  if (!final)
    return res;
  try {
    checkHandPoses(pb, options, out);
  } catch (const Error &failed) {
    // A wrong board size that the hand poses cannot absorb: say so, it is the likelier mistake.
    if (!options.check_board_scale)
      throw;
    BoardScaleCheck c;
    try {
      c = boardScaleOf(pb, board, options);
    } catch (const Error &gross) {
      throw Error(std::string(failed.what()) + "; " + gross.what());
    }
    if (c.status == BoardScaleStatus::Mismatch)
      throw Error(std::string(failed.what()) + "; " + c.message);
    throw;
  }
  for (std::size_t i = 0; i < n; ++i)
    out.view_rms_px.push_back(pb.viewRms(p, i));
  storeHandEyeSigmas(pb, cost, out);
  if (options.check_board_scale)
    out.board_scale = boardScaleOf(pb, board, options);
  return res;
}

} // namespace

HandEyeSetup handEyeSetupFromString(const std::string &word)
{
  if (word == "eye-in-hand")
    return HandEyeSetup::EyeInHand;
  if (word == "eye-to-hand")
    return HandEyeSetup::EyeToHand;
  throw Error("unknown hand-eye setup '" + word + "' (eye-in-hand or eye-to-hand)");
}

HandEyeCalibration calibrateHandEye(const CameraModel &camera, const BoardLayout &board,
                                    const std::vector<HandEyeView> &views, const HandEyeOptions &options)
{
  options.board_scale.validate();
  std::vector<const std::vector<FeatureObservation> *> features;
  std::vector<std::string> names;
  for (const HandEyeView &v : views) {
    checkRobotPose(v.rMe, v.name);
    features.push_back(&v.features);
    names.push_back(v.name);
  }
  std::vector<std::string> skipped;
  const std::vector<BoardView> board_views =
      boardViews(camera, board, features, names, options.min_points_per_view, skipped);
  std::vector<vpHomogeneousMatrix> robot;
  robot.reserve(board_views.size());
  for (const BoardView &v : board_views)
    robot.push_back(views[v.input].rMe);
  HandEyeCalibration out = solveHandEye(camera, board, board_views, robot, options, true).cal;
  out.skipped = skipped;
  return out;
}

TimedHandEyeCalibration calibrateHandEyeWithTimeOffset(const CameraModel &camera, const BoardLayout &board,
                                                       const MotionLog &motion, const std::vector<double> &image_times,
                                                       const std::vector<std::vector<FeatureObservation>> &features,
                                                       const std::vector<std::string> &names,
                                                       const HandEyeOptions &options, const TimeOffsetSearch &search,
                                                       double max_pose_gap)
{
  options.board_scale.validate();
  if (image_times.size() != features.size() || names.size() != features.size())
    throw Error("time offset: " + std::to_string(image_times.size()) + " image times and " +
                std::to_string(names.size()) + " names for " + std::to_string(features.size()) + " detections");
  if (motion.samples.empty() || !motion.samples.front().six_dof)
    throw Error("time offset: --hand-eye needs the hand's 6-DoF poses (a TUM, EuRoC or 6-DoF yawdepth log)");
  // Each image's board pose once: only the hand poses change with the offset.
  std::vector<const std::vector<FeatureObservation> *> feature_ptrs;
  feature_ptrs.reserve(features.size());
  for (const auto &f : features)
    feature_ptrs.push_back(&f);
  std::vector<std::string> skipped;
  const std::vector<BoardView> all =
      boardViews(camera, board, feature_ptrs, names, options.min_points_per_view, skipped);
  std::vector<bool> usable(features.size(), false);
  std::map<std::size_t, std::size_t> view_of; // image index -> its board view
  for (std::size_t k = 0; k < all.size(); ++k) {
    usable[all[k].input] = true;
    view_of[all[k].input] = k;
  }
  const auto viewsOf = [&](const std::vector<MotionSample> &samples, const std::vector<std::size_t> &images,
                           std::vector<BoardView> &views, std::vector<vpHomogeneousMatrix> &robot) {
    for (std::size_t k = 0; k < images.size(); ++k) {
      views.push_back(all[view_of.at(images[k])]);
      robot.push_back(wMv(samples[k]));
    }
  };
  HandEyeOptions profile_options = options;
  profile_options.check_board_scale = false;
  std::optional<HandEyeSolve> last; // the previous offset's solution: the next one's start
  const auto cost = [&](const std::vector<MotionSample> &samples, const std::vector<std::size_t> &images) {
    std::vector<BoardView> views;
    std::vector<vpHomogeneousMatrix> robot;
    viewsOf(samples, images, views, robot);
    // A wrong offset fits badly (its hand poses move): that is its cost, not a refusal.
    const HandEyeSolve s =
        solveHandEye(camera, board, views, robot, profile_options, false, last ? &*last : nullptr);
    last = s;
    ProfileCost c;
    c.sum_squares = s.cost;
    c.residuals = s.residuals;
    c.parameters = s.parameters;
    return c;
  };
  const TimedImagesOffset found = estimateTimeOffsetOverImages(motion, image_times, usable, cost, search, max_pose_gap);
  std::vector<BoardView> views;
  std::vector<vpHomogeneousMatrix> robot;
  viewsOf(found.samples, found.images, views, robot);
  TimedHandEyeCalibration out;
  out.hand_eye = solveHandEye(camera, board, views, robot, options, true).cal;
  out.hand_eye.skipped = skipped;
  out.time_offset = found.estimate;
  out.images_used = static_cast<int>(found.images.size());
  return out;
}

std::string handEyeRigYaml(const HandEyeCalibration &cal)
{
  const vpPoseVector X(cal.camera_pose);
  const bool in_hand = cal.setup == HandEyeSetup::EyeInHand;
  std::ostringstream s;
  s << "# yawdepth calibrate-rig --hand-eye " << (in_hand ? "eye-in-hand" : "eye-to-hand") << ": " << cal.views
    << " views, " << cal.points << " corners, reprojection RMS " << fixed(cal.rms_px, 3) << " px\n";
  s << "# camera_pose: the camera in the " << (in_hand ? "end-effector (eMc)" : "robot base (rMc)")
    << " as a vpPoseVector: tx ty tz (m), theta-u (rad)\n";
  s << "camera_pose: [" << num(X[0]) << ", " << num(X[1]) << ", " << num(X[2]) << ", " << num(X[3]) << ", "
    << num(X[4]) << ", " << num(X[5]) << "]\n";
  s << "# 1-sigma: translation (m), rotation about the camera pose's own axes (rad)\n";
  s << "camera_pose_sigma: [";
  for (int k = 0; k < 6; ++k)
    s << (k ? ", " : "") << num(cal.camera_pose_sigma(k));
  s << "]\n";
  s << "reprojection_rms_px: " << num(cal.rms_px) << "\n";
  if (cal.board_scale.status != BoardScaleStatus::NotEstimated)
    s << "# the board's size as the hand's motion sees it: " << fixed(cal.board_scale.scale, 4) << " +- "
      << fixed(cal.board_scale.sigma, 4) << " times the size given (" << toString(cal.board_scale.status) << ")\n";
  return s.str();
}

} // namespace yawdepth
