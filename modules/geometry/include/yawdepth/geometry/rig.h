#pragma once
/*!
  \file rig.h
  \brief The yawing-camera rig: vision frame, camera frame, world poses and relative motion.

  Frames (ViSP's camera convention throughout: X right, Y down, Z forward):
  - `c`  camera frame: origin at the optical centre, Z along the optical axis.
  - `v`  vision frame: fixed on the robot body at the yaw axis; coincides in orientation with `c`
         at yaw 0. The yaw turns the camera about +Y (down), so positive yaw turns the optical axis
         toward +X.
  - `w`  world frame: fixed, camera convention, the robot's start (the motion log's frame).

  Names carry frames: `aMb` is the pose of frame b in frame a (so a point maps as
  `a_P = aMb * b_P`); `a_t_b` is the origin of b expressed in a. `cur`/`prev` name the camera
  frames of two images, e.g. `curMprev` maps a point from the earlier camera frame to the later one.
  All lengths are metres, all angles radians.
*/
#include <Eigen/Core>
#include <Eigen/Geometry>
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
  \brief One row of a motion log: the pose of the vision frame in the world and the camera yaw.

  `heading` is the robot's rotation about the world's +Y axis, `yaw` the camera's yaw relative
  to the vision frame; both right-handed about +Y (down), positive turns toward +X.
*/
struct MotionSample {
  long frame = 0;       //!< Frame number, as in the motion log.
  double x = 0;         //!< Position of the vision-frame origin in the world: X (m).
  double y = 0;         //!< Position of the vision-frame origin in the world: Y (m).
  double z = 0;         //!< Position of the vision-frame origin in the world: Z (m).
  double heading = 0;   //!< Robot heading about +Y (rad).
  double yaw = 0;       //!< Camera yaw relative to the vision frame (rad).
};

/*!
  \brief Geometry of the yaw mechanism: the optical centre's offset from the yaw axis.

  The paper puts the vision-frame origin on the camera X axis at distance Lb from the optical
  centre, i.e. `v_t0 = (-Lb, 0, 0)`; any offset vector is accepted here.
*/
class YawRig {
public:
  /*! \param v_t0 Position of the optical centre in the vision frame at yaw 0 (m). */
  explicit YawRig(const Eigen::Vector3d &v_t0 = Eigen::Vector3d::Zero()) : v_t0_(v_t0) {}
  /*! \brief Convenience constructor from a ViSP translation vector. */
  explicit YawRig(const vpTranslationVector &v_t0) : v_t0_(v_t0[0], v_t0[1], v_t0[2]) {}

  /*! \brief Position of the optical centre in the vision frame at yaw 0 (m). */
  const Eigen::Vector3d &cameraOffset() const { return v_t0_; }

  /*!
    \brief Pose of the camera in the vision frame, eq. (1):
    \f[ {}^v T_c(\theta) = \begin{bmatrix} R_y(\theta) & R_y(\theta)\, t_0 \\ 0 & 1 \end{bmatrix} \f]
    \param yaw Camera yaw \f$\theta\f$ (rad).
  */
  vpHomogeneousMatrix vMc(double yaw) const;
  /*! \brief Inverse of vMc(): \f$ {}^c T_v = [R_y(\theta)^T \;|\; -t_0] \f$. */
  vpHomogeneousMatrix cMv(double yaw) const;

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
};

/*! \brief Pose of the vision frame in the world: \f$ {}^wT_v = [R_y(h) \;|\; (x, y, z)] \f$. */
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
  pose of the later vision frame in the earlier one, \f$ {}^{v,prev}T_{v,cur} = [R_y(\Delta h) | d] \f$
  with `d` expressed in the earlier vision frame.
*/
template <typename T> struct IncrementPerturbation {
  Eigen::Matrix<T, 3, 1> d_translation = Eigen::Matrix<T, 3, 1>::Zero(); //!< added to d (m)
  T d_heading = T(0);  //!< added to the heading change \f$\Delta h\f$ (rad)
  T d_yaw_prev = T(0); //!< added to the earlier yaw reading (rad)
  T d_yaw_cur = T(0);  //!< added to the later yaw reading (rad)
};

/*!
  \brief Relative camera motion \f$ P_{cur} = R P_{prev} + t \f$ from two motion-log rows, with
  optional perturbations; templated so that estimators can differentiate through it.

  \f[ R = R_y(\theta_p - \Delta h - \theta_c),\quad
      t = R_y(\theta_c)^T R_y(\Delta h)^T (R_y(\theta_p) t_0 - d) - t_0 \f]
*/
template <typename T>
void relativeMotion(const Eigen::Vector3d &v_t0, const MotionSample &prev, const MotionSample &cur,
                    const IncrementPerturbation<T> &p, Eigen::Matrix<T, 3, 3> &R, Eigen::Matrix<T, 3, 1> &t)
{
  const Eigen::Matrix3d Rhp = rotY(prev.heading);
  const Eigen::Vector3d d0 = Rhp.transpose() * Eigen::Vector3d(cur.x - prev.x, cur.y - prev.y, cur.z - prev.z);
  const Eigen::Matrix<T, 3, 1> d = d0.cast<T>() + p.d_translation;
  const T dh = T(cur.heading - prev.heading) + p.d_heading;
  const T yp = T(prev.yaw) + p.d_yaw_prev;
  const T yc = T(cur.yaw) + p.d_yaw_cur;
  const Eigen::Matrix<T, 3, 1> t0(T(v_t0.x()), T(v_t0.y()), T(v_t0.z()));
  R = rotY<T>(yp - dh - yc);
  t = rotY<T>(yc).transpose() * (rotY<T>(dh).transpose() * (rotY<T>(yp) * t0 - d)) - t0;
}

/*! \brief A ViSP homogeneous matrix as an Eigen isometry. */
Eigen::Isometry3d toIsometry(const vpHomogeneousMatrix &M);

/*! \brief The ViSP homogeneous matrix `[R | t]`. */
vpHomogeneousMatrix toVisp(const Eigen::Matrix3d &R, const Eigen::Vector3d &t);
/*! \brief The rotation `R` and translation `t` of a ViSP homogeneous matrix `M = [R | t]`. */
void fromVisp(const vpHomogeneousMatrix &M, Eigen::Matrix3d &R, Eigen::Vector3d &t);

} // namespace yawdepth
