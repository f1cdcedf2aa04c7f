#include <yawdepth/error.h>
#include <yawdepth/geometry/rig.h>
#include <Eigen/Geometry>
#include <algorithm>

namespace yawdepth {

vpHomogeneousMatrix toVisp(const Eigen::Matrix3d &R, const Eigen::Vector3d &t)
{
  vpHomogeneousMatrix M;
  for (unsigned i = 0; i < 3; ++i) {
    for (unsigned j = 0; j < 3; ++j)
      M[i][j] = R(i, j);
    M[i][3] = t(i);
  }
  return M;
}

Eigen::Isometry3d toIsometry(const vpHomogeneousMatrix &M)
{
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(M, R, t);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

void fromVisp(const vpHomogeneousMatrix &M, Eigen::Matrix3d &R, Eigen::Vector3d &t)
{
  for (unsigned i = 0; i < 3; ++i) {
    for (unsigned j = 0; j < 3; ++j)
      R(i, j) = M[i][j];
    t(i) = M[i][3];
  }
}

YawRig::YawRig(const vpHomogeneousMatrix &vMc0)
{
  fromVisp(vMc0, v_R0_, v_t0_);
  if (!v_R0_.allFinite() || !v_t0_.allFinite())
    throw Error("camera pose: not a finite pose");
  if (!(((v_R0_.transpose() * v_R0_) - Eigen::Matrix3d::Identity()).norm() < 1e-6) || !(v_R0_.determinant() > 0))
    throw Error("camera pose: the rotation is not a rotation matrix");
  axis_aligned_ = v_R0_ == Eigen::Matrix3d::Identity();
}

vpHomogeneousMatrix YawRig::vMc(double yaw) const
{
  const Eigen::Matrix3d R = rotY(yaw);
  return toVisp(R * v_R0_, R * v_t0_);
}

vpHomogeneousMatrix YawRig::cMv(double yaw) const
{
  return toVisp(v_R0_.transpose() * rotY(yaw).transpose(), -(v_R0_.transpose() * v_t0_));
}

long rowOfFrame(const std::vector<MotionSample> &motion, long frame)
{
  const auto it = std::lower_bound(motion.begin(), motion.end(), frame,
                                   [](const MotionSample &s, long f) { return s.frame < f; });
  if (it == motion.end() || it->frame != frame)
    return -1;
  return static_cast<long>(it - motion.begin());
}

Eigen::Vector3d logSO3(const Eigen::Matrix3d &R)
{
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

MotionSample MotionSample::fromPose(long frame, const vpHomogeneousMatrix &wMv, double yaw)
{
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  fromVisp(wMv, R, t);
  MotionSample s;
  s.frame = frame;
  s.x = t.x();
  s.y = t.y();
  s.z = t.z();
  s.yaw = yaw;
  s.six_dof = true;
  s.theta_u = logSO3(R);
  return s;
}

double wrapAngle(double angle)
{
  double a = std::remainder(angle, 2 * M_PI); // in [-pi, pi]
  if (a <= -M_PI)
    a += 2 * M_PI;
  return a;
}

MotionSample interpolateMotion(const MotionSample &a, const MotionSample &b, double s)
{
  if (a.six_dof != b.six_dof)
    throw Error("interpolateMotion: a planar and a 6-DoF sample");
  MotionSample r = a;
  r.x = a.x + s * (b.x - a.x);
  r.y = a.y + s * (b.y - a.y);
  r.z = a.z + s * (b.z - a.z);
  r.yaw = a.yaw + s * wrapAngle(b.yaw - a.yaw);
  if (a.six_dof) {
    const Eigen::Matrix3d Ra = a.rotation();
    r.theta_u = logSO3(Ra * expSO3<double>(Eigen::Vector3d(s * logSO3(Ra.transpose() * b.rotation()))));
  } else {
    r.heading = a.heading + s * wrapAngle(b.heading - a.heading);
  }
  return r;
}

static Eigen::Vector3d toEigen3(const vpColVector &v, const char *what)
{
  if (v.size() != 3)
    throw Error(std::string(what) + ": expected a 3-vector");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

static vpColVector toVisp3(const Eigen::Vector3d &e)
{
  vpColVector v(3);
  v[0] = e(0);
  v[1] = e(1);
  v[2] = e(2);
  return v;
}

vpColVector YawRig::cameraIncrement(double yaw, const vpColVector &v_d) const
{
  return toVisp3(v_R0_.transpose() * (rotY(yaw).transpose() * toEigen3(v_d, "cameraIncrement")));
}

vpColVector YawRig::toVision(double yaw, const vpColVector &c_P) const
{
  return toVisp3(visionPoint(yaw, toEigen3(c_P, "toVision")));
}

vpColVector YawRig::toCamera(double yaw, const vpColVector &v_P) const
{
  return toVisp3(v_R0_.transpose() * (rotY(yaw).transpose() * toEigen3(v_P, "toCamera") - v_t0_));
}

vpHomogeneousMatrix wMv(const MotionSample &s) { return toVisp(s.rotation(), s.position()); }

vpHomogeneousMatrix wMc(const YawRig &rig, const MotionSample &s) { return wMv(s) * rig.vMc(s.yaw); }

void TurnAxis::add(const Eigen::Matrix3d &R)
{
  if (!have_key_) {
    R_key_ = R;
    have_key_ = true;
    return;
  }
  const Eigen::Vector3d w = logSO3(R_key_.transpose() * R);
  if (w.norm() <= kKeyStep)
    return;
  turned_ += w.norm();
  sum_ += w.dot(sum_) < 0 ? Eigen::Vector3d(-w) : w;
  R_key_ = R;
}

bool TurnAxis::offPanAxis() const
{
  constexpr double kMinTurn = 0.1;           // rad: less says nothing
  constexpr double kMaxAxisAngle = M_PI / 9; // 20 degrees
  return turned_ > kMinTurn && sum_.norm() > 0.5 * turned_ && std::abs(sum_.y()) < std::cos(kMaxAxisAngle) * sum_.norm();
}

vpHomogeneousMatrix panJointFrame(const Eigen::Vector3d &axis, const Eigen::Vector3d &origin)
{
  if (!axis.allFinite() || !(axis.norm() > 1e-9))
    throw Error("the pan joint's axis must be finite and not zero");
  if (!origin.allFinite())
    throw Error("the pan joint's origin must be finite");
  return toVisp(Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitY(), axis).toRotationMatrix(), origin);
}

vpHomogeneousMatrix curMprev(const YawRig &rig, const MotionSample &prev, const MotionSample &cur)
{
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  relativeMotion<double>(rig, prev, cur, IncrementPerturbation<double>(), R, t);
  return toVisp(R, t);
}

} // namespace yawdepth
