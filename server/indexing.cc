#include "server/indexing.h"

#include <optional>
#include <sstream>

#include "core/localmap/local_map_builder.h"

namespace lmd::server {

Lmd DescribeForIndex(const LocalMap& map, const IndexingConfig& config, const PreparedPlace* place) {
  // One compass for both, when they use the same one (it is a tenth of an
  // insert's CPU).
  std::optional<double> heading;
  if (place != nullptr && config.viewpoint.orientation == config.localize.match.map.orientation) {
    heading = place->map->heading;
  }
  return Describe(map, PlanViewpoint(map, config.viewpoint, heading), config.describer);
}

DescribedMap DescribeMap(const LocalMap& map, const IndexingConfig& config, bool with_lmd) {
  const LocalMap view = MethodView(map);
  DescribedMap described;
  described.place = PreparePlace(view, config.localize);
  if (with_lmd && config.paper_index) described.lmd = DescribeForIndex(view, config, &described.place);
  return described;
}

LocalMap MethodView(LocalMap map) {
  map.points = DeduplicatePoints(map.points, LocalMapOptions().dedup_cell_m);
  return map;
}

IndexingConfig ProductIndexing(bool inner_words, bool paper_index) {
  IndexingConfig config;
  if (inner_words) config.describer = WithInnerWords(config.describer);
  config.paper_index = paper_index;
  return config;
}

std::string Fingerprint(const IndexingConfig& config) {
  // Without the paper's index no stored record depends on the settings below.
  if (!config.paper_index) return "paper_index=0";
  const DescriberOptions& d = config.describer;
  std::ostringstream out;
  out << "planner=" << PlannerName(config.viewpoint.planner) << " projection_version=" << kProjectionVersion
      << " projection_seed=" << d.projection_seed << " R=" << d.setting.radius_m << " A=" << d.setting.sectors
      << " shells=" << d.shells << " bits=" << d.word_bits << " raster=" << d.raster_m
      << " interest_cell=" << d.interest_cell_m << " max_features=" << d.max_features;
  // Without inner words the line is the one of stores made before them
  // (codec version 1), so that those stores still open.
  const bool inner = d.inner_radius_m > 0;
  if (inner) out << " inner=" << d.inner_radius_m;
  out << " codec=" << (inner ? 2 : 1) << " pose_quantum=" << config.index.pose_quantum_m
      << " W=" << config.index.pyramid_cell_m << " L=" << config.index.pyramid_levels;
  return out.str();
}

}  // namespace lmd::server
