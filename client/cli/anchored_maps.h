// A collection's anchored maps, read whole through ListMaps and GetMap (for
// pictures and exports of the site map).
#pragma once

#include <string>
#include <vector>

#include <grpcpp/support/status.h>

#include "client/lmd_client.h"
#include "core/types.h"

namespace lmd::cli {

struct AnchoredMaps {
  std::vector<LocalMap> maps;  // own frame
  std::vector<Pose2> anchors;  // each map's own frame in the collection's
  size_t derived = 0;          // of them anchored by lmdd (a sure localisation), not by a pose hint
};

// Every map of `collection` with an anchor; with `with_derived` false, only
// those anchored by a pose hint. The first failed call's status.
grpc::Status ReadAnchoredMaps(const client::LmdClient& client, const std::string& collection, bool with_derived,
                              AnchoredMaps* out);

}  // namespace lmd::cli
