// Checks of incoming requests, before anything reaches the store or the
// method. Each failure says what is wrong and where ("map 2 ('m7'): point 15
// has a NaN x"), so a robot's engineer can fix the sender.
#pragma once

#include <string>

#include "core/status.h"
#include "core/util/quoted.h"  // Quoted, for the messages of validation and its callers
#include "lmd/v1/lmd.pb.h"
#include "server/config.h"

namespace lmd::server {

// 1 to 64 characters from [A-Za-z0-9._-], not only dots. InvalidArgument otherwise.
Status ValidateCollectionName(const std::string& name);

// 1 to 128 characters from [A-Za-z0-9._:-]; empty allowed when allow_empty
// (the server then assigns one). InvalidArgument otherwise.
Status ValidateMapId(const std::string& map_id, bool allow_empty);

// A local map: at least one point, x and y of equal length, every coordinate
// finite and within max_abs_coordinate_m, counts within the config's limits,
// a bounding box within max_map_extent_m, scans with a positive angle step
// and a max range up to that extent. `where` prefixes messages.
Status ValidateLocalMap(const v1::LocalMap& map, const ServerConfig& config, const std::string& where);

// Metadata and map of one map to insert; `index` is its place in the batch.
Status ValidateInsert(const v1::InsertMapRequest& request, const ServerConfig& config, size_t index);

// ListMaps' page_token: empty, or a map id (the next_page_token of the
// page before). InvalidArgument naming page_token otherwise.
Status ValidatePageToken(const std::string& page_token);

// An insert's request id: empty, or 1 to 64 printable ASCII characters
// without spaces.
Status ValidateRequestId(const std::string& request_id);

// A query's prior (if set) and sequence: not both; a prior's pose finite
// within the coordinate limit, a radius in (0, 100] m, a heading sigma >= 0;
// at most max_sequence_maps earlier maps, each a valid local map with its
// pose relative to the query (in_query) given and finite and a travel >= 0.
Status ValidatePriorAndSequence(bool has_prior, const v1::Prior& prior,
                                const google::protobuf::RepeatedPtrField<v1::SequenceMap>& sequence,
                                const ServerConfig& config);

}  // namespace lmd::server
