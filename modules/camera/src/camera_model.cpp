/*!
  \file camera_model.cpp
  \brief CameraModel: Brown/OpenCV, ViSP kud and Kannala-Brandt distortion, exact undistortion by
  Newton's method.
*/
#include <yawdepth/camera/camera_model.h>

#include <Eigen/LU>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

/*! \brief Shortest round-trip text of a double, for error messages. */
std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

/*! \brief Throws yawdepth::Error unless the pinhole intrinsics are usable. */
void checkIntrinsics(double fx, double fy, double u0, double v0) {
  if (!std::isfinite(fx) || !(fx > 0))
    throw Error("camera: focal length fx = " + num(fx) + " must be finite and > 0");
  if (!std::isfinite(fy) || !(fy > 0))
    throw Error("camera: focal length fy = " + num(fy) + " must be finite and > 0");
  if (!std::isfinite(u0) || !std::isfinite(v0))
    throw Error("camera: principal point (" + num(u0) + ", " + num(v0) + ") must be finite");
}

/*! \brief Pinhole vpCameraParameters, with ViSP exceptions turned into yawdepth::Error. */
vpCameraParameters pinhole(double fx, double fy, double u0, double v0) {
  vpCameraParameters cam;
  try {
    cam.initPersProjWithoutDistortion(fx, fy, u0, v0);
  } catch (const std::exception &e) {
    throw Error(std::string("camera: ViSP rejected the intrinsics: ") + e.what());
  }
  return cam;
}

/*!
  \brief OpenCV's distortion (k1 k2 p1 p2 k3 k4 k5 k6) of a normalised point, with its Jacobian.
  \return false when the result is not finite (e.g. the rational denominator vanishes).
*/
bool distortBrown(const double *k, double x, double y, double &xd, double &yd, Eigen::Matrix2d *J,
                  double *radial_out = nullptr) {
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3], k3 = k[4], k4 = k[5], k5 = k[6], k6 = k[7];
  const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double a = 1 + k1 * r2 + k2 * r4 + k3 * r6;
  const double b = 1 + k4 * r2 + k5 * r4 + k6 * r6;
  const double radial = a / b;
  xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  if (radial_out)
    *radial_out = radial;
  if (J) {
    // d radial / d r2
    const double da = k1 + 2 * k2 * r2 + 3 * k3 * r4;
    const double db = k4 + 2 * k5 * r2 + 3 * k6 * r4;
    const double dR = (da * b - a * db) / (b * b);
    (*J)(0, 0) = radial + 2 * x * x * dR + 2 * p1 * y + 6 * p2 * x;
    (*J)(0, 1) = 2 * x * y * dR + 2 * p1 * x + 2 * p2 * y;
    (*J)(1, 0) = 2 * x * y * dR + 2 * p1 * x + 2 * p2 * y;
    (*J)(1, 1) = radial + 2 * y * y * dR + 6 * p1 * y + 2 * p2 * x;
  }
  return std::isfinite(xd) && std::isfinite(yd) && std::isfinite(radial) &&
         (!J || J->allFinite());
}

/*!
  \brief Kannala-Brandt \f$ \theta_d(\theta) = \theta (1 + k_1 \theta^2 + k_2 \theta^4 + k_3 \theta^6 +
  k_4 \theta^8) \f$, and its derivative in `dtd` when not null.
*/
double kbThetaD(const double *k, double t, double *dtd = nullptr) {
  const double t2 = t * t, t4 = t2 * t2, t6 = t4 * t2, t8 = t4 * t4;
  if (dtd)
    *dtd = 1 + 3 * k[0] * t2 + 5 * k[1] * t4 + 7 * k[2] * t6 + 9 * k[3] * t8;
  return t * (1 + k[0] * t2 + k[1] * t4 + k[2] * t6 + k[3] * t8);
}

/*! \brief Below this radius (normalised) the Kannala-Brandt scale uses its Taylor series. */
constexpr double kKbSeriesRadius = 1e-6;

