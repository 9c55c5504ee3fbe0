// site and anchor of lmdctl: a collection's anchored maps as one site map,
// and anchors set anew when a better estimate of where maps lie arrives
// (after a SLAM loop closure, say).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "client/cli/anchored_maps.h"
#include "client/cli/commands.h"
#include "client/cli/output.h"
#include "core/render/site_svg.h"
#include "proto/convert.h"

namespace lmd::cli {
namespace {

// A re-anchoring batch stays well within lmdd's default message limit (64
// MiB) and batch limit (1000 maps); each batch is one atomic write.
constexpr size_t kAnchorBatchMaps = 256;
constexpr size_t kAnchorBatchBytes = 16u << 20;

struct NewAnchor {
  std::string id;
  Pose2 pose;  // the map's own frame in the collection's
  std::string where;  // "--pose" or "FILE:LINE", for messages
};

// "X,Y,THETA" (m, m, deg).
Result<Pose2> ParsePose(const std::string& text) {
  const Result<std::vector<double>> v = ParseNumberList(text);
  if (!v.ok() || v->size() != 3) return Status::InvalidArgument("not X,Y,THETA (m, m, deg): '" + text + "'");
  return Pose2{(*v)[0], (*v)[1], (*v)[2] * M_PI / 180.0};
}

// "ID X Y THETA" lines (m, m, deg; # starts a comment), each map once.
Result<std::vector<NewAnchor>> AnchorsFromFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) return Status::IoError("cannot read " + path);
  std::vector<NewAnchor> anchors;
  std::map<std::string, std::string> first_seen;
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    line = line.substr(0, line.find('#'));
    std::istringstream words(line);
    std::string id, x, y, theta, extra;
    if (!(words >> id)) continue;  // blank or comment
    const std::string where = path + ":" + std::to_string(number);
    const Result<Pose2> pose = (words >> x >> y >> theta) && !(words >> extra)
                                   ? ParsePose(x + "," + y + "," + theta)
                                   : Result<Pose2>(Status::InvalidArgument("not four words"));
    if (!pose.ok()) return Status::InvalidArgument(where + ": expected 'ID X Y THETA' (m, m, deg)");
    const auto [seen, fresh] = first_seen.emplace(id, where);
    if (!fresh) return Status::InvalidArgument(where + ": map " + id + " is anchored already at " + seen->second);
    anchors.push_back({id, *pose, where});
  }
  if (anchors.empty()) return Status::InvalidArgument(path + ": no 'ID X Y THETA' line");
  return anchors;
}

// Writes `batch` (the stored maps with their new pose hints) in one call.
// 0, or 1 after printing the failure with how many maps were re-anchored before.
int WriteBatch(const CommandContext& ctx, const v1::InsertMapsRequest& batch, size_t written_before) {
  v1::InsertMapsResponse response;
  const grpc::Status status = ctx.client.InsertMaps(batch, &response);
  if (!status.ok()) {
    return FailCall(grpc::Status(status.error_code(), status.error_message() + " (" + std::to_string(written_before) +
                                                          " maps were re-anchored before it)"));
  }
  if (ctx.json) {  // each map as stored now, its anchor among its metadata
    for (const v1::MapMetadata& stored : response.maps()) std::printf("%s\n", MapJsonLine(stored).c_str());
  }
  return 0;
}

}  // namespace

