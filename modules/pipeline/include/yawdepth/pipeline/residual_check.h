#pragma once
/*!
  \file residual_check.h
  \brief Does each track behave as one rigid point, and was the pixel noise right? A check of every
  `ok` point against its whole track, after any method that fits the whole track (fused, window,
  refine).

  For point \f$ {}^wP \f$ (the estimate, moved to the world through its frame's pose) and each
  observation j of its track that the method did not flag as an outlier, the reprojection residual
  \f$ r_j = \pi({}^{c_j}M_w\,{}^wP) - (u_j, v_j) \f$ with the log's poses, and
  \f[ \chi^2 = \sum_j \frac{\nu_j^{\top} \nu_j}{S_j}, \qquad \nu = 2N - 3 \f]
  the normalised innovations of a Kalman filter along the track (per pixel axis, from the point's
  frame outward) whose state is the error of each frame's pose relative to the point's: rotation
  \f$ \theta \f$ and translation \f$ \tau \f$ per axis, each residual
  \f$ r_j = f\,\theta_j + (f / Z_j)\,\tau_j + \text{pixel noise} \f$ (f the focal length, \f$ Z_j \f$
  the point's depth in frame j). Per-increment motion noise is a random walk shared by every later
  observation of the walk (the rotation error turning each later step), per-pose noise is the
  reference pose's error shared and each pose's own; the yaw readings' noise is each reading's own
  plus the reference's. The variance is per pixel axis, isotropic: a stand-in for the full
  covariance that keeps the check O(observations) and overstates the motion's part somewhat (a
  residual check on a correct model gives s0 below 1, never far above; the walk uses the
  marginal per-axis sigmas of the pose between two rows).

  - **Noise from residuals** (the a-posteriori variance factor of adjustment theory): with at least
    `min_tracks` tracks, \f$ s_0^2 = \mathrm{median}_i\, \chi^2_i / m(\nu_i) \f$, where \f$ m(\nu) \f$
    is the median of a \f$ \chi^2_\nu \f$ variable (Wilson-Hilferty). The median makes it robust to
    the tracks that are not points. \f$ s_0 > 1 \f$ says the pixel noise was larger than the noise
    model's; every `ok` point's covariance is then multiplied by \f$ s_0^2 \f$ (`scale_sigma`). A
    smaller \f$ s_0 \f$ never shrinks a covariance here (the motion noise, which pixel residuals see
    only in part, may be what the sigma is made of); estimatePoints() may make the model tighter
    first (below).
  - **The gate**: a track with \f$ \chi^2 > g \max(1, s_0^2)\, q_p(\nu) \f$ (\f$ q_p \f$ the
    `gate_probability` quantile, g = 1; when estimatePoints() made the model tighter, g = 1 / s0^2
    there, so that the gate is never tighter than the model given) is not one rigid point (a T-junction where a near edge crosses a
    far one, a corner on a silhouette, a track that slid along its epipolar line, which the
    tracker's epipolar gate cannot see): its status becomes `inconsistent`.

  - **The tracker's errors**: a tracker that follows a corner from frame to frame makes errors that
    persist (the corner's appearance changes slowly with the view); the fit absorbs much of them,
    and a covariance computed as if each frame's error were new is too small for a long track. Both
    estimates below use every ok track of 5 observations or more, those the gate then calls
    inconsistent too (the gate weighs the residuals as independent: a track whose errors persist
    fails it as a T-junction does):
    - where the residuals show only the pixels (the motion's modelled part under 5 % of every
      observation's variance, and no per-increment drift, which persists as the tracker's slow part
      does), a white part plus a persistent part per pixel axis,
      \f$ \mathrm{cov}(e_j, e_k) = \sigma^2 [w\,\delta_{jk} + (1 - w)\,\phi^{|j - k|}] \f$, by restricted
      maximum likelihood over the tracks (ResidualCheckResult::error_model; tracks of up to 120
      observations, at most 150 of them);
    - otherwise the AR(1) correlation \f$ \rho \f$ from one image to the next (only the observations
      whose pixel noise dominates, the motion's part under a quarter): the \f$ \rho \f$ under which each
      track's residuals, refitted with that model and whitened (each observation's innovation given
      the previous), have no lag-one correlation, pooled (`correlation`; the raw residuals'
      correlation says less: the fit absorbs the slow part), at the pixel variance of the whitened
      residuals (`correlated_variance_factor`, never below the model's).
    Every ok track's depth variance is then at least what that model allows it with its pixels'
    Jacobians, \f$ \sigma_Z^2 \ge \sigma^2 [(J^\top C^{-1} J)^{-1}]_{ZZ} \f$, at the track's own noise where its
    residuals show it larger beyond doubt (their chi-square beyond its 95 % quantile), a track too
    short to show its own errors (under 5 observations) counting them as independent; a track over
    120 observations is thinned for it (the floor then the larger). The whole covariance is scaled.
    Independent errors give a white model or \f$ \rho \approx 0 \f$: nothing changes. estimatePoints()
    gives \f$ \rho \f$ to a method that models it (NoiseModel::pixel_correlation, modelsTrackerCorrelation())
    where no error_model is measured.

  - **The noise model from the residuals** (estimatePoints(), `reestimate_noise`): when the residuals
    see all of the modelled noise (per-pose motion noise is white and shows in them; per-increment
    drift mostly does not, so then only when the pixels hold at least half of the variance), an
    s0 above 1.1 means the model was s0 times too small: the method runs again with the model scaled
    by s0 (every sigma for per-pose motion noise; the pixels' alone for per-increment noise, whose
    drift the residuals do not show). Since the stand-in overstates the motion's part, a smaller s0
    is trusted only for the pixels and only when they hold at least 80 % of the modelled variance,
    s0^2 is below 1/1.1^2 by more than three of its standard errors, and the residuals' correlation is
    under 0.5 (errors that persist from frame to frame hide in the fit): the pixel noise is then made
    the part of s0^2 the pixels explain, s0^2 taken at the upper end of its evidence (plus three
    standard errors), so that a tracker better than the model gets sigmas that say so, and a correct
    model is never made overconfident. When even that leaves the pixels no variance (the residuals
    are smaller than the motion's modelled part alone: the motion model is what is too large), the
    model is left as given. A tighter model does not tighten the gate:
    what counts as a track that is not one point stays what the model given says.

  `paper` and `exact` use only the last two observations, so the rest of their track says nothing
  about their estimate: they are not checked.
*/
#include <limits>
#include <vector>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>
#include <yawdepth/geometry/track_inputs.h>

