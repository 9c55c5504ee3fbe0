// collections, stats and backup of lmdctl.
#include <cstdio>

#include "client/cli/commands.h"
#include "client/cli/output.h"

namespace lmd::cli {

int CollectionsCommand(const CommandContext& ctx) {
  v1::ListCollectionsResponse response;
  const grpc::Status status = ctx.client.ListCollections(&response);
  if (!status.ok()) return FailCall(status);
  for (const auto& info : response.collections()) {
    if (ctx.json) {
      std::printf("%s\n", ToJsonLine(info).c_str());
    } else {
      std::printf("%-24s maps=%-8llu points=%llu\n", info.name().c_str(),
                  static_cast<unsigned long long>(info.maps()), static_cast<unsigned long long>(info.points()));
    }
  }
  return 0;
}

int StatsCommand(const CommandContext& ctx) {
  v1::StatsRequest request;
  request.set_collection(ctx.args.Get("collection"));
  v1::StatsResponse response;
  const grpc::Status status = ctx.client.Stats(request, &response);
  if (!status.ok()) return FailCall(status);
  if (ctx.json) {
    std::printf("%s\n", ToJsonLine(response).c_str());
    return 0;
  }
  std::printf("lmdd %s, up %.1f s\n", response.version().c_str(), response.uptime_s());
  for (const auto& info : response.collections()) {
    std::printf("collection %-20s maps=%-8llu postings=%-10llu points=%llu\n", info.name().c_str(),
                static_cast<unsigned long long>(info.maps()), static_cast<unsigned long long>(info.postings()),
                static_cast<unsigned long long>(info.points()));
  }
  for (const auto& method : response.methods()) {
    std::printf("method %-16s calls=%-8llu errors=%-6llu p50=%.2f ms p95=%.2f ms p99=%.2f ms\n",
                method.method().c_str(), static_cast<unsigned long long>(method.calls()),
                static_cast<unsigned long long>(method.errors()), method.p50_ms(), method.p95_ms(),
                method.p99_ms());
  }
  return 0;
}

int BackupCommand(const CommandContext& ctx) {
  v1::BackupRequest request;
  request.set_directory(Required(ctx.args, "dir"));
  if (request.directory().empty()) return 2;
  v1::BackupResponse response;
  const grpc::Status status = ctx.client.Backup(request, &response);
  if (!status.ok()) return FailCall(status);
  if (ctx.json) {
    std::printf("%s\n", ToJsonLine(response).c_str());
  } else {
    std::printf("backup of %llu bytes written to %s (on the server)\n",
                static_cast<unsigned long long>(response.bytes()), response.directory().c_str());
  }
  return 0;
}

// `cluster --collection C --copies N`: how many copies the cluster keeps.
int SetReplication(const CommandContext& ctx) {
  v1::SetReplicationRequest request;
  request.set_collection(Required(ctx.args, "collection"));
  if (request.collection().empty()) return 2;
  Result<long> copies = GetPositive(ctx.args, "copies", 0, 9);
  if (!copies.ok()) return Fail(copies.status().message(), 2);
  request.set_replication_factor(static_cast<uint32_t>(*copies));
  v1::SetReplicationResponse response;
  const grpc::Status status = ctx.client.SetReplication(request, &response);
  if (!status.ok()) return FailCall(status);
  if (ctx.json) {
    std::printf("%s\n", ToJsonLine(response).c_str());
  } else {
    std::printf("collection %s: %u copies wanted (now %d); the controller adds or removes copies\n",
                request.collection().c_str(), request.replication_factor(), response.placement().copies_size());
  }
  return 0;
}

int ClusterCommand(const CommandContext& ctx) {
  if (ctx.args.Has("copies")) return SetReplication(ctx);
  v1::ClusterResponse response;
  const grpc::Status status = ctx.client.Cluster(&response);
  if (!status.ok()) return FailCall(status);
  if (ctx.json) {
    std::printf("%s\n", ToJsonLine(response).c_str());
    return 0;
  }
  if (!response.enabled()) {
    std::printf("not in a cluster: this lmdd runs alone (cluster_etcd is not set)\n");
    return 0;
  }
  std::printf("answered by %s; controller %s\n", response.node_id().c_str(), response.controller().c_str());
  for (const auto& node : response.nodes()) {
    std::printf("node %-16s %-22s%s%s\n", node.node_id().c_str(), node.address().c_str(),
                node.zone().empty() ? "" : " zone ", node.zone().c_str());
  }
  for (const auto& placement : response.placements()) {
    std::printf("collection %-20s epoch %llu, %u copies wanted\n", placement.collection().c_str(),
                static_cast<unsigned long long>(placement.epoch()), placement.copies_wanted());
    for (const auto& copy : placement.copies()) {
      const char* role = copy.primary() ? "primary" : copy.in_sync() ? "in sync" : "catching up";
      if (copy.reachable()) {
        std::printf("  %-16s %-12s seq %-8llu lag %llu\n", copy.node_id().c_str(), role,
                    static_cast<unsigned long long>(copy.seq()), static_cast<unsigned long long>(copy.lag()));
      } else {
        std::printf("  %-16s %-12s down\n", copy.node_id().c_str(), role);
      }
    }
  }
  return 0;
}

}  // namespace lmd::cli
