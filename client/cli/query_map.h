// Where lmdctl's query commands take their local map from: a points file
// (--file), or one local map built from a CARMEN log (--log FILE --map K, the
// K-th map of 5 m every 1 m; --length / --step change those).
#pragma once

#include <string>
#include <vector>

#include "client/cli/args.h"
#include "core/status.h"
#include "core/types.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd::cli {

// The local maps of the log named by --log (with --length, --step), map ids
// "<log file name without .log/.gz>-<k>". Errors name the file and line.
Result<std::vector<LocalMap>> LocalMapsFromLog(const Args& args);

// The query map named by --file or by --log and --map. InvalidArgument if
// neither or both are given, or --map is out of range.
Result<LocalMap> QueryMapFromArgs(const Args& args);

}  // namespace lmd::cli
