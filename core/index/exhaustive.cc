#include "core/index/exhaustive.h"

#include "core/index/top_hits.h"

namespace lmd {

Result<std::vector<MapHit>> RetrieveExhaustive(const Index& index, const Lmd& query,
                                               const RetrieveOptions& options) {
  Status st = ValidateRetrieveOptions(options);
  if (!st.ok()) return st;
  auto features = ToPoseFeatures(query, index.options());
  if (!features.ok()) return features.status();
  const PreparedLmdQuery q = PrepareLmdQuery(
      WithoutStopWords(std::move(features).value(), index.StopWords(options.max_word_share)), index.options(), options);
  const double quantum = index.options().pose_quantum_m;
  TopHits top(options.top_k);
  KernelScratch scratch;
  index.ForEachMap([&](uint64_t id, const std::vector<PoseFeature>& db) {
    MapHit hit;
    hit.map_id = id;
    if (options.method == Method::kBow) {
      hit.score = ScoreBowMap(q, db.data(), db.size());
    } else {
      const KernelScore s = ScoreLmdMap(q, db.data(), db.size(), &scratch);
      hit.score = s.score;
      hit.orientation = s.orientation;
      hit.offset = {s.offset_x * quantum, s.offset_y * quantum};
    }
    top.Offer(hit);
  });
  return top.Take();
}

}  // namespace lmd
