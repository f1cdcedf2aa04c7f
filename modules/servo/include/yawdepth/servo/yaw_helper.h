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

  The model (receding-horizon active structure from motion): the features are fixed points in the
  vision frame (their bearing and depth now). A candidate target yaw \f$\theta\f$ is played
  forward over `lookahead` seconds: the robot keeps its velocity, the pan moves toward
  \f$\theta\f$ at \f$ \dot\theta = \mathrm{clamp}(g\,(\theta - \theta_t), \pm\dot\theta_{\max}) \f$
  (the rate this function will recommend), and at each of `steps` instants t the Fisher information
  that a view from there adds on feature i's log-depth is
  \f[ \Delta I_i(t) = \frac{f_{\mathrm{frames}}\,\Delta t}{\sigma_{px}^2}
      \Big\lVert K\,\frac{\partial \mathbf m_i(t)}{\partial \log Z_i} \Big\rVert^2,\qquad
      \frac{\partial \mathbf m_i(t)}{\partial \log Z_i} = \frac{\partial \pi}{\partial\, {}^{c}\mathbf P}\,
      {}^{c(t)}\mathbf R_{v}\,(\mathbf P_i - \mathbf C_0) \f]
  (the image motion that a change of the depth along the current bearing causes in the view at t:
  zero at t = 0, growing with the baseline from the current centre \f$\mathbf C_0\f$), counted
  only while the feature is inside the image minus `margin_px`. It includes both ways the yaw
  helps: the pan's lever arm (YawRig::cameraOffset(), the paper's Lb) translates the camera, and
  the yaw decides which features stay in view and where. The candidate's score is D-optimal, the
  gain in log-determinant of the features' depth information:
  \f[ J(\theta) = \sum_i w_i \log\Big(1 + \sigma_{r,i}^2 \sum_t \Delta I_i(t)\Big) \f]
  with \f$\sigma_{r,i}\f$ the feature's current relative depth sigma (1 when unknown): a feature
  that is already well measured gains little, one that is not gains most, so the pan serves the
  worst-measured features first. The candidates are the yaws reachable within `horizon` seconds at
  `max_rate` (and within [min_yaw, max_yaw]) and the current yaw; a candidate that loses a weighted
  feature now in view (it leaves the image minus the margin at the candidate yaw) is inadmissible
  unless every candidate does. The winner maximises \f$ J/J_{\max} - w_c\,c(\theta)^2 \f$, with
  \f$c\f$ the centroid offset of the features from the principal point relative to the half image
  (averaged over the lookahead; with the default \f$w_c = 0\f$ the features are recentred only
  when nothing can be learnt, e.g. a camera that does not translate), and the current yaw is kept
  unless the winner beats it by `switch_margin`. Feature weights \f$w_i\f$ (e.g. 0 for a converged
  feature, 1 otherwise) scale each feature's term. When every weight is 0 and `home_yaw` is set,
  the target is home_yaw (as far as the horizon reaches): the features are measured, the pan goes
  back to looking for new ones.

  Use it as a secondary task: the primary IBVS task usually uses every joint, so the classic
  projector I - W^+W is zero; ViSP's large projection operator (vpServo::secondaryTask(de2dt,
  true)) applies the yaw rate in the directions that keep the error norm decreasing as the
  primary task wants, while the error is large. Or command the pan with it directly when the pan
  is not part of the servo task.
*/
#include <cmath>
#include <limits>
#include <utility>
#include <vector>
#include <Eigen/Core>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief One feature as the helper sees it: its undistorted normalised position, depth and weight. */
struct YawHelperFeature {
  double x = 0;        //!< normalised (undistorted) image coordinate x in the current camera frame
  double y = 0;        //!< normalised (undistorted) image coordinate y in the current camera frame
  double Z = 1;        //!< depth (m), > 0: the estimate, or the prior
  double weight = 1;   //!< weight of its depth information (>= 0), e.g. 0 once converged, 1 before
  /*! its current relative depth sigma sigma_Z / Z (> 0); NaN (the default): unknown, taken as 1 */
  double sigma_rel = std::numeric_limits<double>::quiet_NaN();
};

/*! \brief Options of recommendYawRate(). */
struct YawHelperOptions {
  double max_rate = 0.5;          //!< |yaw rate| limit (rad/s)
  double horizon = 1.0;           //!< candidates: yaws reachable in this time at max_rate (s)
  int candidates = 41;            //!< number of candidate yaws (odd, >= 3)
  double gain = 2.0;              //!< rate = gain * (target - current) (1/s), clamped
  /*! w_c of the recentring term while information is gained (0: the features are recentred only
      when nothing can be learnt; measured with bench_active_yaw, any w_c > 0 makes the pan follow
      the targets' centroid, which costs time and buys nothing that the visibility rule does not) */
  double centring_weight = 0.0;
  double margin_px = 40;          //!< features must stay this far inside the image (px)
  double lookahead = 3.0;         //!< how far ahead each candidate is played (s)
  int steps = 15;                 //!< instants over the lookahead (>= 1)
  double sigma_px = 0.3;          //!< pixel noise of the tracks (px), scales the information
  double frame_rate = 10.0;       //!< frames per second that the estimator gets (Hz)
  /*! the current yaw is kept unless the best candidate's score beats it by this much (scores are
      relative to the best information gain: 0.01 = 1 %) */
  double switch_margin = 0.01;
  double min_yaw = -M_PI; //!< the pan joint's range: lower end (rad)
  double max_yaw = M_PI;  //!< the pan joint's range: upper end (rad)
  /*! Where to pan when no feature needs depth information any more (every weight 0): the view in
      which new features' depth is best observed, e.g. the side view (+-pi/2) of a robot driving past
      what it measures. NaN (the default): keep the converged features centred. */
  double home_yaw = std::numeric_limits<double>::quiet_NaN();
  /*! \brief Throws yawdepth::Error for invalid options. */
  void validate() const;
};

