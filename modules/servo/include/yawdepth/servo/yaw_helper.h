#pragma once
/*!
  \file yaw_helper.h
  \brief A yaw (pan) rate that makes depth better observed while keeping the features in view.

  Why: depth comes from the image motion that the camera's translation causes, the parallax. A
  feature at normalised (x, y) and depth Z moves, for a camera translating at T = (Tx, Ty, Tz)
  (camera frame), by the translational flow
  \f[ \dot{\mathbf m}_T = \tfrac{1}{Z}\,(x T_z - T_x,\; y T_z - T_y) \f]
  (the translation columns of ViSP's point interaction matrix). The camera's rotation adds a flow
  that does not depend on Z and says nothing about depth. At front view (optical axis along the
  motion) the parallax is x Tz / Z, small near the image centre; at side view it is -Tx / Z,
  large everywhere for the features beside the path that a side view sees: the paper's Section 4.

  A pure rotation does not change the angle between a feature's bearing and the camera's
  translation, so it does not change the feature's angular parallax: the yaw helps depth in two
  ways, both in this model. (1) The optical centre sits off the yaw axis (YawRig::cameraOffset(),
  the paper's Lb): panning at rate r translates the camera by r x (e_y x R_y(theta) t0), parallax
  even when the robot stands still, added to (or taken from) the robot's own translation.
  (2) The yaw decides which features stay in view and where they are in the image (a feature's
  flow in pixels grows toward the image border).

  The model: the features are taken as fixed points in the vision frame (their bearing and depth
  now); a candidate yaw \f$\theta\f$, reached at the rate
  \f$ r = \mathrm{clamp}(g\,(\theta - \theta_0), \pm\dot\theta_{\max}) \f$, is scored with
  the features reprojected in the camera at that yaw and the camera's translation (robot and pan
  offset) at that rate:
  \f[ J(\theta) = \frac{P(\theta)}{P_{\max}} - w_c\, c(\theta)^2,\qquad
      P(\theta) = \frac{1}{n}\sum_i w_i\, k \,\lVert \dot{\mathbf m}_{T,i}(\theta) \rVert \ \text{(px/s)} \f]
  where \f$P_{\max}\f$ is the largest P over the candidates, \f$c\f$ the features' centroid
  offset from the principal point relative to the half image (the visibility term), and a
  candidate is inadmissible when a feature leaves the image minus `margin_px` or gets behind the
  camera. The candidates are the yaws reachable within `horizon` seconds at up to `max_rate`
  (and within [min_yaw, max_yaw]); the best one is the target yaw and the recommended rate is
  \f$ \dot\theta = \mathrm{clamp}(g\,(\theta^* - \theta_0),\ \pm \dot\theta_{\max}) \f$. With
  no camera offset and no robot translation the rate only recentres the features. Feature
  weights \f$w_i\f$ (e.g. 0 for a converged feature, 1 otherwise) scale each feature's term. When
  every weight is 0 and `home_yaw` is set, the target is home_yaw (as far as the horizon reaches):
  the features are measured, the pan goes back to looking for new ones.

  Use it as a secondary task: the primary IBVS task usually uses every joint, so the classic
  projector I - W^+W is zero; ViSP's large projection operator (vpServo::secondaryTask(de2dt,
  true)) applies the yaw rate in the directions that keep the error norm decreasing as the
  primary task wants, while the error is large. Or command the pan with it directly when the pan
  is not part of the servo task.
*/
#include <cmath>
#include <limits>
#include <vector>
#include <Eigen/Core>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief One feature as the helper sees it: its undistorted normalised position, depth and weight. */
struct YawHelperFeature {
  /*! normalised (undistorted) image coordinate x in the current camera frame */
  double x = 0, y = 0; //!< normalised (undistorted) image coordinate y in the current camera frame
  double Z = 1;        //!< depth (m), > 0: the estimate, or the prior
  double weight = 1;   //!< weight of its parallax (>= 0), e.g. min(1, sigma_Z/Z / threshold)
};

/*! \brief Options of recommendYawRate(). */
struct YawHelperOptions {
  double max_rate = 0.5;          //!< |yaw rate| limit (rad/s)
  double horizon = 1.0;           //!< candidates: yaws reachable in this time at max_rate (s)
  int candidates = 41;            //!< number of candidate yaws (odd, >= 3)
  double gain = 2.0;              //!< rate = gain * (target - current) (1/s), clamped
  double centring_weight = 0.5;   //!< w_c of the visibility term
  double margin_px = 40;          //!< features must stay this far inside the image (px)
  /*! the pan joint's range: lower end (rad) */
  double min_yaw = -M_PI, max_yaw = M_PI; //!< the pan joint's range: upper end (rad)
  /*! Where to pan when no feature needs depth information any more (every weight 0): the view in
      which new features' depth is best observed, e.g. the side view (+-pi/2) of a robot driving past
      what it measures. NaN (the default): keep the converged features centred. */
  double home_yaw = std::numeric_limits<double>::quiet_NaN();
  /*! \brief Throws yawdepth::Error for invalid options. */
  void validate() const;
};

/*! \brief What recommendYawRate() found. */
struct YawRecommendation {
  double rate = 0;              //!< recommended yaw rate (rad/s), within +-max_rate
  double target_yaw = 0;        //!< the best candidate yaw (rad)
  double parallax_now = 0;      //!< P at the current yaw (px/s, weighted mean)
  double parallax_target = 0;   //!< P at the target yaw (px/s)
  bool visible_now = true;      //!< every feature inside the image (minus margin) at the current yaw
  bool feasible = true;         //!< some candidate keeps every feature in view (else rate recentres only)
};

/*!
  \brief Recommended yaw rate (see the file for the model).
  \param camera Camera (image size needed: throws yawdepth::Error without one).
  \param rig The yaw mechanism. \param yaw Current yaw reading (rad).
  \param v_velocity Velocity of the vision frame's origin expressed in the vision frame (m/s),
         (vx, vy, vz); for a robot driving forward at v: (0, 0, v).
  \param features The tracked features (at least one).
  \param options The helper's options.
*/
YawRecommendation recommendYawRate(const CameraModel &camera, const YawRig &rig, double yaw,
                                   const Eigen::Vector3d &v_velocity, const std::vector<YawHelperFeature> &features,
                                   const YawHelperOptions &options = YawHelperOptions());

/*! \brief The parallax term P (px/s, weighted mean) of the features for a camera translating at c_T (m/s, camera frame). */
double parallaxRate(const CameraModel &camera, const Eigen::Vector3d &c_T, const std::vector<YawHelperFeature> &features);

} // namespace yawdepth
