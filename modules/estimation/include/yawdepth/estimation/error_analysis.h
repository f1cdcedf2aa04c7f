#pragma once
/*!
  \file error_analysis.h
  \brief The paper's Section 4 error analysis, from the general first-order model, with a Monte
  Carlo check.

  Forward motion dz along the vision Z axis at yaw \f$\theta\f$ (dx = 0), so
  \f$ dX_c = -dz \sin\theta,\ dZ_c = dz\cos\theta \f$ and eq. (9):
  \f[ Z = dz\, \frac{(u_i - u_0)\cos\theta + k_x \sin\theta}{u_i - u_{i-1}} = dz \frac{N}{D} \f]
  The first-order relative error is the sum of the absolute terms (eqs. (10)-(14)):
  \f[ \frac{\delta Z}{Z} = \frac{\delta dz}{dz}
     + \frac{|k_x\cos\theta - (u_i-u_0)\sin\theta|\,\delta\theta}{|N|}
     + \frac{|\cos\theta|\,\delta u_i}{|N|}
     + \frac{|\delta u_i - \delta u_{i-1}|}{|D|} \f]
  which is eq. (12) at \f$\theta = 0\f$ and eq. (14) at \f$\theta = 90^\circ\f$.
*/
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace yawdepth {

/*! \brief One case of the error analysis (the paper's units are mm and degrees; these are m, rad, px). */
struct ErrorAnalysisCase {
  double yaw = 0.0;              //!< \f$\theta\f$ (rad): 0 front view, pi/2 side view.
  double depth = 0.5;            //!< Z (m).
  double u_offset = 10.0;        //!< \f$ u_i - u_0 \f$ (px).
  double dz = 0.02;              //!< Forward increment (m).
  double kx = 1700.0;            //!< Focal length (px).
  double delta_dz = 0.001;       //!< Odometry error \f$\delta dz\f$ (m).
  double delta_yaw = 0.05 * M_PI / 180.0; //!< Yaw error \f$\delta\theta\f$ (rad), 0.05 degree.
  double delta_u = 0.1;          //!< Pixel error \f$\delta u_i\f$ (px).
  double delta_du = 0.1;         //!< \f$ |\delta u_i - \delta u_{i-1}| \f$ (px).
  /*! \brief Throws yawdepth::Error unless every field is finite, depth, dz and kx positive, errors non-negative. */
  void validate() const;
};

/*! \brief The terms of the first-order relative depth error (all relative, dimensionless). */
struct DepthErrorTerms {
  double parallax_px = 0; //!< \f$ u_i - u_{i-1} \f$ implied by eq. (9) (px).
  double odometry = 0;    //!< \f$ \delta dz / dz \f$
  double yaw = 0;         //!< yaw term
  double pixel = 0;       //!< \f$ u_i \f$ term (numerator); zero at side view
  double parallax = 0;    //!< \f$ |\delta u_i - \delta u_{i-1}| / |u_i - u_{i-1}| \f$
  double total = 0;       //!< sum of the four: the paper's figure
};

/*! \brief First-order terms of eqs. (9)-(14) for a case. */
DepthErrorTerms firstOrderDepthError(const ErrorAnalysisCase &c);

/*!
  \brief Statistical first-order relative depth error (1 sigma): the same model with independent
  Gaussian errors, \f$ \sigma_{dz} = \delta dz,\ \sigma_\theta = \delta\theta \f$ and pixel noise
  \f$ \sigma_u = \delta u_i \f$ on each of \f$ u_i, u_{i-1} \f$, combined in quadrature with the
  correlation through \f$ u_i \f$ kept. This is what monteCarloDepthError() should reproduce.
*/
double firstOrderDepthSigma(const ErrorAnalysisCase &c);

/*! \brief Lateral error, eq. (17): \f$ \delta X_c / Z_c = \delta u_i / k_x + (u_i - u_0)/k_x \cdot \delta Z_c/Z_c \f$. */
double lateralRelativeError(double delta_u, double kx, double u_offset, double depth_relative_error);

/*! \brief Result of a Monte Carlo run on eq. (9). */
struct MonteCarloDepthError {
  double rms_relative = 0;    //!< RMS of (Z_est - Z)/Z.
  double median_abs_relative = 0; //!< Median of |Z_est - Z|/Z (robust to the heavy tails near the focus of expansion).
  double bias_relative = 0;   //!< Mean of (Z_est - Z)/Z.
  int samples = 0;            //!< Number of draws.
};

/*!
  \brief Monte Carlo of eq. (9) with the noise of firstOrderDepthSigma().
  \param c The case (geometry and noise).
  \param samples Number of draws (> 0). \param seed Random seed (results are reproducible).
*/
MonteCarloDepthError monteCarloDepthError(const ErrorAnalysisCase &c, int samples, std::uint64_t seed = 1);

/*! \brief A row of the paper's Section 4 table. */
struct PaperErrorRow {
  std::string view;       //!< "front", "side" or "lateral"
  ErrorAnalysisCase input; //!< the row's inputs
  double lateral_depth_error = 0; //!< for the lateral row: the dZ/Z it assumes (0.05)
};

/*! \brief The cases of the paper's Section 4 table (inputs only: every number is computed). */
std::vector<PaperErrorRow> paperErrorCases();

/*!
  \brief Format a term the way the paper prints it: four decimals, trailing zeros dropped
  (0.05, 0.1484, 0.0015), and below 5e-4 five significant digits in scientific form (5.1333e-6).
*/
std::string formatPaperTerm(double v);
/*! \brief A relative error as the paper prints totals: a percentage with two decimals ("45.84 %"). */
std::string formatPercent(double v);

} // namespace yawdepth
