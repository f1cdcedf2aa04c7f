#pragma once
/*!
  \file two_view.h
  \brief Depth of a feature from one motion increment between two frames: the paper's eq. (5)
  (`paper`) and the exact finite-increment form (`exact`), with gates and first-order uncertainty.

  Notation: `prev` and `cur` are the two frames (cur later); \f$ m = (x, y) \f$ are undistorted
  normalised coordinates; the relative camera motion is \f$ P_{cur} = R\,P_{prev} + t \f$ (see
  yawdepth/geometry/rig.h); \f$ r = R\,(x_{prev}, y_{prev}, 1)^T \f$ is the earlier bearing
  rotated into the current frame.

  Uncertainty: the inputs that carry noise are the four observed pixel coordinates
  (`NoiseModel::sigma_px` each), the odometry increment between the frames (translation
  `sigma_odom` per axis, and rotation: the heading `sigma_heading` for a planar log, `sigma_rot`
  per axis for a 6-DoF log; all scaled by sqrt(n) when the two frames are n motion-log rows apart) and the two yaw readings (`sigma_yaw` each). The covariance of
  (Xc, Yc, Zc) is their first-order propagation \f$ \Sigma_P = J \Sigma J^T \f$.
*/
#include <Eigen/Core>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief Options shared by the two-view estimators. */
struct TwoViewOptions {
  NoiseModel noise;                 //!< Input noise, for the covariance and the weighting.
  GateOptions gates;                //!< Degeneracy gates.
  bool compute_covariance = true;   //!< Set false to skip the covariance (faster; c_cov stays NaN).
  int increments = 1;               //!< Motion-log rows between the two frames (odometry noise scales with it).
};

/*!
  \brief The paper's eq. (5) for one point from the current normalised point, its pixel motion and
  the camera increment, built on ViSP's point interaction matrix (vpFeaturePoint::interaction()).

  With \f$ L \f$ the u-row of the interaction matrix at Z = 1, split into translation
  \f$ L_v \f$ and rotation \f$ L_\omega \f$ parts, eq. (2) gives
  \f[ Z_c = \frac{k_x\, L_v\, (dX_c, dY_c, dZ_c)^T}{du - k_x L_\omega \omega}
      \;\overset{\omega=0}{=}\; \frac{k_x (x\, dZ_c - dX_c)}{du} \quad (5) \f]
  \param x, y Current normalised point (the paper's \f$ x_i \f$).
  \param du Pixel motion \f$ u_i - u_{i-1} \f$ along the row (undistorted pixels).
  \param kx Focal length in pixels along u.
  \param c_d Camera translation increment in the current camera frame, eq. (4) (m).
  \param c_omega Camera rotation increment (rotation vector, current camera frame, rad); zero for
         the published translation-only form.
*/
double paperDepth(double x, double y, double du, double kx, const Eigen::Vector3d &c_d,
                  const Eigen::Vector3d &c_omega = Eigen::Vector3d::Zero());

/*!
  \brief `exact`: the finite-increment two-view estimate, rotation compensated, both image rows
  combined by generalised least squares.

  Each image row gives a linear equation in the current depth, \f$ a_u Z = b_u \f$ and
  \f$ a_v Z = b_v \f$ with \f$ a_u = x_{cur} r_3 - r_1,\ b_u = t_1 r_3 - t_3 r_1 \f$ (and the same
  with y and index 2). Both hold exactly for noise-free data whatever the increment, rotation and
  yaw, so the estimate is exact to round-off. With noise the two residuals \f$ e = aZ - b \f$ have
  a 2x2 covariance \f$ \Sigma_e \f$ (from pixels, odometry and yaw, with their correlation), and
  \f[ \hat Z = \frac{a^T \Sigma_e^{-1} b}{a^T \Sigma_e^{-1} a} \f]
  is the minimum-variance combination; \f$ \Sigma_e \f$ is re-evaluated at \f$ \hat Z \f$ twice.
  Then \f$ X_c = x_{cur} Z,\ Y_c = y_{cur} Z \f$ (6) and the vision-frame point by eq. (7).

  Gates, in order: camera translation below `min_baseline` gives `no_motion`; parallax below
  `min_parallax_px` gives `degenerate`; a non-positive depth at either frame gives `behind`;
  a pixel outside the distortion model gives `undistort_failed`.

  \param camera Camera model (observed pixels are undistorted with it).
  \param rig Yaw rig.
  \param prev, cur Motion-log rows of the two frames.
  \param uv_prev, uv_cur Observed (distorted) pixels.
  \param options Noise model and gates.
*/
PointEstimate estimateExact(const CameraModel &camera, const YawRig &rig, const MotionSample &prev,
                            const MotionSample &cur, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv_cur,
                            const TwoViewOptions &options = TwoViewOptions());

/*!
  \brief `paper`: eq. (5)-(7) on one increment, as published: the u-row only, the depth attributed
  to the current frame, the increment of eq. (4) taken from the relative motion (\f$ c_d = -t \f$),
  a known rotation removed to first order with the interaction matrix's rotational columns.

  Being first order, it is biased by about \f$ dZ_c/Z \f$ (docs/method.md): it returns, exactly, the
  depth of the *previous* frame for a pure translation. Kept for comparison with the paper.
  Gates as estimateExact(), with the parallax measured on the u-row only. The covariance is
  propagated by central finite differences of the same function.
*/
PointEstimate estimatePaper(const CameraModel &camera, const YawRig &rig, const MotionSample &prev,
                            const MotionSample &cur, const Eigen::Vector2d &uv_prev, const Eigen::Vector2d &uv_cur,
                            const TwoViewOptions &options = TwoViewOptions());

} // namespace yawdepth
