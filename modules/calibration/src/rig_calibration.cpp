/*!
  \file rig_calibration.cpp
  \brief Yaw-rig calibration: camera offset, yaw axis and yaw zero by Levenberg–Marquardt on the
  reprojection error of a static board seen at several yaw readings.
*/
#include <yawdepth/calibration/rig_calibration.h>

#include "board_pose.h"
#include "reprojection.h"
#include "text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

using calibration_detail::fixed;
using calibration_detail::kDeg;
using calibration_detail::num;

constexpr int kParams = 12;
// Parameter layout; P_SCALE: the board's points are 1 + p[P_SCALE] times the given ones (free only
// in the board scale check).
enum { P_AX = 0, P_AZ, P_TX, P_TZ, P_DELTA, P_PSI, P_ALPHA, P_GAMMA, P_BX, P_BY, P_BZ, P_SCALE };



Eigen::Matrix3d rotX(double a)
{
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
Eigen::Matrix3d rotZ(double a)
{
  return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

Eigen::Isometry3d isoWMV(const MotionSample &s)
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.linear() = s.rotation(); // planar (heading) or 6-DoF rows alike
  M.translation() = s.position();
  return M;
}

Eigen::Vector3d axisOf(const Eigen::VectorXd &p)
{
  return Eigen::Vector3d(p[P_AX], 1.0, p[P_AZ]).normalized();
}

/*! Pose of the camera in the vision frame at true yaw theta: [Ra(theta) | Ra(theta) t0]. */
Eigen::Isometry3d vMc(const Eigen::Vector3d &axis, double theta, const Eigen::Vector3d &t0)
{
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.linear() = Eigen::AngleAxisd(theta, axis).toRotationMatrix();
  M.translation() = M.linear() * t0;
  return M;
}

/* The views' board points, pixels and residual count (BoardObservations), the robot's poses and
   yaw readings, and the reprojection residuals of parameters p. */
struct RigProblem : calibration_detail::BoardObservations {
  const CameraModel *camera = nullptr;
  std::vector<Eigen::Isometry3d> v0Mv;                   // vision frame of each view in the first one
  std::vector<double> readings;                          // yaw readings
  double t0y = 0;

  Eigen::Isometry3d board(const Eigen::VectorXd &p) const
  {
    Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
    M.linear() = rotY(p[P_PSI]) * rotX(p[P_ALPHA]) * rotZ(p[P_GAMMA]);
    M.translation() = Eigen::Vector3d(p[P_BX], p[P_BY], p[P_BZ]);
    return M;
  }
  Eigen::Isometry3d cMb(const Eigen::VectorXd &p, std::size_t i) const
  {
    const Eigen::Vector3d t0(p[P_TX], t0y, p[P_TZ]);
    return (v0Mv[i] * vMc(axisOf(p), readings[i] + p[P_DELTA], t0)).inverse() * board(p);
  }
  Eigen::VectorXd residual(const Eigen::VectorXd &p) const
  {
    Eigen::VectorXd r(static_cast<Eigen::Index>(residuals));
    Eigen::Index k = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      pixelResiduals(*camera, cMb(p, i), i, 1.0, r, k, 1.0 + p[P_SCALE]);
    return r;
  }
  Eigen::MatrixXd jacobian(const Eigen::VectorXd &p, const std::vector<int> &free) const
  {
    return calibration_detail::centralJacobian([this](const Eigen::VectorXd &q) { return residual(q); }, p, free, 1e-6,
                                               static_cast<Eigen::Index>(residuals));
  }
};

void eulerYXZ(const Eigen::Matrix3d &R, double &psi, double &alpha, double &gamma)
{
  // R = Ry(psi) Rx(alpha) Rz(gamma): third column (s_psi c_a, -s_a, c_psi c_a), second row (c_a s_g, c_a c_g, -s_a).
  alpha = std::asin(std::clamp(-R(1, 2), -1.0, 1.0));
  psi = std::atan2(R(0, 2), R(2, 2));
  gamma = std::atan2(R(1, 0), R(1, 1));
}

void setBoard(Eigen::VectorXd &p, const Eigen::Isometry3d &M)
{
  eulerYXZ(M.linear(), p[P_PSI], p[P_ALPHA], p[P_GAMMA]);
  p[P_BX] = M.translation().x();
  p[P_BY] = M.translation().y();
  p[P_BZ] = M.translation().z();
}

/* The views whose board pose PnP finds: their points and pixels into pb, their poses into cMb0 and
   their motion samples into samples. */
void collectRigViews(const CameraModel &camera, const BoardLayout &board, const std::vector<RigView> &views,
                     int min_points, RigProblem &pb, std::vector<Eigen::Isometry3d> &cMb0,
                     std::vector<MotionSample> &samples)
{
  const std::map<long, Eigen::Vector3d> pts = calibration_detail::boardPoints(board);
  for (const RigView &v : views) {
    std::vector<Eigen::Vector3d> P;
    std::vector<Eigen::Vector2d> uv;
    Eigen::Isometry3d M;
    if (!calibration_detail::boardPoseByPnP(camera, pts, v.features, min_points, M, P, uv))
      continue;
    cMb0.push_back(M);
    samples.push_back(v.sample);
    pb.add(std::move(P), std::move(uv));
  }
}

/* The yaw readings' distinct values and span into out; refused when too few or too narrow. */
void checkYawReadings(const std::vector<MotionSample> &samples, const RigCalibrationOptions &options, RigCalibration &out)
{
  std::vector<double> yaws;
  yaws.reserve(samples.size());
  for (const auto &s : samples)
    yaws.push_back(s.yaw);
  std::sort(yaws.begin(), yaws.end());
  out.distinct_yaws = 1;
  for (std::size_t i = 1; i < yaws.size(); ++i)
    if (yaws[i] - yaws[i - 1] > 0.2 * kDeg)
      ++out.distinct_yaws;
  out.yaw_span = yaws.back() - yaws.front();
  if (out.distinct_yaws < options.min_distinct_yaws || out.yaw_span < options.min_yaw_span)
    throw Error("yaw readings span only " + fixed(out.yaw_span / kDeg, 1) + " deg over " +
                std::to_string(out.distinct_yaws) + " distinct value(s) in the " + std::to_string(samples.size()) +
                " usable views: the camera offset and the yaw axis need at least " +
                std::to_string(options.min_distinct_yaws) + " distinct yaws spanning " +
                fixed(options.min_yaw_span / kDeg, 0) + " deg");
}

/* The robot poses in the first view's vision frame and the yaw readings into pb; the largest
   distance between two robot positions into out.baseline. */
void setRobotPoses(const std::vector<MotionSample> &samples, RigProblem &pb, RigCalibration &out)
{
  const Eigen::Isometry3d wMv0 = isoWMV(samples.front());
  for (const auto &s : samples) {
    pb.v0Mv.push_back(wMv0.inverse() * isoWMV(s));
    pb.readings.push_back(s.yaw);
  }
  const std::size_t n = samples.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      out.baseline = std::max(out.baseline, (pb.v0Mv[i].translation() - pb.v0Mv[j].translation()).norm());
}

/* The views sharing the first view's robot pose (the static group of the closed-form start). */
std::vector<std::size_t> staticGroup(const RigProblem &pb)
{
  std::vector<std::size_t> group;
  for (std::size_t i = 0; i < pb.v0Mv.size(); ++i) {
    const Eigen::Isometry3d &M = pb.v0Mv[i];
    if (M.translation().norm() < 1e-6 && (M.linear() - Eigen::Matrix3d::Identity()).norm() < 1e-9)
      group.push_back(i);
  }
  return group;
}

/* The camera offset's x and z from the static group's own board poses (y kept at pb.t0y): the
   camera centre C_i = O + bRc_i t0 in the board frame, so (bRc_i - bRc_lo) t0 = C_i - C_lo.
   False when the least-squares solution is not finite. */
bool offsetFromGroup(const RigProblem &pb, const std::vector<Eigen::Isometry3d> &cMb0,
                     const std::vector<std::size_t> &group, std::size_t lo, Eigen::Vector3d &t0)
{
  Eigen::MatrixXd A(3 * (group.size() - 1), 2);
  Eigen::VectorXd b(3 * (group.size() - 1));
  Eigen::Index row = 0;
  const Eigen::Isometry3d bMc_ref = cMb0[lo].inverse();
  for (std::size_t i : group) {
    if (i == lo)
      continue;
    const Eigen::Isometry3d bMc = cMb0[i].inverse();
    const Eigen::Matrix3d D = bMc.linear() - bMc_ref.linear();
    A.block(row, 0, 3, 1) = D.col(0);
    A.block(row, 1, 3, 1) = D.col(2);
    b.segment(row, 3) = bMc.translation() - bMc_ref.translation() - D.col(1) * pb.t0y;
    row += 3;
  }
  const Eigen::Vector2d xz = A.colPivHouseholderQr().solve(b);
  if (!xz.allFinite())
    return false;
  t0 = Eigen::Vector3d(xz.x(), pb.t0y, xz.y());
  return true;
}

/* The closed-form start of the offset and the axis from the static group, when its yaws span
   more than 2 degrees (t0 and axis untouched otherwise). */
void closedFormStart(const RigProblem &pb, const std::vector<Eigen::Isometry3d> &cMb0,
                     const RigCalibrationOptions &options, Eigen::Vector3d &t0, Eigen::Vector3d &axis)
{
  const std::vector<std::size_t> group = staticGroup(pb);
  if (group.size() < 2)
    return;
  std::size_t lo = group.front(), hi = group.front();
  for (std::size_t i : group) {
    if (pb.readings[i] < pb.readings[lo])
      lo = i;
    if (pb.readings[i] > pb.readings[hi])
      hi = i;
  }
  if (!(pb.readings[hi] - pb.readings[lo] > 2 * kDeg))
    return;
  if (!options.use_initial_offset)
    offsetFromGroup(pb, cMb0, group, lo, t0);
  if (options.estimate_axis) {
    // Relative rotation between the extreme yaws: about the axis (in the camera frame).
    const Eigen::Matrix3d Rrel = cMb0[hi].linear() * cMb0[lo].linear().transpose();
    const Eigen::AngleAxisd aa(Rrel);
    Eigen::Vector3d a = aa.axis();
    if (a.y() < 0)
      a = -a;
    if (a.y() > 0.5)
      axis = a;
  }
}

/* The starting parameters: the closed-form offset and axis (or the options' values), the yaw
   offset asked for, and the board placed by the first view's pose (square to the robot with
   options.board_square, its heading then absorbed by the yaw offset). */
Eigen::VectorXd initialParameters(const RigProblem &pb, const std::vector<Eigen::Isometry3d> &cMb0,
                                  const RigCalibrationOptions &options)
{
  Eigen::VectorXd p = Eigen::VectorXd::Zero(kParams);
  Eigen::Vector3d t0 = options.initial_offset;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  closedFormStart(pb, cMb0, options, t0, axis);
  axis /= axis.y();
  p[P_AX] = axis.x();
  p[P_AZ] = axis.z();
  p[P_TX] = t0.x();
  p[P_TZ] = t0.z();
  p[P_DELTA] = options.initial_yaw_offset;
  auto boardFromView = [&](const Eigen::VectorXd &q) {
    const Eigen::Vector3d t(q[P_TX], pb.t0y, q[P_TZ]);
    return pb.v0Mv[0] * vMc(axisOf(q), pb.readings[0] + q[P_DELTA], t) * cMb0[0];
  };
  setBoard(p, boardFromView(p));
  if (options.board_square) {
    p[P_DELTA] -= p[P_PSI];
    setBoard(p, boardFromView(p));
    p[P_PSI] = 0;
  }
  return p;
}

/* The parameters the fit moves: the axis when estimated, the offset's x and z, the yaw offset
   unless fixed, the board's heading unless square, and the board's other angles and position. */
std::vector<int> freeParameters(const RigCalibrationOptions &options, YawZeroSource yaw_zero)
{
  std::vector<int> free;
  if (options.estimate_axis) {
    free.push_back(P_AX);
    free.push_back(P_AZ);
  }
  free.push_back(P_TX);
  free.push_back(P_TZ);
  if (yaw_zero != YawZeroSource::Fixed)
    free.push_back(P_DELTA);
  if (!options.board_square)
    free.push_back(P_PSI);
  for (int k : {P_ALPHA, P_GAMMA, P_BX, P_BY, P_BZ})
    free.push_back(k);
  return free;
}

/* Levenberg–Marquardt on the free parameters from p (p, r and cost: the solution, its residuals
   and their squared norm); the number of iterations. */
int refineRig(const RigProblem &pb, const std::vector<int> &free, Eigen::VectorXd &p, Eigen::VectorXd &r, double &cost)
{
  const Eigen::Index nf = static_cast<Eigen::Index>(free.size());
  r = pb.residual(p);
  cost = r.squaredNorm();
  double lambda = 1e-3;
  int it = 0;
  for (; it < 200; ++it) {
    const Eigen::MatrixXd J = pb.jacobian(p, free);
    const Eigen::MatrixXd H = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    bool improved = false;
    double rel = 0;
    for (int tries = 0; tries < 20 && !improved; ++tries) {
      const Eigen::VectorXd dx = calibration_detail::dampedStep(H, g, lambda);
      Eigen::VectorXd q = p;
      for (Eigen::Index k = 0; k < nf; ++k)
        q[free[static_cast<std::size_t>(k)]] += dx[k];
      const Eigen::VectorXd rq = pb.residual(q);
      const double cq = rq.squaredNorm();
      if (std::isfinite(cq) && cq < cost) {
        rel = (cost - cq) / std::max(cost, 1e-300);
        p = q;
        r = rq;
        cost = cq;
        lambda = std::max(lambda / 10, 1e-12);
        improved = true;
        if (dx.norm() < 1e-12)
          rel = 0;
      } else {
        lambda *= 10;
      }
    }
    if (!improved || rel < 1e-14)
      break;
  }
  return it + 1;
}

/* The solution's estimates and their 1-sigma (sigma^2 (J^T J)^-1 on the free parameters) into out. */
void storeRigEstimates(const RigProblem &pb, const std::vector<int> &free, const Eigen::VectorXd &p, double cost,
                       const RigCalibrationOptions &options, RigCalibration &out)
{
  const Eigen::MatrixXd J = pb.jacobian(p, free);
  const double sigma2 = cost / static_cast<double>(pb.residuals - free.size());
  const Eigen::MatrixXd cov = sigma2 * (J.transpose() * J).inverse();
  auto sd = [&](int param) {
    for (std::size_t k = 0; k < free.size(); ++k)
      if (free[k] == param)
        return std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k))));
    return 0.0;
  };
  out.camera_offset = Eigen::Vector3d(p[P_TX], pb.t0y, p[P_TZ]);
  out.camera_offset_sigma = Eigen::Vector3d(sd(P_TX), 0.0, sd(P_TZ));
  out.yaw_offset = p[P_DELTA];
  out.yaw_offset_sigma = sd(P_DELTA);
  out.yaw_axis = axisOf(p);
  if (options.estimate_axis) {
    // a(p, q) = (p, 1, q) / |.|: propagate the 2x2 covariance of (p, q).
    Eigen::Matrix<double, 3, 2> Ja;
    for (int c = 0; c < 2; ++c) {
      Eigen::VectorXd pp = p, pm = p;
      const int idx = c == 0 ? P_AX : P_AZ;
      pp[idx] += 1e-7;
      pm[idx] -= 1e-7;
      Ja.col(c) = (axisOf(pp) - axisOf(pm)) / 2e-7;
    }
    const Eigen::Matrix2d C = cov.topLeftCorner(2, 2);
    const Eigen::Matrix3d Ca = Ja * C * Ja.transpose();
    out.yaw_axis_sigma = Ca.diagonal().cwiseMax(0.0).cwiseSqrt();
  }
  out.v0Mb = pb.board(p);
}

