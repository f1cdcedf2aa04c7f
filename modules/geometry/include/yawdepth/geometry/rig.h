#pragma once
/*!
  \file rig.h
  \brief The yawing-camera rig: vision frame, camera frame, world poses and relative motion.

  Frames (ViSP's camera convention throughout: X right, Y down, Z forward):
  - `c`  camera frame: origin at the optical centre, Z along the optical axis.
  - `v`  vision frame: fixed on the robot body at the yaw axis (an arm's end-effector, or any body
         whose pose the motion log gives). The yaw turns the camera about the vision frame's +Y
         axis (down), so positive yaw turns the optical axis toward +X. With `camera_offset` the
         vision frame coincides in orientation with `c` at yaw 0; with `camera_pose` the camera's
         pose in it at yaw 0 is any fixed pose (an arm's hand-eye eMc).
  - `w`  world frame: fixed, the motion log's frame (a mobile robot's start, an arm's base).

  The motion is a kinematic chain: world -> vision frame (planar odometry `x, y, z, heading`, or a
  full 6-DoF pose) -> yaw joint -> camera. The estimators only see relative camera motion and its
  noise; this header and the file readers are the only places that know which form a log had.

  Names carry frames: `aMb` is the pose of frame b in frame a (so a point maps as
  `a_P = aMb * b_P`); `a_t_b` is the origin of b expressed in a. `cur`/`prev` name the camera
  frames of two images, e.g. `curMprev` maps a point from the earlier camera frame to the later one.
  All lengths are metres, all angles radians.
*/
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpRotationMatrix.h>
#include <visp3/core/vpTranslationVector.h>

