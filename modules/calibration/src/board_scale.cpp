/*!
  \file board_scale.cpp
  \brief The board scale check (yawdepth/calibration/board_scale.h).
*/
#include <yawdepth/calibration/board_scale.h>

#include "text.h"

#include <cmath>
#include <yawdepth/error.h>

namespace yawdepth {

const char *toString(BoardScaleStatus s)
{
  switch (s) {
  case BoardScaleStatus::Consistent:
    return "consistent";
  case BoardScaleStatus::Unconfirmed:
    return "unconfirmed";
  case BoardScaleStatus::Mismatch:
    return "mismatch";
  case BoardScaleStatus::NotEstimated:
    break;
  }
  return "not_estimated";
}

void BoardScaleOptions::validate() const
{
  if (!std::isfinite(min_sigmas) || !(min_sigmas > 0) || !std::isfinite(min_relative) || !(min_relative > 0) ||
      !std::isfinite(max_relative) || !(min_relative < max_relative) || !std::isfinite(detectable) ||
      !(detectable > 0))
    throw Error("board scale check: min_sigmas " + calibration_detail::num(min_sigmas) + ", min_relative " +
                calibration_detail::num(min_relative) + ", max_relative " + calibration_detail::num(max_relative) +
                " and detectable " + calibration_detail::num(detectable) +
                " must be finite with min_sigmas > 0, detectable > 0 and 0 < min_relative < max_relative");
}

BoardScaleCheck checkBoardScale(double scale, double sigma, const BoardLayout &board, const BoardScaleOptions &options)
{
  options.validate();
  if (!std::isfinite(scale) || !(scale > 0) || !std::isfinite(sigma) || !(sigma >= 0))
    throw Error("board scale check: the scale " + calibration_detail::num(scale) + " +- " +
                calibration_detail::num(sigma) + " is not finite and positive");
  BoardScaleCheck c;
  c.scale = scale;
  c.sigma = sigma;
  const double departure = std::abs(scale - 1.0);
  const bool significant = departure > options.min_sigmas * sigma && departure > options.min_relative;
  const bool tag = board.pattern.kind == PatternSpec::Kind::AprilTag;
  if (!significant) {
    c.status = BoardScaleStatus::Consistent;
    if (options.min_sigmas * sigma > options.detectable) {
      c.status = BoardScaleStatus::Unconfirmed;
      c.message = "the views cannot confirm the board's size: its scale is " + calibration_detail::fixed(scale, 3) +
                  " +- " + calibration_detail::fixed(sigma, 3) + " times the size given by --pattern " +
                  board.pattern.toString() + ", so a " + (tag ? "tag size" : "square size") + " off by less than " +
                  calibration_detail::fixed(100 * options.min_sigmas * sigma, 0) +
                  " % would pass unseen; the result is only as good as the size typed (views at more varied "
                  "distances to the board would tell)";
    }
    return c;
  }
  c.status = BoardScaleStatus::Mismatch;
  c.message = "the board looks " + calibration_detail::fixed(scale, 3) + " times the size given by --pattern " +
              board.pattern.toString() + " (+-" + calibration_detail::fixed(sigma, 3) + ", " +
              calibration_detail::fixed(departure / std::max(sigma, 1e-300), 0) + " sigma): check the " +
              (tag ? "tag size" : "square size") + " (the views say " +
              calibration_detail::fixed(1e3 * scale * (tag ? board.pattern.tag_size : board.pattern.square), 2) +
              " mm)";
  if (departure > options.max_relative)
    throw Error(c.message + "; refused: more than " + calibration_detail::fixed(100 * options.max_relative, 0) +
                " % off is a wrong unit or number, not a printer's scaling");
  return c;
}

} // namespace yawdepth