namespace yawdepth {

/*! \brief Options of checkResiduals(). */
struct ResidualCheckOptions {
  bool enabled = false;            //!< estimatePoints(): run the check after the method
  double gate_probability = 0.999; //!< p of the chi-square gate, in (0.5, 1)
  bool scale_sigma = true;         //!< multiply the ok points' covariance by s0^2 when s0 > 1
  int min_tracks = 20;             //!< fewest checked tracks for s0 (else s0 = 1)
  bool correlated = true;          //!< the tracker's correlated errors: each ok depth's variance at least the AR(1) one
  /*! estimatePoints(): when the residuals say the noise model was wrong (see the file: larger, or
      smaller with strong evidence and the pixels dominating), run the method again with the model
      they say (the pixel noise at least 0.01 px), then check. */
  bool reestimate_noise = true;
  /*! The gate at the noise model given whatever s0 says (estimatePoints() when the tracks do not fit
      the motion: s0 then measures the mistake, not the noise). */
  bool gate_at_model = false;
  /*! \brief Throws yawdepth::Error for a probability outside (0.5, 1) or min_tracks < 1. */
  void validate() const;
};

/*! \brief One track's fit: chi-square and its degrees of freedom (0: nothing to check). */
struct TrackResidual {
  double chi2 = std::numeric_limits<double>::quiet_NaN(); //!< see the file
  int dof = 0;                                            //!< 2N - 3 (N the observations used)
  double rms_px = std::numeric_limits<double>::quiet_NaN(); //!< root mean square residual (px, per observation)
  /*! The depth's 1-sigma (m, the point's frame) that the tracker's error model allows this track with
      the poses known, at the model's pooled noise: its Cramer-Rao bound under that model (the model:
      ResidualCheckResult::error_model when estimated, else the AR(1) one of `correlation`; NaN: neither,
      a model without correlation (white), or a track under 5 observations). */
  double sigma_z_bound = std::numeric_limits<double>::quiet_NaN();
};

/*! \brief The tracker's errors along a track, per pixel axis (checkResiduals() measures it, see the
    file): \f$ \mathrm{cov}(e_j, e_k) = \sigma^2 [w\,\delta_{jk} + (1 - w)\,\phi^{|j - k|}] \f$. */
struct TrackerErrorModel {
  double white = 1.0;    //!< w: the white share of the variance (1: independent errors)
  double phi = 0.0;      //!< phi: the persistent part's correlation from one image to the next
  double variance = 0.0; //!< sigma^2 (px^2; 0: not estimated)
};

/*! \brief What checkResiduals() found. */
struct ResidualCheckResult {
  double variance_factor = 1.0; //!< s0^2 (1 with fewer than min_tracks tracks)
  double variance_factor_sigma = 0; //!< standard error of s0^2 from the tracks' spread (0 with fewer than min_tracks tracks)
  double sigma_scale = 1.0;     //!< factor applied to every ok point's sigma (1 or s0)
  int tracks_used = 0;          //!< ok tracks with dof >= 1
  int inconsistent = 0;         //!< ok points the gate turned `inconsistent`
  double correlation = 0;       //!< rho: the AR(1) correlation of the tracker's errors the tracks say (0: not estimated)
  /*! The variance factor of the tracks' residuals whitened under rho (refitted, each observation's
      innovation; the median over tracks whose pixels dominate, as variance_factor): the AR(1) model's
      pixel noise is sqrt of it times the model's (0: not estimated). */
  double correlated_variance_factor = 0;
  /*! The tracker's errors, white and persistent parts (restricted maximum likelihood over the tracks
      whose pixels dominate): every ok depth's variance is at least what it allows the track. */
  TrackerErrorModel error_model;
  int correlation_scaled = 0;   //!< ok points whose covariance the correlation made larger
  double pixel_share = 0;       //!< mean share of the pixels in the checked observations' modelled variance
  double noise_scale = 1;       //!< estimatePoints(): the factor the noise model was scaled by before the final run (1: none)
  std::vector<TrackResidual> tracks; //!< per track (same order as the tracks)
};

/*!
  \brief The check on every ok point (see the file): s0 from the residuals, the covariances scaled,
  the tracks that are not one point made `inconsistent`.
  \param camera Camera model. \param rig Yaw rig. \param motion The log.
  \param noise The noise model.
  \param tracks The features (with the log, validated first: yawdepth::validateInputs()). \param outliers Per track and observation: flagged by the method (may be empty).
  \param options Options (validated). \param points The estimates, one per track; changed in place.
*/
ResidualCheckResult checkResiduals(const CameraModel &camera, const YawRig &rig,
                                   const std::vector<MotionSample> &motion, const std::vector<Track> &tracks,
                                   const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                   const ResidualCheckOptions &options, std::vector<PointEstimate> &points);

/*!
  \brief checkResiduals() on input already validated (yawdepth::validateInputs(): what
  yawdepth::estimatePoints() passes); the same results.
*/
ResidualCheckResult checkResiduals(const CameraModel &camera, const YawRig &rig, const TracksByFrame &input,
                                   const std::vector<std::vector<bool>> &outliers, const NoiseModel &noise,
                                   const ResidualCheckOptions &options, std::vector<PointEstimate> &points);

} // namespace yawdepth
