// How lmdd turns a local map into what it indexes: the viewpoint planner,
// the describer and the index options of the paper's methods, fixed for a
// store, and the default method's place features. The fingerprint of the
// paper's settings is saved in the store when it is created; a store made
// with other settings is refused (its descriptors would not be comparable),
// never rewritten. Place features carry their own version in each record;
// records of another version are computed again from the stored map when
// the store opens.
#pragma once

#include <optional>
#include <string>

#include "core/describe/describer.h"
#include "core/index/retrieve_options.h"
#include "core/localize/localizer.h"
#include "core/types.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd::server {

struct IndexingConfig {
  ViewpointOptions viewpoint;  // planner: the product default
  DescriberOptions describer = ProductDescriberOptions();  // paper setting #6, 13-bit words
  IndexOptions index;          // W = 5 m, L = 2
  // The default method (core/localize): its place features and map
  // preparation are computed at insert; the rest applies per query.
  LocalizeOptions localize;
  // false: maps are stored without the paper's descriptor and postings (an
  // empty one each), and the paper's methods are refused (ServerConfig::
  // paper_index).
  bool paper_index = true;
};

// The product's indexing, with or without inner words and the paper's index
// (ServerConfig::inner_words, paper_index).
IndexingConfig ProductIndexing(bool inner_words, bool paper_index = true);

// The planned frame and descriptor of `map` (in its own frame). `place`:
// the same map's PreparePlace, if computed already (its compass is reused).
Lmd DescribeForIndex(const LocalMap& map, const IndexingConfig& config, const PreparedPlace* place = nullptr);

// Everything lmdd computes from a map's content: the default method's
// preparation (scan-matching grids, place features) and the paper's
// descriptor. A query of the default method needs no descriptor: it is
// computed for maps stored (the paper's methods query them) and queries of
// the paper's methods only.
struct DescribedMap {
  std::optional<Lmd> lmd;
  PreparedPlace place;
};
// Both (the descriptor only `with_lmd` and config.paper_index) of `map` as the method sees it (MethodView).
DescribedMap DescribeMap(const LocalMap& map, const IndexingConfig& config, bool with_lmd);

// `map` as lmdd's method sees it: its points deduplicated on the local-map
// grid (0.1 m), as lmd builds its own maps. A client's raw, dense or repeated
// points then cost what one of lmd's maps does (200k copies of one point
// made a scan match run for minutes); lmd-built maps are unchanged.
LocalMap MethodView(LocalMap map);

// One line naming every setting that changes stored descriptors or postings.
std::string Fingerprint(const IndexingConfig& config);

}  // namespace lmd::server
