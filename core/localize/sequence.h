// Sequence queries: a lost robot sends its last few local maps with the
// relative poses its odometry measured between them. A look-alike room fits
// the newest map but rarely the maps before it where the robot really came
// from, so each hypothesis of the newest map is checked against the earlier
// maps at the poses the odometry predicts in the same stored map.
#pragma once

#include <functional>
#include <vector>

#include "core/localize/localizer.h"

namespace lmd {

struct SequenceStep {
  LocalQuery query;  // an earlier local map of the robot, prepared
  Pose2 in_newest;   // its own frame in the newest map's own frame (odometry)
  double travel_m = 0.0;  // distance the robot travelled from it to the newest (drift grows with it)
};

// Localises `newest` as Localize does, then scores each of the best
// `sequence_hypotheses` hits by the mean verification score over the whole
// sequence (the newest map's, and each earlier map's, matched against the
// same stored map near its predicted pose) and ranks and judges them by it.
// A hit's sequence_agreeing counts the earlier maps that fit it
// (score >= confidence.min_score); the verdict says it for the best.
Localization LocalizeSequence(const LocalQuery& newest, const std::vector<SequenceStep>& earlier,
                              const MapSource& source, const LocalizeOptions& options,
                              const std::function<bool(uint64_t)>& excluded = {},
                              const std::function<bool()>& stop = {}, bool with_changes = false);

}  // namespace lmd
