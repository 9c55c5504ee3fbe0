// What a robot's software does with the client library: after building each
// new local map, ask lmdd where it is and what changed, then store the map.
//
//   lmd-robot-example --server 127.0.0.1:50051 --collection demo [--token T]
//
// The robot here is simulated (the demo world); a real one would fill the
// LocalMap from its own SLAM front end.
#include <cmath>
#include <cstdio>
#include <string>

#include "client/lmd_client.h"
#include "core/sim/simulate.h"
#include "proto/convert.h"

int main(int argc, char** argv) {
  lmd::client::ClientOptions options;
  std::string collection = "demo";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--server") options.target = argv[i + 1];
    else if (flag == "--collection") collection = argv[i + 1];
    else if (flag == "--token") options.token = argv[i + 1];
  }
  options.deadline = std::chrono::seconds(5);
  auto client = lmd::client::LmdClient::Create(options);
  if (!client.ok()) {
    std::fprintf(stderr, "robot: %s\n", client.status().message().c_str());
    return 1;
  }

  lmd::SimulationOptions drive = lmd::DefaultDemoOptions();
  drive.route.seed = 42;
  drive.route.length_m = 20.0;
  drive.local_map.id_prefix = "robot42";
  bool lost = true;  // until a verified hit places the robot
  for (const lmd::LocalMap& map : lmd::SimulateLocalMaps(drive)) {
    lmd::v1::DetectChangesRequest query;
    query.set_collection(collection);
    *query.mutable_map() = lmd::ToProto(map);
    query.set_top_k(3);
    // A lost robot asks lmdd to verify more of the index's hits (slower,
    // finds its place more often); a tracking one takes the server's default.
    query.set_verify_candidates(lost ? 40 : 0);
    lmd::v1::DetectChangesResponse answer;
    grpc::Status status = (*client)->DetectChanges(query, &answer);
    if (status.error_code() == grpc::StatusCode::NOT_FOUND) {
      std::printf("%s: collection '%s' is new, nothing to localise against\n", map.id.c_str(), collection.c_str());
    } else if (!status.ok()) {
      std::fprintf(stderr, "robot: DetectChanges failed: %s\n", status.error_message().c_str());
      return 1;
    } else {
      lost = answer.hits_size() == 0 || !answer.hits(0).hit().verified();
      if (!lost) {
        const auto& hit = answer.hits(0).hit();
        std::printf("%s: like stored map %s (score %.3f), my frame at (%.2f, %.2f) %.1f deg in its frame, %d changes\n",
                    map.id.c_str(), hit.map_id().c_str(), hit.score(), hit.pose().x(), hit.pose().y(),
                    hit.pose().theta() * 180 / M_PI, answer.hits(0).masks_size());
      }
    }

    lmd::v1::InsertMapsRequest insert;
    lmd::v1::InsertMapRequest* entry = insert.add_maps();
    entry->mutable_metadata()->set_collection(collection);
    entry->mutable_metadata()->set_map_id(map.id);  // explicit id: a retried insert replaces, never duplicates
    entry->mutable_metadata()->set_robot_id("robot42");
    *entry->mutable_map() = lmd::ToProto(map);
    lmd::v1::InsertMapsResponse stored;
    status = (*client)->InsertMaps(insert, &stored);
    if (!status.ok()) {
      std::fprintf(stderr, "robot: InsertMaps failed: %s\n", status.error_message().c_str());
      return 1;
    }
  }
  return 0;
}
