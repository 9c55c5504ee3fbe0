// How lmdctl prints: human-readable lines by default, or with --json one JSON
// object per line (protobuf's JSON mapping, proto field names).
#pragma once

#include <string>

#include <google/protobuf/message.h>

#include "core/io/bag_log.h"
#include "core/util/progress_bar.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd::cli {

// One message as a single-line JSON object.
std::string ToJsonLine(const google::protobuf::Message& message);

// A stored map's metadata as a JSON line that leads with its id, {"id": ...,
// then the metadata's fields}, as `ingest --json` lines do, so that the lines
// of `ingest`, `insert` and `maps` can be matched by id.
std::string MapJsonLine(const v1::MapMetadata& metadata);

// A map lmdd deleted to keep its collection within its cap, as a JSON line
// {"evicted": id, "collection": ...}, so that scripts tracking ids drop it.
std::string EvictedJsonLine(const v1::MapMetadata& metadata);

// What `ingest --bag` read, as the JSON line it ends with: {"bag": path,
// "format", "scan_topic", "scans_read", "scans_without_pose", "pose_source",
// "laser_mounting", "maps"}.
std::string BagSummaryJsonLine(const std::string& bag, const BagLogSummary& summary, size_t maps);

// A progress bar on stderr drawn only when stderr is a terminal: off one (a
// script, a CI log) lmdctl's stderr carries nothing but its error line.
ProgressBar TerminalProgress(std::string label, size_t total);

}  // namespace lmd::cli
