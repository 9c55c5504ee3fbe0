// Auditing a log's ground truth with lmdd's own matcher (lmd-eval
// truth-audit): does the log's pose of one map relative to another agree
// with where the matcher puts it, and do the maps of one place agree on
// moving a map off its log pose? Reads the log's poses; no method may.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "core/localize/localizer.h"

namespace lmd {

// `query` posed in `db` by lmdd's matcher and refinement (as a served hit is
// posed), started 0.25 m and 2 deg off `log_pose` (the log's pose of the
// query's own frame in db's), so that it finds the pose itself, and searching
// +-window_m (0: the matcher's own window). Empty
// when the match explains too little of the query to be a fix (below
// confidence.min_score).
std::optional<Pose2> MatchNearLogPose(const LocalQuery& query, const PreparedMap& db, const Pose2& log_pose,
                                      const LocalizeOptions& options, double window_m = 0.0);

// A map of one place, with the log's pose of the query in it.
struct PlaceMap {
  const PreparedMap* map = nullptr;
  Pose2 log_pose;  // query own frame in the map's own frame, by the log
};

struct PlaceMove {
  Pose2 move;            // the correction to the query's log pose, in its own frame (median of the matches)
  size_t agreeing = 0;   // matches within 0.1 m and 0.5 deg of it
  size_t matched = 0;    // maps that fit the query
};

// Each of `place` matched with the query within +-3 m of the log's pose;
// where at least three agree, how they move the query off its log pose
// (nothing otherwise). A move beyond the tolerance a pose may have says the
// query's log pose is wrong (or its local map distorted): the maps of its
// place, from other passes, agree on another pose.
std::optional<PlaceMove> MoveByItsPlace(const LocalQuery& query, const std::vector<PlaceMap>& place,
                                        const LocalizeOptions& options);

}  // namespace lmd