/*! \brief Why the pan goes where YawRecommendation::target_yaw says. */
enum class YawMode {
  Measure,  //!< toward the most depth information on the features that still need it
  Explore,  //!< nothing to learn from the tracked features: toward the view longest unseen (YawHelper)
  Home,     //!< every feature measured, nothing left to explore: toward YawHelperOptions::home_yaw
  Recentre  //!< nothing to learn and no home view: keep the features centred
};

/*! \brief What recommendYawRate() found. */
struct YawRecommendation {
  double rate = 0;              //!< recommended yaw rate (rad/s), within +-max_rate
  double target_yaw = 0;        //!< the best candidate yaw (rad)
  double parallax_now = 0;      //!< translational flow at the current yaw, standing (px/s, weighted mean: parallaxRate())
  double parallax_target = 0;   //!< the same at the target yaw, panning toward it (px/s)
  double information_now = 0;   //!< J of holding the current yaw (see the file)
  double information_target = 0; //!< J of the target yaw
  bool visible_now = true;      //!< every feature inside the image (minus margin) at the current yaw
  bool feasible = true;         //!< some candidate keeps every weighted feature now in view in view
  YawMode mode = YawMode::Measure; //!< why the target was chosen
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

/*! \brief Options of YawHelper's exploration (the views it has not looked at recently). */
struct YawExploreOptions {
  bool enabled = true;        //!< explore when the tracked features give nothing to learn
  double bin = M_PI / 180;    //!< width of a bearing bin of the look-up memory (rad)
  /*! a bearing looked at this long ago is stale to 1 - 1/e (s): what is there may have changed
      (the robot moved, something came into range) */
  double stale_time = 10.0;
  /*! explore only toward a view whose bins are on average at least this stale (0..1); otherwise the
      pan goes home (or recentres) */
  double min_stale = 0.3;
  /*! a view's worth is its staleness times (floor + (1 - floor) |sin(angle to the motion)|): the
      parallax that a new feature there would give, with this floor (0..1) for the views ahead that
      the motion will later turn to the side */
  double parallax_floor = 0.2;
  /*! \brief Throws yawdepth::Error for invalid options. */
  void validate() const;
};

/*!
  \brief The yaw helper with a memory: recommendYawRate() plus exploration of unseen bearings.

  recommendYawRate() knows only the features it is given: once they are measured there is nothing to
  learn, and a target the camera has never seen cannot draw the pan. YawHelper remembers, per
  bearing bin of the vision frame (the yaw about the pan axis, `YawExploreOptions::bin` wide), when
  the camera's horizontal field of view last covered it. Each call:
  - marks the bins in view at the current yaw as seen now;
  - if the tracked features still have depth information to give (recommendYawRate()'s best score
    is not zero), returns that recommendation (YawMode::Measure): measuring comes first, and a
    feature found while exploring takes the pan from then on;
  - otherwise, if some yaw within [min_yaw, max_yaw] has a field of view whose bins' staleness
    \f$ s_b = 1 - e^{-(t - t_b)/\tau} \f$ (1 for a bin never seen; \f$\tau\f$ = stale_time)
    averages at least min_stale, pans toward the view of most worth: its staleness times the
    parallax a new feature there would give (\f$ f + (1 - f)\,|\sin\beta| \f$, \f$\beta\f$ its
    bearing from the direction of travel, f = parallax_floor), less 0.05 per pi of pan travel
    (YawMode::Explore: a sweep over what it has not looked at, sides of the path first);
  - otherwise goes to home_yaw (YawMode::Home) or recentres (YawMode::Recentre).

  The bins are bearings relative to the robot (the vision frame), not the world: a bearing seen a
  while ago becomes stale again as the robot moves. Call it once per frame with increasing times.
*/
class YawHelper {
public:
  /*! \brief A helper for this camera (needs its image size) and rig; throws yawdepth::Error for bad options. */
  YawHelper(const CameraModel &camera, const YawRig &rig, const YawHelperOptions &options = YawHelperOptions(),
            const YawExploreOptions &explore = YawExploreOptions());
  /*!
    \brief The recommended yaw rate now.
    \param t Time of this call (s), not before the previous call's.
    \param yaw Current yaw reading (rad).
    \param v_velocity Velocity of the vision frame's origin in the vision frame (m/s).
    \param features The tracked features (may be empty: then it explores, or goes home).
  */
  YawRecommendation recommend(double t, double yaw, const Eigen::Vector3d &v_velocity,
                              const std::vector<YawHelperFeature> &features);
  /*! \brief Forgets where the camera has looked. */
  void reset();
  /*! \brief Staleness (0..1) of the view at yaw `yaw` at time t (the mean over its bins). */
  double staleness(double t, double yaw) const;

private:
  std::pair<int, int> binsInView(double yaw) const;
  CameraModel camera_;
  YawRig rig_;
  YawHelperOptions options_;
  YawExploreOptions explore_;
  double fov_left_ = 0, fov_right_ = 0; // bearings of the image's left / right edge off the optical axis (rad)
  double bin_origin_ = 0;               // bearing of bin 0's lower edge (rad)
  std::vector<double> last_seen_;       // per bin: time it was last in view (-inf: never)
  double last_t_ = -std::numeric_limits<double>::infinity();
};

/*! \brief The parallax term P (px/s, weighted mean) of the features for a camera translating at c_T (m/s, camera frame). */
double parallaxRate(const CameraModel &camera, const Eigen::Vector3d &c_T, const std::vector<YawHelperFeature> &features);

} // namespace yawdepth
