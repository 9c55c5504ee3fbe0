// Sequence queries: a lost robot sends its last few local maps with the
// relative poses its odometry measured between them. A look-alike room fits
// the newest map but rarely the maps before it where the robot really came
// from, so each hypothesis of the newest map is checked against the earlier
// maps at the poses the odometry predicts in the same stored map.
#pragma once

#include <functional>
#include <vector>

#include "core/localize/localizer.h"
#include "core/localize/prior.h"

namespace lmd {

struct SequenceStep {
  LocalQuery query;  // an earlier local map of the robot, prepared
  Pose2 in_newest;   // its own frame in the newest map's own frame (odometry)
  double travel_m = 0.0;  // distance the robot travelled from it to the newest (drift grows with it)
};

// Each map of the sequence localised where `newest_pose` (the newest map's
// own frame in the collection's frame) puts it: LocalizeNear, the window
// grown by the odometry's drift over the map's travel. A hypothesis of
// LocalizeSequence is scored by this (and the hits it has in hand); lmd-eval
// sequence-misses asks it at the truth.
struct SequenceCheck {
  std::vector<Prior> windows;       // per map (0: the newest, k: earlier[k - 1]): where it was looked for
  std::vector<LocalizedHit> best;   // ... and its best hit there (db null: none)
  size_t maps_matched = 0;
};
SequenceCheck CheckSequenceAt(const LocalQuery& newest, const std::vector<SequenceStep>& earlier,
                              const MapSource& source, const LocalizeOptions& options, const Pose2& newest_pose,
                              const std::function<bool(uint64_t)>& excluded = {},
                              const std::function<bool()>& stop = {});

// In an anchored collection: every map of the sequence is localised (first
// stage and verification) and proposes poses for the newest through the
// odometry; for the `sequence_hypotheses` best, each map of the sequence is
// localised where the pose puts it (CheckSequenceAt) and the hypothesis
// scores the sequence's mean. A look-alike that fools the newest map rarely
// fools the maps before it. The hits are the newest map's at each
// hypothesis, ranked by the mean of the maps' fits as single hits are ranked
// (RankFit: closeness_weight of each share replaced by its closeness) and
// judged by the mean of their scores; sequence_agreeing counts the earlier
// maps that fit (score >= confidence.min_score). Without anchored maps the
// newest map is judged alone (verdict.sequence_agreeing 0).
Localization LocalizeSequence(const LocalQuery& newest, const std::vector<SequenceStep>& earlier,
                              const MapSource& source, const LocalizeOptions& options,
                              const std::function<bool(uint64_t)>& excluded = {},
                              const std::function<bool()>& stop = {}, bool with_changes = false);

}  // namespace lmd
