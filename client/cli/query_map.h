// Where lmdctl's query commands take their local map from: a points file
// (--file), or one local map built from a CARMEN log (--log FILE --map K, the
// K-th map of 5 m every 1 m; --length / --step change those) or from a
// recorded bag (--bag PATH --map K, with --scan-topic, --odom-topic, --frame,
// --scan-matching, --allow-nan, --salvage as core/io/bag_log.h describes).
#pragma once

#include <string>
#include <vector>

#include "client/cli/args.h"
#include "core/io/bag_log.h"
#include "core/localmap/local_map_builder.h"
#include "core/status.h"
#include "core/types.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd::cli {

// "intel" for ".../intel.log.gz" (also .mcap, .bag, .db3): map ids' prefix
// and the robot an ingested log or bag is (one route).
std::string LogName(const std::string& path);

// The one input of a command among --file POINTS, --log FILE and --bag
// PATH, those in `allowed` (e.g. {"log", "bag"}), each followed by " --map K"
// if `numbered`: its key, or InvalidArgument "give <what> as --log FILE or
// as --bag PATH" when none, several or another is given (a second source is
// never silently ignored).
Result<std::string> OneSource(const Args& args, const std::vector<std::string>& allowed, const std::string& what,
                              bool numbered);

// --length and --step (m; 5 and 1 by default): how local maps are built
// from a log or bag. InvalidArgument naming the option and its range: a
// usage error, to be reported before any file is read.
Result<LocalMapOptions> LocalMapOptionsFromArgs(const Args& args);

// The local maps of the log named by --log, built with `options`, map ids
// "<log file name without .log/.gz>-<k>". Errors name the file and line.
Result<std::vector<LocalMap>> LocalMapsFromLog(const Args& args, LocalMapOptions options);

// The local maps of the bag named by --bag (a file or a rosbag2 directory),
// built with `options`, map ids "<bag name without extension>-<k>";
// *summary (if not null) says which topics and pose source were used.
// Errors name the bag and message.
Result<std::vector<LocalMap>> LocalMapsFromBag(const Args& args, LocalMapOptions options, BagLogSummary* summary);

// A query map and, for a sequence query, the robot's earlier maps.
struct QueryInput {
  LocalMap map;
  std::vector<v1::SequenceMap> sequence;  // each with its own frame in the query map's
};

// The query map named by --file or by --log / --bag and --map; with
// --sequence K (a log or bag only) also the K maps before it, --sequence-step
// maps apart (5, i.e. 5 m at the default --step), their relative poses from
// the log's or bag's poses. InvalidArgument if none or several sources are
// given, or --map or the sequence is out of range: then *usage_error (if not
// null) is set true; it stays false when the file itself is at fault.
Result<QueryInput> QueryFromArgs(const Args& args, bool* usage_error = nullptr);

}  // namespace lmd::cli