/* A failed fit is an error, not a rig file: its RMS, offset or offset's uncertainty says so. */
void checkRigFit(const RigCalibration &out, const RigCalibrationOptions &options)
{
  auto mm = [](double v) { return std::to_string(static_cast<long long>(std::llround(1000 * v))) + " mm"; };
  if (!(out.rms_px <= options.max_rms_px))
    throw Error("calibrate-rig: the fit failed: reprojection RMS " + std::to_string(out.rms_px) + " px (at most " +
                std::to_string(options.max_rms_px) +
                " px); check the yaw readings (sign, radians, order against the images) and the camera file");
  if (!out.camera_offset.allFinite() || !(out.camera_offset.norm() <= options.max_offset))
    throw Error("calibrate-rig: the fit failed: a camera offset of " + mm(out.camera_offset.norm()) +
                " from the yaw axis (at most " + mm(options.max_offset) + "); check --initial-offset and the yaw readings");
  if (!(out.camera_offset_sigma.maxCoeff() <= options.max_offset_sigma))
    throw Error("calibrate-rig: the offset is not determined: 1-sigma " + mm(out.camera_offset_sigma.maxCoeff()) +
                " (at most " + mm(options.max_offset_sigma) + "); take images over a wider span of yaws");
}

/* The board's scale as the robot's translation sees it: the fit again from the solution p with the
   board's scale free, its 1-sigma from the covariance (the result keeps the size given). A static
   robot cannot tell it: the camera offset and the board's distance grow with the board together. */