/*!
  \brief Kannala-Brandt distortion of a normalised point, \f$ (x_d, y_d) = s(r) (x, y) \f$ with
  \f$ s = \theta_d(\arctan r) / r \f$, with its Jacobian \f$ s I + (s'(r)/r)\, m m^T \f$.
  Near the centre \f$ s = 1 + (k_1 - 1/3) r^2 + O(r^4) \f$ (no 0/0).
  \return false when the result is not finite.
*/
bool distortKannalaBrandt(const double *k, double x, double y, double &xd, double &yd, Eigen::Matrix2d *J) {
  const double r = std::hypot(x, y), r2 = r * r;
  double s = 1, g = 0; // s = theta_d / r, g = (ds/dr) / r
  if (r < kKbSeriesRadius) {
    const double c1 = k[0] - 1.0 / 3.0;
    s = 1 + c1 * r2;
    g = 2 * c1;
  } else {
    double dtd = 0;
    s = kbThetaD(k, std::atan(r), &dtd) / r;
    g = std::isinf(r2) ? 0.0 : (dtd / (1 + r2) - s) / r2; // ds/dr = (theta_d' dtheta/dr - s) / r
  }
  xd = s * x;
  yd = s * y;
  if (J) {
    (*J)(0, 0) = s + g * x * x;
    (*J)(0, 1) = g * x * y;
    (*J)(1, 0) = g * x * y;
    (*J)(1, 1) = s + g * y * y;
  }
  return std::isfinite(xd) && std::isfinite(yd) && (!J || J->allFinite());
}

/*!
  \brief The angle in (0, pi/2] up to which \f$ \theta_d(\theta) \f$ increases: pi/2, or the first
  zero of \f$ \theta_d'(\theta) \f$ below it (sampled every pi/8192, then bisected).
*/
double kbMonotonicLimit(const double *k) {
  const double half_pi = 2 * std::atan(1.0);
  constexpr int kSamples = 4096;
  double prev = 0;
  for (int i = 1; i <= kSamples; ++i) {
    const double t = half_pi * i / kSamples;
    double d = 0;
    kbThetaD(k, t, &d);
    if (!(d > 0)) {
      double lo = prev, hi = t; // theta_d' > 0 at lo, <= 0 at hi
      for (int it = 0; it < 80 && hi - lo > 1e-16; ++it) {
        const double mid = 0.5 * (lo + hi);
        kbThetaD(k, mid, &d);
        (d > 0 ? lo : hi) = mid;
      }
      return lo;
    }
    prev = t;
  }
  return half_pi;
}

} // namespace

CameraModel::CameraModel() : cam_(pinhole(1, 1, 0, 0)) {}

CameraModel::CameraModel(const vpCameraParameters &cam, unsigned width, unsigned height)
    : cam_(cam), width_(width), height_(height) {
  kx_ = cam.get_px();
  ky_ = cam.get_py();
  u0_ = cam.get_u0();
  v0_ = cam.get_v0();
  checkIntrinsics(kx_, ky_, u0_, v0_);
  switch (cam.get_projModel()) {
  case vpCameraParameters::perspectiveProjWithoutDistortion:
    model_ = Distortion::None;
    break;
  case vpCameraParameters::perspectiveProjWithDistortion:
    model_ = Distortion::ViSP;
    kud_ = cam.get_kud();
    if (!std::isfinite(kud_) || !std::isfinite(cam.get_kdu()))
      throw Error("camera: ViSP distortion kud = " + num(kud_) + ", kdu = " + num(cam.get_kdu()) +
                  " must be finite");
    coeffs_[0] = kud_; // the kud model is Brown with k1 = kud only
    break;
  default:
    throw Error("camera: unsupported ViSP projection model (only perspectiveProjWithoutDistortion and "
                "perspectiveProjWithDistortion are handled)");
  }
}

CameraModel CameraModel::withIntrinsics(double fx, double fy, double u0, double v0, unsigned width, unsigned height)
{
  CameraModel c;
  c.cam_ = pinhole(fx, fy, u0, v0);
  c.kx_ = fx;
  c.ky_ = fy;
  c.u0_ = u0;
  c.v0_ = v0;
  c.width_ = width;
  c.height_ = height;
  return c;
}

CameraModel CameraModel::brown(double fx, double fy, double u0, double v0, const std::vector<double> &coeffs,
                               unsigned width, unsigned height) {
  checkIntrinsics(fx, fy, u0, v0);
  const std::size_t n = coeffs.size();
  if (n != 0 && n != 4 && n != 5 && n != 8)
    throw Error("camera: " + std::to_string(n) +
                " distortion coefficients given; expected 0, 4, 5 or 8 (k1 k2 p1 p2 [k3 [k4 k5 k6]])");
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(coeffs[i]))
      throw Error("camera: distortion coefficient " + std::to_string(i) + " = " + num(coeffs[i]) +
                  " must be finite");
  CameraModel c = withIntrinsics(fx, fy, u0, v0, width, height);
  c.model_ = n == 0 ? Distortion::None : Distortion::Brown;
  c.coeffs_.assign(8, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    c.coeffs_[i] = coeffs[i];
  return c;
}

