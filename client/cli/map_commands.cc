// insert, get, delete and list (maps) of lmdctl.
#include <cstdio>

#include "client/cli/commands.h"
#include "client/cli/output.h"
#include "client/cli/query_map.h"
#include "client/points_file.h"

namespace lmd::cli {

int InsertCommand(const CommandContext& ctx) {
  const std::string collection = Required(ctx.args, "collection");
  const std::string file = Required(ctx.args, "file");
  if (collection.empty() || file.empty()) return 2;
  Result<LocalMapOptions> options = LocalMapOptionsFromArgs(ctx.args);  // --heading-drift
  if (!options.ok()) return Fail(options.status().message(), 2);
  Result<v1::LocalMap> map = client::ReadPointsFile(file);
  if (!map.ok()) return Fail(map.status().message());
  if (ctx.args.Has("heading-drift")) map->set_heading_drift_rad_per_m(options->heading_drift_rad_per_m);

  v1::InsertMapsRequest request;
  v1::InsertMapRequest* insert = request.add_maps();
  insert->mutable_metadata()->set_collection(collection);
  insert->mutable_metadata()->set_map_id(ctx.args.Get("id"));
  insert->mutable_metadata()->set_robot_id(ctx.args.Get("robot"));
  *insert->mutable_map() = std::move(map).value();
  v1::InsertMapsResponse response;
  const grpc::Status status = ctx.client.InsertMaps(request, &response);
  if (!status.ok()) return FailCall(status);
  for (const auto& meta : response.maps()) {
    if (ctx.json) {
      std::printf("%s\n", MapJsonLine(meta).c_str());
    } else {
      std::printf("inserted %s/%s (%u points)\n", meta.collection().c_str(), meta.map_id().c_str(),
                  meta.point_count());
    }
  }
  for (const auto& meta : response.evicted()) {
    if (ctx.json) {
      std::printf("%s\n", EvictedJsonLine(meta).c_str());
    } else {
      std::printf("evicted %s/%s (the collection's oldest map, over its cap)\n", meta.collection().c_str(),
                  meta.map_id().c_str());
    }
  }
  return 0;
}

int GetCommand(const CommandContext& ctx) {
  v1::GetMapRequest request;
  request.set_collection(Required(ctx.args, "collection"));
  request.set_map_id(Required(ctx.args, "id"));
  if (request.collection().empty() || request.map_id().empty()) return 2;
  v1::GetMapResponse response;
  const grpc::Status status = ctx.client.GetMap(request, &response);
  if (!status.ok()) return FailCall(status);
  if (ctx.args.Has("out")) {
    Status written = client::WritePointsFile(ctx.args.Get("out"), response.map().map());
    if (!written.ok()) return Fail(written.message());
  }
  const v1::MapMetadata& meta = response.map().metadata();
  if (ctx.json) {
    std::printf("%s\n", ToJsonLine(response.map()).c_str());
  } else {
    std::printf("%s/%s robot=%s sequence=%llu points=%u trajectory=%d scans=%d\n", meta.collection().c_str(),
                meta.map_id().c_str(), meta.robot_id().empty() ? "-" : meta.robot_id().c_str(),
                static_cast<unsigned long long>(meta.sequence()), meta.point_count(),
                response.map().map().trajectory_size(), response.map().map().scans_size());
  }
  return 0;
}

int DeleteCommand(const CommandContext& ctx) {
  v1::DeleteMapRequest request;
  request.set_collection(Required(ctx.args, "collection"));
  request.set_map_id(Required(ctx.args, "id"));
  if (request.collection().empty() || request.map_id().empty()) return 2;
  const grpc::Status status = ctx.client.DeleteMap(request);
  if (!status.ok()) return FailCall(status);
  if (ctx.json) {
    std::printf("{\"collection\":\"%s\",\"map_id\":\"%s\",\"deleted\":true}\n", request.collection().c_str(),
                request.map_id().c_str());
  } else {
    std::printf("deleted %s/%s\n", request.collection().c_str(), request.map_id().c_str());
  }
  return 0;
}

int ListMapsCommand(const CommandContext& ctx) {
  v1::ListMapsRequest request;
  request.set_collection(Required(ctx.args, "collection"));
  if (request.collection().empty()) return 2;
  do {
    v1::ListMapsResponse response;
    const grpc::Status status = ctx.client.ListMaps(request, &response);
    if (!status.ok()) return FailCall(status);
    for (const auto& meta : response.maps()) {
      if (ctx.json) {
        std::printf("%s\n", MapJsonLine(meta).c_str());
      } else {
        std::printf("%-24s robot=%-10s sequence=%-6llu points=%u\n", meta.map_id().c_str(),
                    meta.robot_id().empty() ? "-" : meta.robot_id().c_str(),
                    static_cast<unsigned long long>(meta.sequence()), meta.point_count());
      }
    }
    request.set_page_token(response.next_page_token());
  } while (!request.page_token().empty());
  return 0;
}

}  // namespace lmd::cli
