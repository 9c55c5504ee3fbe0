#include "client/cli/result_mcap.h"

#include <chrono>
#include <cstdio>

#include "core/io/mcap_writer.h"
#include "core/render/result_mcap.h"
#include "proto/convert.h"

namespace lmd::cli {

int WriteResultMcap(const CommandContext& ctx, const std::string& collection, const v1::LocalMap& query,
                    const std::vector<v1::MapHit>& hits, const std::vector<std::vector<v1::ChangeMask>>& masks) {
  const std::string out = ctx.args.Get("mcap");
  const LocalMap query_map = FromProto(query);
  std::vector<LocalMap> stored;
  stored.reserve(hits.size());
  ResultScene scene;
  scene.query = &query_map;
  scene.stamp_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                       std::chrono::system_clock::now().time_since_epoch()).count();
  for (size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i].has_pose()) continue;  // bow gives no pose: nothing to place
    v1::GetMapRequest get;
    get.set_collection(collection);
    get.set_map_id(hits[i].map_id());
    v1::GetMapResponse response;
    const grpc::Status status = ctx.client.GetMap(get, &response);
    if (!status.ok()) return FailCall(status);
    stored.push_back(FromProto(response.map().map()));
    ResultSceneHit hit;
    hit.map_id = hits[i].map_id();
    hit.rank = hits[i].rank();
    hit.score = hits[i].score();
    hit.query_in_db = FromProto(hits[i].pose());
    if (i < masks.size()) {
      for (const v1::ChangeMask& mask : masks[i]) {
        std::vector<Point2> points;
        for (int k = 0; k < mask.x_size() && k < mask.y_size(); ++k) points.push_back({mask.x(k), mask.y(k)});
        hit.masks.push_back(std::move(points));
      }
    }
    scene.hits.push_back(std::move(hit));
  }
  for (size_t i = 0; i < scene.hits.size(); ++i) scene.hits[i].map = &stored[i];  // stored no longer grows
  const Status written = WriteBytesToFile(out, RenderResultMcap(scene));
  if (!written.ok()) return Fail(written.message());
  if (!ctx.json) std::printf("wrote %s (%zu hits with a pose)\n", out.c_str(), scene.hits.size());
  return 0;
}

}  // namespace lmd::cli
