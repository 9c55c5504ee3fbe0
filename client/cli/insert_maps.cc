#include "client/cli/insert_maps.h"

#include <cstdio>

#include "client/cli/output.h"
#include "proto/convert.h"

namespace lmd::cli {

int InsertLocalMaps(const CommandContext& ctx, const std::string& collection, const std::vector<LocalMap>& maps,
                    const std::vector<Pose2>& pose_hints, const std::string& label, const std::string& robot,
                    size_t* evicted) {
  ProgressBar progress = TerminalProgress(label, maps.size());
  for (size_t i = 0; i < maps.size(); ++i) {
    v1::InsertMapsRequest request;
    v1::InsertMapRequest* insert = request.add_maps();
    insert->mutable_metadata()->set_collection(collection);
    insert->mutable_metadata()->set_map_id(maps[i].id);
    insert->mutable_metadata()->set_robot_id(ctx.args.Get("robot", robot));
    insert->mutable_metadata()->set_sequence(i + 1);  // 0 would mean "no sequence"
    if (i < pose_hints.size()) *insert->mutable_metadata()->mutable_pose_hint() = ToProto(pose_hints[i]);
    *insert->mutable_map() = ToProto(maps[i]);
    v1::InsertMapsResponse response;
    const grpc::Status status = ctx.client.InsertMaps(request, &response);
    if (!status.ok()) {
      progress.Abandon();
      return FailCall(grpc::Status(status.error_code(), status.error_message() + " (" + std::to_string(i) + " of " +
                                                            std::to_string(maps.size()) +
                                                            " maps were stored before it)"));
    }
    if (evicted != nullptr) *evicted += static_cast<size_t>(response.evicted_size());
    if (ctx.json) {  // as soon as lmdd acknowledged it
      std::printf("{\"id\":\"%s\",\"collection\":\"%s\",\"points\":%u}\n", response.maps(0).map_id().c_str(),
                  collection.c_str(), response.maps(0).point_count());
      for (const auto& meta : response.evicted()) std::printf("%s\n", EvictedJsonLine(meta).c_str());
      std::fflush(stdout);
    }
    progress.Add();
  }
  progress.Done();
  return 0;
}

}  // namespace lmd::cli