CameraModel CameraModel::kannalaBrandt(double fx, double fy, double u0, double v0, const std::vector<double> &k,
                                       unsigned width, unsigned height) {
  checkIntrinsics(fx, fy, u0, v0);
  if (k.size() != 4)
    throw Error("camera: " + std::to_string(k.size()) +
                " Kannala-Brandt (fisheye) coefficients given; expected 4 (k1 k2 k3 k4)");
  for (std::size_t i = 0; i < k.size(); ++i)
    if (!std::isfinite(k[i]))
      throw Error("camera: Kannala-Brandt coefficient k" + std::to_string(i + 1) + " = " + num(k[i]) +
                  " must be finite");
  CameraModel c = withIntrinsics(fx, fy, u0, v0, width, height);
  c.model_ = Distortion::KannalaBrandt;
  c.kb_ = k;
  c.theta_max_ = kbMonotonicLimit(c.kb_.data());
  c.theta_d_max_ = kbThetaD(c.kb_.data(), c.theta_max_);
  return c;
}

Eigen::Vector2d CameraModel::distortNormalized(const Eigen::Vector2d &m, Eigen::Matrix2d *J) const {
  if (model_ == Distortion::None) {
    if (J)
      J->setIdentity();
    return m;
  }
  if (model_ == Distortion::KannalaBrandt) {
    double xd = 0, yd = 0;
    distortKannalaBrandt(kb_.data(), m.x(), m.y(), xd, yd, J);
    return Eigen::Vector2d(xd, yd);
  }
  // ViSP's kud model is Brown with k1 = kud (coeffs_ holds that): x_d = x (1 + kud r^2).
  double xd = 0, yd = 0;
  distortBrown(coeffs_.data(), m.x(), m.y(), xd, yd, J);
  return Eigen::Vector2d(xd, yd);
}

Eigen::Vector2d CameraModel::project(const Eigen::Vector2d &m) const {
  const Eigen::Vector2d d = distortNormalized(m);
  return Eigen::Vector2d(u0_ + kx_ * d.x(), v0_ + ky_ * d.y());
}

bool CameraModel::undistort(const Eigen::Vector2d &uv, Eigen::Vector2d &m, Eigen::Matrix2d *J) const {
  const Eigen::Vector2d target((uv.x() - u0_) / kx_, (uv.y() - v0_) / ky_);
  if (!target.allFinite())
    return false;
  if (model_ == Distortion::None) {
    m = target;
    if (J)
      *J << 1.0 / kx_, 0.0, 0.0, 1.0 / ky_;
    return true;
  }
  if (model_ == Distortion::KannalaBrandt)
    return undistortKannalaBrandt(target, m, J);

  const double *k = coeffs_.data();
  const double eps = std::numeric_limits<double>::epsilon();
  Eigen::Vector2d x = target; // start from the distorted point
  Eigen::Matrix2d Jd;
  double prev_step = std::numeric_limits<double>::infinity();
  bool converged = false;
  for (int it = 0; it < 50; ++it) {
    double xd = 0, yd = 0;
    if (!distortBrown(k, x.x(), x.y(), xd, yd, &Jd))
      return false;
    const double det = Jd.determinant();
    if (!std::isfinite(det) || det == 0.0)
      return false;
    const Eigen::Vector2d f(xd - target.x(), yd - target.y());
    const Eigen::Vector2d step = Jd.inverse() * f;
    if (!step.allFinite())
      return false;
    x -= step;
    const double s = step.norm();
    // Converged when the step is below 1e-15 (relative to |x| when |x| > 1, so that rounding
    // noise of large points cannot stall it), or when the step has reached rounding level and
    // stopped shrinking (near a fold the Jacobian is small and amplifies rounding noise).
    if (s <= 1e-15 * std::max(1.0, x.norm()) || (s < 1e3 * eps * std::max(1.0, x.norm()) && s >= 0.5 * prev_step)) {
      converged = true;
      break;
    }
    prev_step = s;
  }
  if (!converged || !x.allFinite())
    return false;

  // Reject roots on a folded branch: the model must be locally orientation-preserving with a
  // positive radial factor along the whole segment from the centre to the solution (the valid
  // region is the one around the principal point).
  constexpr int kSamples = 32;
  for (int i = 1; i <= kSamples; ++i) {
    const Eigen::Vector2d p = x * (static_cast<double>(i) / kSamples);
    double xd = 0, yd = 0, radial = 0;
    Eigen::Matrix2d Js;
    if (!distortBrown(k, p.x(), p.y(), xd, yd, &Js, &radial))
      return false;
    if (!(radial > 0) || !(Js.determinant() > 0))
      return false;
  }

  return acceptRoot(x, target, m, J);
}