BoardScaleCheck rigBoardScale(const RigProblem &pb, std::vector<int> free, Eigen::VectorXd p, const BoardLayout &board,
                              const RigCalibrationOptions &options)
{
  free.push_back(P_SCALE);
  Eigen::VectorXd r;
  double cost = 0;
  refineRig(pb, free, p, r, cost);
  const Eigen::MatrixXd J = pb.jacobian(p, free);
  const double sigma2 = cost / static_cast<double>(pb.residuals - free.size());
  const Eigen::MatrixXd cov = sigma2 * (J.transpose() * J).inverse();
  const double sigma = std::sqrt(std::max(0.0, cov(cov.rows() - 1, cov.cols() - 1)));
  if (!std::isfinite(sigma) || !std::isfinite(p[P_SCALE]))
    return BoardScaleCheck();
  return checkBoardScale(1.0 + p[P_SCALE], sigma, board, options.board_scale);
}

} // namespace

RigCalibration calibrateRig(const CameraModel &camera, const BoardLayout &board, const std::vector<RigView> &views,
                            const RigCalibrationOptions &options)
{
  options.board_scale.validate();
  RigProblem pb;
  pb.camera = &camera;
  std::vector<Eigen::Isometry3d> cMb0; // per view, from its own pose estimate
  std::vector<MotionSample> samples;
  collectRigViews(camera, board, views, options.min_points_per_view, pb, cMb0, samples);
  const std::size_t n = samples.size();
  if (n < 3)
    throw Error("too few views: the board was usable in " + std::to_string(n) +
                " image(s); at least 3 at different yaw readings are needed");

  RigCalibration out;
  out.views = static_cast<int>(n);
  out.points = static_cast<int>(pb.residuals / 2);
  checkYawReadings(samples, options, out);
  setRobotPoses(samples, pb, out);
  const bool motion = out.baseline >= options.min_baseline;

  pb.t0y = options.initial_offset.y();
  Eigen::VectorXd p = initialParameters(pb, cMb0, options);
  out.yaw_zero = options.board_square ? YawZeroSource::BoardSquare
                                      : (motion ? YawZeroSource::RobotMotion : YawZeroSource::Fixed);
  const std::vector<int> free = freeParameters(options, out.yaw_zero);
  if (pb.residuals <= free.size())
    throw Error("too few points for the rig calibration");

  Eigen::VectorXd r;
  double cost = 0;
  out.iterations = refineRig(pb, free, p, r, cost);
  if (!std::isfinite(cost))
    throw Error("rig calibration failed: no finite solution");

  const std::size_t pairs = pb.residuals / 2; // residuals come in (u, v) pairs: one per feature
  out.rms_px = std::sqrt(cost / static_cast<double>(pairs));
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0;
    for (std::size_t j = 0; j < pb.points[i].size(); ++j, k += 2)
      s += r[static_cast<Eigen::Index>(k)] * r[static_cast<Eigen::Index>(k)] +
           r[static_cast<Eigen::Index>(k + 1)] * r[static_cast<Eigen::Index>(k + 1)];
    out.view_rms_px.push_back(std::sqrt(s / static_cast<double>(pb.points[i].size())));
  }
  storeRigEstimates(pb, free, p, cost, options, out);
  checkRigFit(out, options);
  if (options.check_board_scale && motion)
    out.board_scale = rigBoardScale(pb, free, p, board, options);
  return out;
}

