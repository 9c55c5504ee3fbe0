// How lmdctl stores a run of local maps (ingest of a log or bag, import-map):
// one InsertMaps call per map, so that each is acknowledged as it is stored,
// a progress bar (on a terminal), and --json lines.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "client/cli/commands.h"
#include "core/types.h"

namespace lmd::cli {

// Inserts `maps` into `collection` in order (sequence = index + 1; robot
// from --robot, else `robot`; pose_hints[i], if given, anchors map i).
// With --json prints
// {"id", "collection", "points"} per acknowledged map (and evicted lines).
// Returns 0, or 1 after printing the failure with how many maps were
// stored before it. *evicted (if not null) counts maps lmdd evicted.
int InsertLocalMaps(const CommandContext& ctx, const std::string& collection, const std::vector<LocalMap>& maps,
                    const std::vector<Pose2>& pose_hints, const std::string& label, const std::string& robot,
                    size_t* evicted);

}  // namespace lmd::cli
