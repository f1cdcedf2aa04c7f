#pragma once
/*!
  \file track_inputs.h
  \brief The rules every method's input obeys, checked in one place, and the tracks seen by
  motion-log row: what every batch method (paper, exact, fused, window, refine, the Cramér–Rao bound)
  reads.

  yawdepth::estimatePoints() (yawdepth/pipeline/pipeline.h) calls validateInputs() once and hands
  the view to the method it runs; each method's public function that takes the raw vectors calls it
  first; what runs on a TracksByFrame assumes the rules below hold (a TracksByFrame exists only when
  they do).

  The rules (each broken one is a yawdepth::Error, one line naming the feature and frame at fault):
  - the motion log's frames strictly increase, and its rows are all planar or all 6-DoF;
  - every observed frame is in the motion log;
  - a track's observations are in strictly increasing frame order;
  - no feature id is in two tracks.
*/
#include <cstddef>
#include <utility>
#include <vector>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*!
  \brief The tracks and the motion log, validated, with each observation's motion-log row and the
  observations at each row. A view: the vectors it was made from must outlive it, unchanged.
*/
class TracksByFrame {
public:
  /*! \brief (track index, observation index) of one observation. */
  using Entry = std::pair<std::size_t, std::size_t>;

  /*! \brief The motion log (rows by strictly increasing frame). */
  const std::vector<MotionSample> &motion() const { return *motion_; }
  /*! \brief The tracks, in the order given. */
  const std::vector<Track> &tracks() const { return *tracks_; }
  /*! \brief The motion-log row of observation `k` of track `t`. */
  std::size_t row(std::size_t t, std::size_t k) const { return rows_[t][k]; }
  /*! \brief The observations at motion-log row `r`, by track index. */
  const std::vector<Entry> &observedAt(std::size_t r) const { return at_row_[r]; }
  /*!
    \brief The same log with `fewer`: these tracks, same order, each keeping some of its observations
    (e.g. without those no method can use). Throws yawdepth::Error when they are not such a subset.
  */
  TracksByFrame withFewer(const std::vector<Track> &fewer) const;
  TracksByFrame withFewer(std::vector<Track> &&) const = delete; //!< A view of a temporary would dangle.
  /*!
    \brief The same tracks with another reading of the same log: `motion` has this log's frames (e.g.
    its yaw readings negated). Throws yawdepth::Error when its frames or row kinds differ.
  */
  TracksByFrame withMotion(const std::vector<MotionSample> &motion) const;
  TracksByFrame withMotion(std::vector<MotionSample> &&) const = delete; //!< A view of a temporary would dangle.

private:
  friend TracksByFrame validateInputs(const std::vector<MotionSample> &motion, const std::vector<Track> &tracks);
  TracksByFrame() = default;
  /* The index of tracks that obey the rules (validateInputs() checked them). */
  static TracksByFrame index(const std::vector<MotionSample> &motion, const std::vector<Track> &tracks);
  const std::vector<MotionSample> *motion_ = nullptr;
  const std::vector<Track> *tracks_ = nullptr;
  std::vector<std::vector<std::size_t>> rows_; // per track and observation
  std::vector<std::vector<Entry>> at_row_;     // per motion-log row
};

/*!
  \brief Check the rules of the file's description and index the observations by row.
  \throws yawdepth::Error naming the first rule broken (the feature, the frame).
*/
TracksByFrame validateInputs(const std::vector<MotionSample> &motion, const std::vector<Track> &tracks);
/* A view of a temporary would dangle: refused at compile time. */
TracksByFrame validateInputs(std::vector<MotionSample> &&, const std::vector<Track> &) = delete;
TracksByFrame validateInputs(const std::vector<MotionSample> &, std::vector<Track> &&) = delete;
TracksByFrame validateInputs(std::vector<MotionSample> &&, std::vector<Track> &&) = delete;

} // namespace yawdepth
