// --mcap OUT.mcap of lmdctl query / changes: the answer as an MCAP file for
// Foxglove, Lichtblick or `ros2 bag play` (core/render/result_mcap.h).
#pragma once

#include <string>
#include <vector>

#include "client/cli/commands.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd::cli {

// Fetches the stored map of every hit with a metric pose and writes the
// scene to --mcap; `masks` holds each hit's change masks (empty for query).
// Returns 0, or 1 after printing the failure (a GetMap call, the file).
int WriteResultMcap(const CommandContext& ctx, const std::string& collection, const v1::LocalMap& query,
                    const std::vector<v1::MapHit>& hits, const std::vector<std::vector<v1::ChangeMask>>& masks);

}  // namespace lmd::cli