std::string rigCalibrationYaml(const RigCalibration &rig)
{
  auto vec = [](const Eigen::Vector3d &v) { return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]"; };
  std::ostringstream s;
  s << "# yawdepth calibrate-rig: " << rig.views << " views, " << rig.points << " points, yaw readings spanning "
    << fixed(rig.yaw_span / kDeg, 1) << " deg, reprojection RMS " << fixed(rig.rms_px, 3) << " px\n";
  s << "# camera_offset: optical centre in the vision frame at yaw 0 (m); its component along the\n"
       "# yaw axis is not observable and was kept at its initial value (sigma 0)\n";
  s << "camera_offset: " << vec(rig.camera_offset) << "\n";
  s << "# true yaw = reading + yaw_offset (rad)";
  if (rig.yaw_zero == YawZeroSource::Fixed)
    s << "; not estimated (static robot, board not declared square): kept at its initial value";
  else if (rig.yaw_zero == YawZeroSource::RobotMotion)
    s << "; from the robot's translation";
  else
    s << "; from the board standing square to the robot";
  s << "\n";
  s << "yaw_offset: " << num(rig.yaw_offset) << "\n";
  s << "# yaw axis in the vision frame (unit)\n";
  s << "yaw_axis: " << vec(rig.yaw_axis) << "\n";
  s << "# 1-sigma uncertainties (0: fixed)\n";
  s << "camera_offset_sigma: " << vec(rig.camera_offset_sigma) << "\n";
  s << "yaw_offset_sigma: " << num(rig.yaw_offset_sigma) << "\n";
  s << "yaw_offset_estimated: " << (rig.yaw_zero == YawZeroSource::Fixed ? "false" : "true") << "\n";
  s << "yaw_axis_sigma: " << vec(rig.yaw_axis_sigma) << "\n";
  s << "reprojection_rms_px: " << num(rig.rms_px) << "\n";
  if (rig.board_scale.status != BoardScaleStatus::NotEstimated)
    s << "# the board's size as the robot's translation sees it: " << fixed(rig.board_scale.scale, 4) << " +- "
      << fixed(rig.board_scale.sigma, 4) << " times the size given (" << toString(rig.board_scale.status) << ")\n";
  return s.str();
}

} // namespace yawdepth