bool CameraModel::undistortKannalaBrandt(const Eigen::Vector2d &target, Eigen::Vector2d &m,
                                         Eigen::Matrix2d *J) const {
  // The distorted radius is theta_d: solve theta_d(theta) = rd on [0, theta_max_), where theta_d
  // increases (a unique root), by Newton's method kept inside a shrinking bracket (bisection when
  // a step would leave it). rd >= theta_d(theta_max_): a ray at 90 degrees or more, or beyond the
  // fold of theta_d, which no normalised point represents.
  const double *k = kb_.data();
  const double rd = target.norm();
  if (!(rd < theta_d_max_))
    return false;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  if (rd > 0) {
    const double eps = std::numeric_limits<double>::epsilon();
    double lo = 0, hi = theta_max_;
    double t = std::min(rd, 0.5 * theta_max_);
    double prev_step = std::numeric_limits<double>::infinity();
    bool converged = false;
    for (int it = 0; it < 200; ++it) {
      double d = 0;
      const double f = kbThetaD(k, t, &d) - rd;
      if (f == 0) {
        converged = true;
        break;
      }
      (f < 0 ? lo : hi) = t;
      double next = t - f / d;
      // A Newton step may land on the bracket's end (a root at rounding level); otherwise bisect.
      const bool newton = d > 0 && next >= lo && next <= hi;
      if (!newton)
        next = 0.5 * (lo + hi);
      const double step = std::abs(next - t);
      t = next;
      // Converged when a Newton step is below 1e-15 relative to theta, or has reached rounding
      // level and stopped shrinking, or when the bracket is down to a few ulps.
      if ((newton && (step <= 1e-15 * t || (step < 1e3 * eps * t && step >= 0.5 * prev_step))) ||
          hi - lo <= 4 * eps * t) {
        converged = true;
        break;
      }
      prev_step = newton ? step : std::numeric_limits<double>::infinity();
    }
    if (!converged || !(t > 0 && t < theta_max_))
      return false;
    double d = 0;
    kbThetaD(k, t, &d);
    if (!(d > 0))
      return false;
    x = target * (std::tan(t) / rd);
  }
  if (!x.allFinite())
    return false;
  return acceptRoot(x, target, m, J);
}

bool CameraModel::acceptRoot(const Eigen::Vector2d &x, const Eigen::Vector2d &target, Eigen::Vector2d &m,
                             Eigen::Matrix2d *J) const {
  double xd = 0, yd = 0;
  Eigen::Matrix2d Jd;
  const bool ok = model_ == Distortion::KannalaBrandt ? distortKannalaBrandt(kb_.data(), x.x(), x.y(), xd, yd, &Jd)
                                                      : distortBrown(coeffs_.data(), x.x(), x.y(), xd, yd, &Jd);
  if (!ok)
    return false;
  // Final residual check (normalised units); far below 1e-9 px for any sensible focal length.
  if (std::hypot(xd - target.x(), yd - target.y()) > 1e-12 * std::max(1.0, target.norm()))
    return false;
  m = x;
  if (J) {
    Eigen::Matrix2d A = Jd;
    A.row(0) *= kx_;
    A.row(1) *= ky_;
    *J = A.inverse();
    if (!J->allFinite())
      return false;
  }
  return true;
}

void CameraModel::pixelToMeter(const vpImagePoint &ip, double &x, double &y) const {
  Eigen::Vector2d m;
  if (!undistort(Eigen::Vector2d(ip.get_u(), ip.get_v()), m))
    throw Error("camera: pixel (" + num(ip.get_u()) + ", " + num(ip.get_v()) +
                ") is outside the valid range of the distortion model (undistortion did not converge)");
  x = m.x();
  y = m.y();
}

bool CameraModel::undistortPixel(const Eigen::Vector2d &uv, Eigen::Vector2d &uv_undist) const {
  Eigen::Vector2d m;
  if (!undistort(uv, m))
    return false;
  uv_undist = Eigen::Vector2d(u0_ + kx_ * m.x(), v0_ + ky_ * m.y());
  return true;
}

} // namespace yawdepth