int SiteCommand(const CommandContext& ctx) {
  const std::string collection = Required(ctx.args, "collection");
  const std::string out = collection.empty() ? "" : Required(ctx.args, "out");
  if (collection.empty() || out.empty()) return 2;
  AnchoredMaps site;
  const grpc::Status read = ReadAnchoredMaps(ctx.client, collection, /*with_derived=*/true, &site);
  if (!read.ok()) return FailCall(read);
  if (site.maps.empty()) {
    return Fail("collection '" + collection + "' has no anchored maps (maps stored with a pose hint, or " +
                "localised surely by lmdd against anchored ones)");
  }
  SitePicture picture;
  for (size_t i = 0; i < site.maps.size(); ++i) picture.maps.push_back({&site.maps[i], site.anchors[i]});
  picture.title = "site map of " + collection + ": " + std::to_string(site.maps.size()) + " anchored maps";
  std::ofstream file(out);
  file << RenderSiteSvg(picture);
  if (!file) return Fail("cannot write " + out);
  if (ctx.json) {
    std::printf("{\"svg\":\"%s\",\"maps\":%zu,\"derived\":%zu}\n", out.c_str(), site.maps.size(), site.derived);
  } else {
    std::printf("wrote %s (%zu anchored maps, %zu of them anchored by lmdd)\n", out.c_str(), site.maps.size(),
                site.derived);
  }
  return 0;
}

int AnchorCommand(const CommandContext& ctx) {
  const std::string collection = Required(ctx.args, "collection");
  if (collection.empty()) return 2;
  const bool from_file = ctx.args.Has("file");
  if (from_file == (ctx.args.Has("id") || ctx.args.Has("pose"))) {
    return Fail("give --id ID --pose X,Y,THETA or --file ANCHORS (one of the two)", 2);
  }
  if (!from_file && !(ctx.args.Has("id") && ctx.args.Has("pose"))) return Fail("--id and --pose go together", 2);
  std::vector<NewAnchor> anchors;
  if (from_file) {
    Result<std::vector<NewAnchor>> read = AnchorsFromFile(ctx.args.Get("file"));
    if (!read.ok()) return Fail(read.status().message());
    anchors = std::move(*read);
  } else {
    const Result<Pose2> pose = ParsePose(ctx.args.Get("pose"));
    if (!pose.ok()) return Fail("--pose must be X,Y,THETA (m, m, deg), got '" + ctx.args.Get("pose") + "'", 2);
    anchors.push_back({ctx.args.Get("id"), *pose, "--pose"});
  }
  // Every map read before anything is written: an unknown id changes nothing.
  std::vector<v1::InsertMapRequest> writes;
  for (const NewAnchor& a : anchors) {
    v1::GetMapRequest get;
    get.set_collection(collection);
    get.set_map_id(a.id);
    v1::GetMapResponse stored;
    const grpc::Status status = ctx.client.GetMap(get, &stored);
    if (!status.ok()) {
      return FailCall(
          grpc::Status(status.error_code(), status.error_message() + " (" + a.where + "; nothing re-anchored)"));
    }
    v1::InsertMapRequest& write = writes.emplace_back();
    *write.mutable_metadata() = stored.map().metadata();
    write.mutable_metadata()->clear_anchor();  // output only: lmdd sets it from the pose hint
    write.mutable_metadata()->clear_point_count();
    *write.mutable_metadata()->mutable_pose_hint() = ToProto(a.pose);
    *write.mutable_map() = std::move(*stored.mutable_map()->mutable_map());
  }
  v1::InsertMapsRequest batch;
  size_t written = 0, bytes = 0;
  for (v1::InsertMapRequest& write : writes) {
    const size_t size = write.ByteSizeLong();
    const bool full = batch.maps_size() >= static_cast<int>(kAnchorBatchMaps) || bytes + size > kAnchorBatchBytes;
    if (batch.maps_size() > 0 && full) {
      if (int code = WriteBatch(ctx, batch, written)) return code;
      written += static_cast<size_t>(batch.maps_size());
      batch.clear_maps();
      bytes = 0;
    }
    bytes += size;
    *batch.add_maps() = std::move(write);
  }
  if (int code = WriteBatch(ctx, batch, written)) return code;
  written += static_cast<size_t>(batch.maps_size());
  if (!ctx.json) std::printf("re-anchored %zu maps of '%s'\n", written, collection.c_str());
  return 0;
}

}  // namespace lmd::cli
