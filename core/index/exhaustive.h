// Exhaustive scorer: the reference for the inverted file. Scores every map
// stored in an Index with the same kernel (pyramid_kernel.h), without reading
// any posting list, and ranks them the same way (score descending, then map
// id ascending; maps scoring 0 are not returned).
#pragma once

#include <vector>

#include "core/index/index.h"

namespace lmd {

// Same contract as Index::Retrieve: top options.top_k hits, or
// InvalidArgument for bad options or a bad query feature.
Result<std::vector<MapHit>> RetrieveExhaustive(const Index& index, const Lmd& query,
                                               const RetrieveOptions& options = {});

}  // namespace lmd
