#pragma once
/*!
  \file camera_model.h
  \brief Pinhole camera with lens distortion, and its exact inverse (undistortion).

  Pixels: \f$ u = u_0 + k_x x_d,\ v = v_0 + k_y y_d \f$ where \f$(x_d, y_d)\f$ is the distorted
  normalised point; eq. (3) of the paper inverts this after undistortion. Three distortion models:
  - `Brown`: OpenCV's model, coefficients in OpenCV order k1 k2 p1 p2 [k3 [k4 k5 k6]]
    (0, 4, 5 or 8 values; the rational part k4..k6 is used when 8 are given).
  - `ViSP`: ViSP's kud model, \f$ x_d = x (1 + k_{ud} r^2) \f$ (undistorted to distorted, as
    vpMeterPixelConversion applies it). Its kdu companion is an approximation of the inverse and is
    not needed: undistortion here is the exact inverse of the kud projection.
  - `KannalaBrandt`: the fisheye model of OpenCV's cv::fisheye (ROS's and Kalibr's `equidistant`),
    coefficients k1 k2 k3 k4: with \f$ r = |(x, y)| \f$ and \f$ \theta = \arctan r \f$ (the ray's
    angle to the optical axis), \f$ \theta_d = \theta (1 + k_1 \theta^2 + k_2 \theta^4 + k_3 \theta^6
    + k_4 \theta^8) \f$ and \f$ (x_d, y_d) = (\theta_d / r) (x, y) \f$ (cv::fisheye::projectPoints
    without skew). A normalised point holds rays below 90 degrees only; an observed pixel whose ray
    is at 90 degrees or more (a lens with a field over 180 degrees), or beyond the first maximum of
    \f$ \theta_d(\theta) \f$, does not undistort (undistort() returns false).
  Undistortion is solved by Newton's method to convergence (|step| below 1e-15 in normalised
  units, i.e. far below 1e-9 px), not by a fixed number of iterations.
*/
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpImagePoint.h>

namespace yawdepth {

/*!
  \brief A camera's intrinsics and lens distortion (see the file's description), built from ViSP
  parameters, from OpenCV/Brown coefficients, or by loadCameraFile().
*/
class CameraModel {
public:
  /*! \brief The distortion model. */
  enum class Distortion {
    None,  //!< Pinhole, no distortion.
    Brown, //!< OpenCV's model, k1 k2 p1 p2 k3 k4 k5 k6.
    ViSP,  //!< ViSP's kud model (x_d = x (1 + kud r^2)).
    KannalaBrandt //!< Fisheye (cv::fisheye, ROS/Kalibr `equidistant`), k1 k2 k3 k4.
  };

  /*! \brief An identity-like default camera (px = py = 1, u0 = v0 = 0, no distortion). */
  CameraModel();
  /*!
    \brief Pinhole camera, or ViSP's kud model when `cam` is `perspectiveProjWithDistortion`.
    \param cam ViSP camera parameters.
    \param width, height Image size in pixels (0 when unknown).
  */
  explicit CameraModel(const vpCameraParameters &cam, unsigned width = 0, unsigned height = 0);
  /*!
    \brief OpenCV/Brown camera.
    \param fx, fy Focal lengths in pixels (\f$k_x, k_y\f$). \param u0, v0 Principal point.
    \param coeffs 0, 4, 5 or 8 coefficients in OpenCV order. Throws yawdepth::Error otherwise.
    \param width, height Image size in pixels (0 when unknown).
  */
  static CameraModel brown(double fx, double fy, double u0, double v0, const std::vector<double> &coeffs,
                           unsigned width = 0, unsigned height = 0);
  /*!
    \brief Kannala-Brandt fisheye camera (OpenCV's cv::fisheye, ROS and Kalibr `equidistant`).
    \param fx, fy Focal lengths in pixels. \param u0, v0 Principal point.
    \param k The 4 coefficients k1 k2 k3 k4 (finite). Throws yawdepth::Error otherwise.
    \param width, height Image size in pixels (0 when unknown).
  */
  static CameraModel kannalaBrandt(double fx, double fy, double u0, double v0, const std::vector<double> &k,
                                   unsigned width = 0, unsigned height = 0);