namespace yawdepth {

/*!
  \brief Rotation by `angle` about +Y: \f[ R_y(a) = \begin{bmatrix} \cos a & 0 & \sin a\\ 0&1&0\\ -\sin a&0&\cos a\end{bmatrix} \f]
*/
template <typename T> Eigen::Matrix<T, 3, 3> rotY(const T &angle)
{
  using std::cos;
  using std::sin;
  const T c = cos(angle), s = sin(angle);
  Eigen::Matrix<T, 3, 3> R;
  R << c, T(0), s, T(0), T(1), T(0), -s, T(0), c;
  return R;
}

/*!
  \brief Rotation of a rotation vector (theta-u, as ViSP's vpThetaUVector), templated so that
  estimators can differentiate through it: \f[ \exp([\omega]_\times) = I + \frac{\sin\theta}{\theta}
  [\omega]_\times + \frac{1-\cos\theta}{\theta^2} [\omega]_\times^2,\quad \theta = \|\omega\| \f]
  (a Taylor expansion, exact in value and first derivative, below 1e-8 rad).
*/
template <typename T> Eigen::Matrix<T, 3, 3> expSO3(const Eigen::Matrix<T, 3, 1> &w)
{
  using std::cos;
  using std::sin;
  using std::sqrt;
  Eigen::Matrix<T, 3, 3> K;
  K << T(0), -w(2), w(1), w(2), T(0), -w(0), -w(1), w(0), T(0);
  const T theta2 = w.squaredNorm();
  Eigen::Matrix<T, 3, 3> R = Eigen::Matrix<T, 3, 3>::Identity();
  if (theta2 < T(1e-16)) {
    R += K + T(0.5) * K * K;
    return R;
  }
  const T theta = sqrt(theta2);
  R += (sin(theta) / theta) * K + ((T(1) - cos(theta)) / theta2) * (K * K);
  return R;
}

/*! \brief The cross-product matrix: \f$ [v]_\times w = v \times w \f$. */
inline Eigen::Matrix3d skew(const Eigen::Vector3d &v)
{
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

/*! \brief The rotation vector (theta-u) of a rotation matrix, the inverse of expSO3() for angles below pi. */
Eigen::Vector3d logSO3(const Eigen::Matrix3d &R);

/*!
  \brief One row of a motion log: the pose of the vision frame in the world and the camera yaw.

  Two forms. Planar (a mobile robot's odometry): the position (x, y, z) and `heading`, the robot's
  rotation about the world's +Y axis. 6-DoF (`six_dof`, an arm's forward kinematics, mocap, VIO):
  the position (x, y, z) and the orientation `theta_u`, i.e. wMv as a ViSP vpPoseVector
  (tx, ty, tz, tux, tuy, tuz); `heading` is then not used. `yaw` is the camera's yaw relative to the
  vision frame in both; angles are right-handed about +Y (down), positive turns toward +X.
*/
struct MotionSample {
  long frame = 0;       //!< Frame number, as in the motion log.
  double x = 0;         //!< Position of the vision-frame origin in the world: X (m).
  double y = 0;         //!< Position of the vision-frame origin in the world: Y (m).
  double z = 0;         //!< Position of the vision-frame origin in the world: Z (m).
  double heading = 0;   //!< Robot heading about +Y (rad); planar form only.
  double yaw = 0;       //!< Camera yaw relative to the vision frame (rad).
  bool six_dof = false; //!< The 6-DoF form: the orientation is `theta_u`, not `heading`.
  Eigen::Vector3d theta_u = Eigen::Vector3d::Zero(); //!< Orientation of the vision frame in the world, theta-u (rad); 6-DoF form only.

  /*! \brief A 6-DoF sample from the vision frame's pose in the world (wMv) and the yaw reading. */
  static MotionSample fromPose(long frame, const vpHomogeneousMatrix &wMv, double yaw = 0);
  /*! \brief Orientation of the vision frame in the world: \f$ R_y(h) \f$ (planar) or \f$ \exp(\theta u) \f$. */
  Eigen::Matrix3d rotation() const { return six_dof ? expSO3<double>(theta_u) : rotY(heading); }
  /*! \brief Position of the vision frame's origin in the world (m). */
  Eigen::Vector3d position() const { return Eigen::Vector3d(x, y, z); }
};

/*! \brief `angle` wrapped to (-pi, pi] (rad). */
double wrapAngle(double angle);

/*!
  \brief The motion a fraction `s` of the way from sample `a` to sample `b` (s in [0, 1]): the
  position linear; the orientation by slerp on SO(3), \f$ R_a \exp(s \log(R_a^T R_b)) \f$ (6-DoF)
  or the heading linear along the shorter way round (planar); the yaw linear along the shorter way
  round. Both samples must have the same form (throws yawdepth::Error otherwise). The result has
  a's frame number. Time alignment (yawdepth/io/recording.h) interpolates a pose log at each image
  time with it.
*/
MotionSample interpolateMotion(const MotionSample &a, const MotionSample &b, double s);

/*!
  \brief The row of a motion log (sorted by strictly increasing frame) that holds `frame`, or -1.
  Binary search: every estimator, the refiner and the report find a frame's pose with it.
*/
long rowOfFrame(const std::vector<MotionSample> &motion, long frame);

/*!
  \brief Geometry of the camera mount: the yaw joint and the camera's fixed pose on it.

  The paper puts the vision-frame origin on the camera X axis at distance Lb from the optical
  centre, i.e. `v_t0 = (-Lb, 0, 0)`, with the camera's axes parallel to the vision frame's at yaw 0
  (a rig file's `camera_offset`); any offset vector is accepted here. A camera mounted at any fixed
  orientation (a rig file's `camera_pose`, an arm's hand-eye eMc) has the pose
  \f$ {}^vT_{c}(0) = [R_0 \,|\, t_0] \f$ at yaw 0; the yaw joint turns it about the vision frame's +Y.
*/
class YawRig {
public:
  /*! \param v_t0 Position of the optical centre in the vision frame at yaw 0 (m). */
  explicit YawRig(const Eigen::Vector3d &v_t0 = Eigen::Vector3d::Zero()) : v_t0_(v_t0) {}
  /*! \brief Convenience constructor from a ViSP translation vector. */
  explicit YawRig(const vpTranslationVector &v_t0) : v_t0_(v_t0[0], v_t0[1], v_t0[2]) {}
  /*! \brief A camera at any fixed pose: \param vMc0 the camera's pose in the vision frame at yaw 0
      (for an arm without a pan joint, the hand-eye eMc). */
  explicit YawRig(const vpHomogeneousMatrix &vMc0);

  /*! \brief Position of the optical centre in the vision frame at yaw 0 (m). */
  const Eigen::Vector3d &cameraOffset() const { return v_t0_; }
  /*! \brief Orientation \f$ R_0 \f$ of the camera in the vision frame at yaw 0 (identity for `camera_offset`). */
  const Eigen::Matrix3d &cameraRotation() const { return v_R0_; }
  /*! \brief Whether the camera's axes are those of the vision frame at yaw 0 (\f$ R_0 = I \f$, the paper's rig). */
  bool axisAligned() const { return axis_aligned_; }

  /*!
    \brief Pose of the camera in the vision frame, eq. (1) (with \f$ R_0 = I \f$ in the paper):
    \f[ {}^v T_c(\theta) = \begin{bmatrix} R_y(\theta) R_0 & R_y(\theta)\, t_0 \\ 0 & 1 \end{bmatrix} \f]
    \param yaw Camera yaw \f$\theta\f$ (rad).
  */
  vpHomogeneousMatrix vMc(double yaw) const;
  /*! \brief Inverse of vMc(): \f$ {}^c T_v = [R_0^T R_y(\theta)^T \;|\; -R_0^T t_0] \f$. */
  vpHomogeneousMatrix cMv(double yaw) const;

  /*!
    \brief A camera-frame point in the vision frame, eq. (7), as Eigen vectors:
    \f$ {}^vP = R_y(\theta) (R_0\, {}^cP + t_0) \f$.
  */
  Eigen::Vector3d visionPoint(double yaw, const Eigen::Vector3d &c_P) const
  {
    return rotY(yaw) * (v_R0_ * c_P + v_t0_);
  }
  /*! \brief The inverse of visionPoint(): \f$ {}^cP = R_0^T (R_y(\theta)^T\, {}^vP - t_0) \f$. */
  Eigen::Vector3d cameraPoint(double yaw, const Eigen::Vector3d &v_P) const
  {
    return v_R0_.transpose() * (rotY(yaw).transpose() * v_P - v_t0_);
  }
  /*! \brief Orientation of the camera in the vision frame, \f$ {}^vR_c(\theta) = R_y(\theta) R_0 \f$. */
  Eigen::Matrix3d vRc(double yaw) const { return rotY(yaw) * v_R0_; }

  /*!
    \brief Camera translation increment in the camera frame, eq. (4):
    \f[ (dX_c, dY_c, dZ_c)^T = {}^c R_v(\theta)\,(dx, dy, dz)^T \f]
    \param yaw Camera yaw \f$\theta\f$ (rad).
    \param v_d Translation increment of the camera expressed in the vision frame (m).
  */
  vpColVector cameraIncrement(double yaw, const vpColVector &v_d) const;

  /*!
    \brief A camera-frame point in the vision frame, eq. (7): \f$ [X\,Y\,Z\,1]^T = {}^vT_c [X_c\,Y_c\,Z_c\,1]^T \f$.
  */
  vpColVector toVision(double yaw, const vpColVector &c_P) const;
  /*! \brief Inverse of toVision(). */
  vpColVector toCamera(double yaw, const vpColVector &v_P) const;

private:
  Eigen::Vector3d v_t0_;
  Eigen::Matrix3d v_R0_ = Eigen::Matrix3d::Identity();
  bool axis_aligned_ = true;
};

/*!
  \brief The vision frame of a pan joint on a robot's body: \f$ {}^bT_v \f$, whose +Y is the joint's
  axis and whose origin is a point on it, both in the body frame b (e.g. REP 103's z-up base_link
  with axis (0, 0, 1) and the joint's position from the URDF). The rotation is the smallest one
  taking +Y to the axis. A positive joint position turns the camera right-handedly about the axis,
  which is yawdepth's positive yaw about the vision frame's +Y. With it, a body pose wMb gives the
  motion row's \f$ {}^wT_v = {}^wT_b\, {}^bT_v \f$ and a mount bMc at yaw 0 gives the rig's
  \f$ {}^vT_c(0) = ({}^bT_v)^{-1}\, {}^bT_c \f$. Throws yawdepth::Error for a zero or non-finite axis
  or a non-finite origin.
*/
vpHomogeneousMatrix panJointFrame(const Eigen::Vector3d &axis, const Eigen::Vector3d &origin);

/*!
  \brief The axis a moving frame turns about, accumulated over its orientations in order: a step is
  taken each time the frame has turned more than kKeyStep (0.01 rad) since the last step's
  orientation (so that jitter of a frame at rest adds nothing), its rotation vector
  \f$ \log(R_{key}^T R) \f$ (in the frame before the step), its sign aligned with the running sum,
  summed; and the total angle of the steps. A pan rig's vision frame on a robot driving on a floor
  turns about its own +Y (the pan axis is vertical); offPanAxis() says when it clearly does not, the
  sign of a wrong pan axis (import-bag's and the online measurer's warning).
*/
class TurnAxis {
public:
  static constexpr double kKeyStep = 0.01; //!< rad: the least turn of a step.
  /*! \brief The next orientation of the frame (in the world). */
  void add(const Eigen::Matrix3d &R);
  /*! \brief The summed rotation vector (rad; its direction the axis, in the moving frame). */
  const Eigen::Vector3d &sum() const { return sum_; }
  /*! \brief The total angle turned (rad). */
  double turned() const { return turned_; }
  /*!
    \brief Whether the frame turned more than 0.1 rad, mostly about one axis (the sum is over half the
    total), and that axis is more than 20 degrees from its +Y.
  */
  bool offPanAxis() const;

private:
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
  double turned_ = 0;
  bool have_key_ = false;
  Eigen::Matrix3d R_key_ = Eigen::Matrix3d::Identity();
};

/*! \brief Pose of the vision frame in the world: \f$ {}^wT_v = [R_y(h) \;|\; (x, y, z)] \f$, or the 6-DoF pose. */
vpHomogeneousMatrix wMv(const MotionSample &s);
/*! \brief Pose of the camera in the world: \f$ {}^wT_c = {}^wT_v\, {}^vT_c(\theta) \f$. */
vpHomogeneousMatrix wMc(const YawRig &rig, const MotionSample &s);
/*!
  \brief Relative camera motion between two motion-log rows, rotation included:
  \f$ {}^{cur}T_{prev} = ({}^wT_{c,cur})^{-1}\, {}^wT_{c,prev} \f$, so \f$ P_{cur} = R P_{prev} + t \f$.
*/
vpHomogeneousMatrix curMprev(const YawRig &rig, const MotionSample &prev, const MotionSample &cur);

/*!
  \brief Noisy quantities of one motion increment, as perturbations of a motion-log pair.

  The estimators' uncertainty is first-order in these perturbations. The odometry increment is the
  pose of the later vision frame in the earlier one, \f$ {}^{v,prev}T_{v,cur} = [\Delta R | d] \f$
  with `d` expressed in the earlier vision frame; the rotation perturbation acts on the right,
  \f$ \Delta R \exp(\delta) \f$ (in the later vision frame). For a planar log,
  \f$ \Delta R = R_y(\Delta h) \f$ and only \f$ \delta_y \f$ (the heading) is noisy.
*/
template <typename T> struct IncrementPerturbation {
  Eigen::Matrix<T, 3, 1> d_translation = Eigen::Matrix<T, 3, 1>::Zero(); //!< added to d (m)
  Eigen::Matrix<T, 3, 1> d_rotation = Eigen::Matrix<T, 3, 1>::Zero();    //!< rotation vector on \f$\Delta R\f$ (rad); y is the heading
  T d_yaw_prev = T(0); //!< added to the earlier yaw reading (rad)
  T d_yaw_cur = T(0);  //!< added to the later yaw reading (rad)
};

/*!
  \brief Relative camera motion \f$ P_{cur} = R P_{prev} + t \f$ from two motion-log rows, with
  optional perturbations; templated so that estimators can differentiate through it.

  \f[ R = R_0^T R_y(\theta_c)^T \Delta R^T R_y(\theta_p) R_0,\quad
      t = R_0^T \left(R_y(\theta_c)^T \Delta R^T (R_y(\theta_p) t_0 - d) - t_0\right) \f]
  which for a planar log and \f$ R_0 = I \f$ is \f$ R = R_y(\theta_p - \Delta h - \theta_c) \f$,
  \f$ t = R_y(\theta_c)^T R_y(\Delta h)^T (R_y(\theta_p) t_0 - d) - t_0 \f$, computed so (every
  rotation about +Y) when both rows are planar and the rig is axis-aligned: a planar log's rotation
  noise is its heading, `p.d_rotation.y()`; the other two components are not part of its model and
  are ignored there.
*/
template <typename T>
void relativeMotion(const YawRig &rig, const MotionSample &prev, const MotionSample &cur,
                    const IncrementPerturbation<T> &p, Eigen::Matrix<T, 3, 3> &R, Eigen::Matrix<T, 3, 1> &t)
{
  const Eigen::Matrix3d Rp = prev.rotation();
  const Eigen::Vector3d d0 = Rp.transpose() * (cur.position() - prev.position());
  const Eigen::Matrix<T, 3, 1> d = d0.cast<T>() + p.d_translation;
  const T yp = T(prev.yaw) + p.d_yaw_prev;
  const T yc = T(cur.yaw) + p.d_yaw_cur;
  const Eigen::Vector3d &v_t0 = rig.cameraOffset();
  const Eigen::Matrix<T, 3, 1> t0(T(v_t0.x()), T(v_t0.y()), T(v_t0.z()));
  if (!prev.six_dof && !cur.six_dof && rig.axisAligned()) { // the paper's planar chain, cheaper
    const T dh = T(cur.heading - prev.heading) + p.d_rotation(1);
    R = rotY<T>(yp - dh - yc);
    t = rotY<T>(yc).transpose() * (rotY<T>(dh).transpose() * (rotY<T>(yp) * t0 - d)) - t0;
    return;
  }
  const Eigen::Matrix3d dR0 = Rp.transpose() * cur.rotation();
  const Eigen::Matrix<T, 3, 3> dR = dR0.cast<T>() * expSO3<T>(p.d_rotation);
  const Eigen::Matrix<T, 3, 3> R0 = rig.cameraRotation().cast<T>();
  R = R0.transpose() * rotY<T>(yc).transpose() * dR.transpose() * rotY<T>(yp) * R0;
  t = R0.transpose() * (rotY<T>(yc).transpose() * (dR.transpose() * (rotY<T>(yp) * t0 - d)) - t0);
}

/*! \brief A ViSP homogeneous matrix as an Eigen isometry. */
Eigen::Isometry3d toIsometry(const vpHomogeneousMatrix &M);

/*! \brief The ViSP homogeneous matrix `[R | t]`. */
vpHomogeneousMatrix toVisp(const Eigen::Matrix3d &R, const Eigen::Vector3d &t);
/*! \brief The rotation `R` and translation `t` of a ViSP homogeneous matrix `M = [R | t]`. */
void fromVisp(const vpHomogeneousMatrix &M, Eigen::Matrix3d &R, Eigen::Vector3d &t);

} // namespace yawdepth
