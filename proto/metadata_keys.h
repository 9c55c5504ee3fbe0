// gRPC metadata keys of lmd's API beyond its messages, shared by lmdd and
// the client library.
#pragma once

namespace lmd {

// Request header naming the call's collection, so that a proxy can route the
// call to the lmdd holding it (deploy/: sharding) without parsing messages.
inline constexpr char kCollectionMetadata[] = "x-lmd-collection";

// Trailer of a StreamInsertMaps call that ended with an error: how many of
// the stream's maps, its first ones in order, are stored all the same (gRPC
// sends no response message with an error status).
inline constexpr char kStoredMapsMetadata[] = "lmd-stored-maps";

// Trailer of a call refused with RESOURCE_EXHAUSTED because lmdd's queue
// was full (value "1"): worth retrying later, unlike a limit's refusal.
inline constexpr char kBusyMetadata[] = "lmd-busy";

}  // namespace lmd
