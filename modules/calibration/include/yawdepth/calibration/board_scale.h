#pragma once
/*!
  \file board_scale.h
  \brief Whether the images agree with the board's size as given (`--pattern`'s square or tag
  size): the one check a wrong size typed for the board would otherwise pass.

  A board printed 0.944 times the size typed (a printer's "fit to page", 25 mm typed for 23.6 mm)
  fits every image as well as the right one: each board pose simply comes out 0.944 times as far.
  What tells the size is a metric motion between the images (an arm's kinematics, a robot's
  odometry): the calibrations that have one estimate a scale factor s of the board's points (the
  true points are s times the given ones) as one more free parameter, with its 1-sigma from the
  fit's covariance, and hand it to checkBoardScale(). The calibration's own result (eMc, the camera
  offset) is still the one estimated with the size given: the scale is reported, never applied.
*/
#include <string>
#include <yawdepth/features/pattern.h>

namespace yawdepth {

/*! \brief What the board scale check found. */
enum class BoardScaleStatus {
  NotEstimated, //!< the views cannot tell the board's size (no metric motion between them)
  Consistent,   //!< the size given agrees with the views (or the difference is too small to matter)
  Mismatch,     //!< the board looks larger or smaller than given: a warning (checkBoardScale()'s message)
  /*! the size given agrees, but the views could not have told a wrong one: min_sigmas sigmas exceed
      BoardScaleOptions::detectable (a warning: the result is only as good as the size typed) */
  Unconfirmed
};
/*! \brief "not_estimated", "consistent", "mismatch", "unconfirmed". */
const char *toString(BoardScaleStatus s);

/*! \brief When a scale differs enough from 1 to say so. */
struct BoardScaleOptions {
  /*! |s - 1| must exceed this many of its sigmas (a chance departure of 4 sigma: 6e-5). */
  double min_sigmas = 4.0;
  /*! ... and this relative size: a printer's own scale error (0.1 to 0.5 %) and the kinematics'
      calibration are not a wrong square size; 1 % is 0.24 mm on a 23.6 mm square. */
  double min_relative = 0.01;
  /*! A significant |s - 1| above this is refused (yawdepth::Error), not warned: a wrong unit or
      number (mm for m, the board's size for a square's), not a printer's scaling. */
  double max_relative = 0.25;
  /*! The relative size error the views must be able to see (at min_sigmas): 25 mm typed for 23.6 mm
      is 5.6 %. A consistent scale whose min_sigmas sigmas exceed it is Unconfirmed. */
  double detectable = 0.05;
  /*! \brief Throws yawdepth::Error unless 0 < min_relative < max_relative, min_sigmas > 0 and detectable > 0, all finite. */
  void validate() const;
};

/*! \brief The board's scale as the views see it. */
struct BoardScaleCheck {
  BoardScaleStatus status = BoardScaleStatus::NotEstimated; //!< what was found
  double scale = 1.0;  //!< s: the true board points are s times the given ones (1 when not estimated)
  double sigma = 0.0;  //!< its 1-sigma (0 when not estimated)
  /*! The views' spread (standard deviation) of the camera's distance to the board (m), which
      tells the scale from a camera sliding along its axis (hand-eye; 0 when not computed). */
  double distance_spread = 0.0;
  std::string message; //!< one line for a Mismatch or Unconfirmed (empty otherwise)
};

/*!
  \brief The check of an estimated scale `scale` +- `sigma` (see BoardScaleOptions): Consistent,
  Mismatch (its message names the figure, e.g. "the board looks 0.944 times the size given by
  --pattern chessboard:9x6:0.025 (+-0.003): check the square size") or Unconfirmed ("the views
  cannot confirm the board's size: ... a size off by less than 12 % would pass unseen").
  \throws yawdepth::Error with that message when the mismatch is gross (above max_relative), or when
  the scale or sigma is not finite and positive.
*/
BoardScaleCheck checkBoardScale(double scale, double sigma, const BoardLayout &board,
                                const BoardScaleOptions &options = BoardScaleOptions());

} // namespace yawdepth