  /*! \brief The distortion model. */
  Distortion distortion() const { return model_; }
  /*! \brief The pinhole part as ViSP parameters (perspectiveProjWithoutDistortion), or the ViSP
      kud/kdu model when distortion() is ViSP. */
  const vpCameraParameters &parameters() const { return cam_; }
  double kx() const { return kx_; }         //!< Focal length along u, in pixels (ViSP's px).
  double ky() const { return ky_; }         //!< Focal length along v, in pixels (ViSP's py).
  double u0() const { return u0_; }         //!< Principal point, u (pixels).
  double v0() const { return v0_; }         //!< Principal point, v (pixels).
  unsigned width() const { return width_; }   //!< Image width in pixels (0 when unknown).
  unsigned height() const { return height_; } //!< Image height in pixels (0 when unknown).
  /*! \brief Brown coefficients, always 8 (k1 k2 p1 p2 k3 k4 k5 k6), zero-padded. For the ViSP
      model these are the equivalent Brown coefficients (k1 = kud, the others 0); all zero for None
      and for KannalaBrandt (which has no Brown form: check distortion() first). */
  const std::vector<double> &brownCoefficients() const { return coeffs_; }
  /*! \brief Kannala-Brandt coefficients, always 4 (k1 k2 k3 k4); all zero for the other models. */
  const std::vector<double> &kannalaBrandtCoefficients() const { return kb_; }
  /*!
    \brief Bound on the angle (radians) between the optical axis and a ray that undistort() can
    return. KannalaBrandt: pi/2, or the angle where \f$ \theta_d(\theta) \f$ stops increasing when
    that comes first (pixels beyond it do not undistort). The other models: pi/2 (a normalised
    point is a ray below 90 degrees; their valid range is checked point by point).
  */
  double maxRayAngle() const { return theta_max_; }

  /*!
    \brief Distort a normalised point: \f$ (x, y) \mapsto (x_d, y_d) \f$.
    \param m Normalised (undistorted) point (x, y).
    \param J If not null, receives \f$ \partial (x_d,y_d) / \partial (x,y) \f$.
  */
  Eigen::Vector2d distortNormalized(const Eigen::Vector2d &m, Eigen::Matrix2d *J = nullptr) const;
  /*! \brief Normalised (undistorted) point to observed pixel. */
  Eigen::Vector2d project(const Eigen::Vector2d &m) const;
  /*!
    \brief Observed (distorted) pixel to undistorted normalised point, exactly.
    \param uv Pixel (u, v).
    \param m Output normalised point (x, y).
    \param J If not null, receives \f$ \partial (x,y) / \partial (u,v) \f$ (for noise propagation).
    \return false when Newton's method does not converge (pixel outside the model's valid range),
    and for KannalaBrandt when the pixel's ray is at maxRayAngle() or more (90 degrees or beyond).
  */
  bool undistort(const Eigen::Vector2d &uv, Eigen::Vector2d &m, Eigen::Matrix2d *J = nullptr) const;
  /*! \brief Same as undistort(), ViSP types. Throws yawdepth::Error when it does not converge. */
  void pixelToMeter(const vpImagePoint &ip, double &x, double &y) const;
  /*! \brief Undistorted pixel (pinhole, no distortion) of an observed pixel. */
  bool undistortPixel(const Eigen::Vector2d &uv, Eigen::Vector2d &uv_undist) const;

private:
  /*! \brief The intrinsics and image size set, no distortion yet (the named constructors' shared part). */
  static CameraModel withIntrinsics(double fx, double fy, double u0, double v0, unsigned width, unsigned height);
  /*! \brief undistort() for KannalaBrandt, from the distorted normalised point `target`. */
  bool undistortKannalaBrandt(const Eigen::Vector2d &target, Eigen::Vector2d &m, Eigen::Matrix2d *J) const;
  /*! \brief The tail of both undistortions: accepts the root `x` of distorted point `target` when
      distorting it gives `target` back (residual check), writes it to `m` and, if `J` is not null,
      \f$ \partial (x,y) / \partial (u,v) \f$. */
  bool acceptRoot(const Eigen::Vector2d &x, const Eigen::Vector2d &target, Eigen::Vector2d &m, Eigen::Matrix2d *J) const;

  Distortion model_ = Distortion::None;
  vpCameraParameters cam_;
  double kx_ = 1, ky_ = 1, u0_ = 0, v0_ = 0;
  double kud_ = 0;
  std::vector<double> coeffs_ = std::vector<double>(8, 0.0);
  std::vector<double> kb_ = std::vector<double>(4, 0.0);
  double theta_max_ = 1.5707963267948966;                        // pi/2; KannalaBrandt: its valid range
  double theta_d_max_ = std::numeric_limits<double>::infinity(); // KannalaBrandt: theta_d(theta_max_)
  unsigned width_ = 0, height_ = 0;
};

} // namespace yawdepth
