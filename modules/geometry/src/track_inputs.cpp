#include <yawdepth/geometry/track_inputs.h>

#include <limits>
#include <string>
#include <unordered_set>
#include <yawdepth/error.h>

namespace yawdepth {

TracksByFrame TracksByFrame::index(const std::vector<MotionSample> &motion, const std::vector<Track> &tracks)
{
  TracksByFrame view;
  view.motion_ = &motion;
  view.tracks_ = &tracks;
  view.rows_.resize(tracks.size());
  view.at_row_.resize(motion.size());
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    view.rows_[t].reserve(tracks[t].observations.size());
    for (std::size_t k = 0; k < tracks[t].observations.size(); ++k) {
      const auto row = static_cast<std::size_t>(rowOfFrame(motion, tracks[t].observations[k].frame));
      view.rows_[t].push_back(row);
      view.at_row_[row].emplace_back(t, k);
    }
  }
  return view;
}

TracksByFrame validateInputs(const std::vector<MotionSample> &motion, const std::vector<Track> &tracks)
{
  for (std::size_t i = 1; i < motion.size(); ++i) {
    if (!(motion[i].frame > motion[i - 1].frame))
      throw Error("motion log: frame " + std::to_string(motion[i].frame) + " after frame " +
                  std::to_string(motion[i - 1].frame) + ": frames must be strictly increasing");
    if (motion[i].six_dof != motion[0].six_dof)
      throw Error("motion log: frame " + std::to_string(motion[i].frame) + " is " +
                  (motion[i].six_dof ? "6-DoF" : "planar") + " after " + (motion[0].six_dof ? "6-DoF" : "planar") +
                  " rows: a log must be all planar or all 6-DoF rows");
  }
  std::unordered_set<long> ids;
  for (const Track &track : tracks) {
    if (!ids.insert(track.id).second)
      throw Error("feature " + std::to_string(track.id) + " is in two tracks");
    long last = std::numeric_limits<long>::min();
    for (const Observation &ob : track.observations) {
      if (rowOfFrame(motion, ob.frame) < 0)
        throw Error("feature " + std::to_string(track.id) + " is observed in frame " + std::to_string(ob.frame) +
                    ", which the motion log does not have");
      if (!(ob.frame > last))
        throw Error("feature " + std::to_string(track.id) + ": frame " + std::to_string(ob.frame) + " after frame " +
                    std::to_string(last) + ": observations must be in strictly increasing frame order");
      last = ob.frame;
    }
  }
  return TracksByFrame::index(motion, tracks);
}

TracksByFrame TracksByFrame::withFewer(const std::vector<Track> &fewer) const
{
  const std::vector<Track> &all = *tracks_;
  bool subset = fewer.size() == all.size();
  for (std::size_t t = 0; subset && t < fewer.size(); ++t) {
    const auto &kept = fewer[t].observations, &had = all[t].observations;
    subset = fewer[t].id == all[t].id && kept.size() <= had.size();
    std::size_t k = 0;
    for (const Observation &ob : kept) { // a subsequence of the frames it had
      while (k < had.size() && had[k].frame != ob.frame)
        ++k;
      subset = subset && k < had.size();
      ++k;
    }
  }
  if (!subset)
    throw Error("tracks by frame: the fewer tracks are not a subset of the tracks validated");
  return index(*motion_, fewer);
}

TracksByFrame TracksByFrame::withMotion(const std::vector<MotionSample> &motion) const
{
  bool same = motion.size() == motion_->size();
  for (std::size_t i = 0; same && i < motion.size(); ++i)
    same = motion[i].frame == (*motion_)[i].frame && motion[i].six_dof == (*motion_)[i].six_dof;
  if (!same)
    throw Error("tracks by frame: the other motion log does not have the same frames");
  TracksByFrame view = *this;
  view.motion_ = &motion;
  return view;
}

} // namespace yawdepth
