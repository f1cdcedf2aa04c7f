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
   and the whitened residuals of increments p about X0, Y0 and E0. */
struct HandEyeProblem : calibration_detail::BoardObservations {
  const CameraModel *camera = nullptr;
  bool in_hand = true;
  std::vector<Iso> rMe;                               // per view: the measured hand pose
  std::vector<Iso> A;                                 // per view: eMr (eye-in-hand) or rMe (eye-to-hand)
  Iso X0 = Iso::Identity(), Y0 = Iso::Identity();     // linearisation points of the parameters
  std::vector<Iso> E0;                                // per view: the estimated hand pose (starts at rMe)
  double inv_px = 1, inv_t = 1, inv_r = 1;            // whitening

  int params() const { return kPoseParams + 6 * static_cast<int>(A.size()); }
  /* The hand pose of view i, moved by its kinematic error (about the hand's own axes). */
  Iso hand(const Eigen::VectorXd &p, std::size_t i) const
  {
    const double *d = p.data() + kPoseParams + 6 * i;
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
  /* Whitened residuals: the pixels over sigma_px, then each hand pose's departure from the
     measured one over the kinematics' sigmas (translation in the hand frame, rotation vector). */
  Eigen::VectorXd residual(const Eigen::VectorXd &p) const
  {
    Eigen::VectorXd r(static_cast<Eigen::Index>(residuals + 6 * A.size()));
    Eigen::Index k = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      pixelResiduals(*camera, cMo(p, i), i, inv_px, r, k);
    for (std::size_t i = 0; i < A.size(); ++i) {
      const Iso D = rMe[i].inverse() * hand(p, i);
      const Eigen::Vector3d t = D.translation(), w = logSO3(D.linear());
      for (int a = 0; a < 3; ++a)
        r[k++] = t(a) * inv_t;
      for (int a = 0; a < 3; ++a)
        r[k++] = w(a) * inv_r;
    }
    return r;
  }
  /* The pixel part of a residual vector, in pixels. */
  double pixelSse(const Eigen::VectorXd &r) const
  {
    return r.head(static_cast<Eigen::Index>(residuals)).squaredNorm() / (inv_px * inv_px);
  }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd &p) const
  {
    std::vector<int> all(static_cast<std::size_t>(params()));
    for (std::size_t c = 0; c < all.size(); ++c)
      all[c] = static_cast<int>(c);
    // Step 1e-7 (m and rad): well above round-off, far below the noise.
    return calibration_detail::centralJacobian([this](const Eigen::VectorXd &q) { return residual(q); }, p, all, 1e-7,
                                               static_cast<Eigen::Index>(residuals + 6 * A.size()));
  }
  double viewRms(const Eigen::VectorXd &p, std::size_t i) const
  {
    const Iso M = cMo(p, i);
    double se = 0;
    for (std::size_t j = 0; j < points[i].size(); ++j) {
      const Eigen::Vector3d P = M * points[i][j];
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

/* A view's robot pose, refused when not finite or its rotation not a rotation matrix. */
void checkRobotPose(const HandEyeView &v)
{
  for (unsigned a = 0; a < 3; ++a)
    for (unsigned b = 0; b < 4; ++b)
      if (!std::isfinite(v.rMe[a][b]))
        throw Error(v.name + ": the robot pose is not finite");
  if (!v.rMe.isAnHomogeneousMatrix(1e-6))
    throw Error(v.name + ": the robot pose's rotation is not a rotation matrix");
}

/* The views whose board pose PnP finds: into pb (A_i, rMe, points and pixels), cMo0, ViSP's
   inputs (cMo_i, B_i = A_i^-1) and out.view_names; the others into out.skipped. */
void collectHandEyeViews(const CameraModel &camera, const BoardLayout &board, const std::vector<HandEyeView> &views,
                         const HandEyeOptions &options, HandEyeProblem &pb, std::vector<Iso> &cMo0,
                         std::vector<vpHomogeneousMatrix> &visp_cMo, std::vector<vpHomogeneousMatrix> &visp_B,
                         HandEyeCalibration &out)
{
  const std::map<long, Eigen::Vector3d> pts = calibration_detail::boardPoints(board);
  for (const HandEyeView &v : views) {
    checkRobotPose(v);
    std::vector<Eigen::Vector3d> P;
    std::vector<Eigen::Vector2d> uv;
    Iso M;
    if (!calibration_detail::boardPoseByPnP(camera, pts, v.features, options.min_points_per_view, M, P, uv)) {
      out.skipped.push_back(v.name + ": " + std::to_string(P.size()) + " usable features, or no board pose");
      continue;
    }
    const Iso rMe = toIso(v.rMe);
    // cMo_i = X^-1 A_i Y; ViSP's solver takes B_i X cMo_i = const with B_i = A_i^-1.
    const Iso A = options.setup == HandEyeSetup::EyeInHand ? rMe.inverse() : rMe;
    cMo0.push_back(M);
    pb.A.push_back(A);
    pb.rMe.push_back(rMe);
    visp_cMo.push_back(toHom(M));
    visp_B.push_back(toHom(A.inverse()));
    pb.add(std::move(P), std::move(uv));
    out.view_names.push_back(v.name);
  }
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

/* Levenberg–Marquardt on X, Y and the hand poses, relinearising after each accepted step (pb's
   X0, Y0 and E0 move, the parameters stay zero); r and cost: the residuals at zero and their
   squared norm, then at the solution. */
void refineHandEye(HandEyeProblem &pb, Eigen::VectorXd &r, double &cost)
{
  double lambda = 1e-3;
  for (int it = 0; it < 100; ++it) {
    const Eigen::MatrixXd J = pb.jacobian(Eigen::VectorXd::Zero(pb.params()));
    const Eigen::MatrixXd H = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
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
   problem, scaled by the variance factor when the residuals are larger than the noise model; the
   1-sigma of X and Y into out, refused when not finite. */
void storeHandEyeSigmas(const HandEyeProblem &pb, double cost, HandEyeCalibration &out)
{
  const int np = pb.params();
  const Eigen::MatrixXd J = pb.jacobian(Eigen::VectorXd::Zero(np));
  const double dof = static_cast<double>(pb.residuals) - kPoseParams;
  const double s2 = std::max(1.0, cost / dof);
  Eigen::MatrixXd cov = (J.transpose() * J).ldlt().solve(Eigen::MatrixXd::Identity(np, np)) * s2;
  for (int k = 0; k < 6; ++k) {
    out.camera_pose_sigma(k) = std::sqrt(std::max(0.0, cov(k, k)));
    out.target_pose_sigma(k) = std::sqrt(std::max(0.0, cov(6 + k, 6 + k)));
  }
  if (!out.camera_pose_sigma.allFinite() || !out.target_pose_sigma.allFinite())
    throw Error("the hand-eye pose is not determined by these views (singular information)");
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
  HandEyeCalibration out;
  out.setup = options.setup;
  HandEyeProblem pb;
  pb.camera = &camera;
  std::vector<Iso> cMo0;
  std::vector<vpHomogeneousMatrix> visp_cMo, visp_B;
  collectHandEyeViews(camera, board, views, options, pb, cMo0, visp_cMo, visp_B, out);
  const std::size_t n = pb.A.size();
  if (n < 3)
    throw Error("too few views: the board was usable in " + std::to_string(n) +
                " image(s); a hand-eye calibration needs at least 3 (better 8 or more) robot poses");
  checkTwoRotationAxes(pb.A);

  const vpHomogeneousMatrix X_visp = vispHandEyeStart(visp_cMo, visp_B);
  out.initial_camera_pose = X_visp;
  pb.X0 = toIso(X_visp);
  pb.Y0 = averageY(pb.X0, pb.A, cMo0);
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
  checkHandPoses(pb, options, out);
  out.camera_pose = toHom(pb.X0);
  out.target_pose = toHom(pb.Y0);
  for (std::size_t i = 0; i < n; ++i)
    out.view_rms_px.push_back(pb.viewRms(p, i));
  storeHandEyeSigmas(pb, cost, out);
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
  return s.str();
}

} // namespace yawdepth
