// ingest, query, changes and render of lmdctl.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "client/cli/commands.h"
#include "client/cli/insert_maps.h"
#include "client/cli/output.h"
#include "client/cli/query_map.h"
#include "client/cli/result_mcap.h"
#include "core/align/icp.h"
#include "core/render/result_svg.h"
#include "core/util/progress_bar.h"
#include "proto/convert.h"

namespace lmd::cli {
namespace {

Result<v1::Method> MethodFromArgs(const Args& args) {
  const std::string name = args.Get("method", "default");
  if (name == "default") return v1::METHOD_DEFAULT;
  if (name == "lmd-cor") return v1::METHOD_LMD_COR;
  if (name == "lmd-cog") return v1::METHOD_LMD_COG;
  if (name == "bow") return v1::METHOD_BOW;
  return Status::InvalidArgument("--method must be default, lmd-cor, lmd-cog or bow, got '" + name + "'");
}

// --prior X,Y,THETA_DEG[,RADIUS_M] (with --prior-sigma DEG, --fall-back):
// the query map's own frame in the collection's frame.
Result<v1::Prior> PriorFromArgs(const Args& args) {
  const std::string text = args.Get("prior");
  const Result<std::vector<double>> parsed = ParseNumberList(text);
  if (!parsed.ok() || (parsed->size() != 3 && parsed->size() != 4)) {
    return Status::InvalidArgument("--prior must be X,Y,THETA[,RADIUS] (m, m, deg, m), got '" + text + "'");
  }
  const std::vector<double>& values = *parsed;
  Result<double> sigma = GetMetres(args, "prior-sigma", 15.0, 0.0, 180.0);  // degrees, same bounds check
  if (!sigma.ok()) return Status::InvalidArgument("--prior-sigma must be a heading uncertainty from 0 to 180 deg");
  v1::Prior prior;
  *prior.mutable_pose() = ToProto(Pose2{values[0], values[1], values[2] * M_PI / 180.0});
  prior.set_radius_m(values.size() == 4 ? values[3] : 2.0);
  prior.set_heading_sigma_rad(*sigma * M_PI / 180.0);
  prior.set_fall_back_to_global(args.Switch("fall-back"));
  return prior;
}

// Fills the collection, map, top_k, method, verification depth (--verify N),
// excluded ids (--exclude ID[,ID...]), prior (--prior) and sequence
// (--sequence K) of a Retrieve or DetectChanges request; 2 after printing a
// usage error, 1 after another error, else 0.
template <typename Request>
int FillQuery(const CommandContext& ctx, Request* request) {
  request->set_collection(Required(ctx.args, "collection"));
  if (request->collection().empty()) return 2;
  if (ctx.args.Has("prior") && ctx.args.Has("sequence")) return Fail("give --prior or --sequence, not both", 2);
  bool usage_error = false;
  Result<QueryInput> query = QueryFromArgs(ctx.args, &usage_error);
  if (!query.ok()) return Fail(query.status().message(), usage_error ? 2 : 1);
  *request->mutable_map() = ToProto(query->map);
  for (v1::SequenceMap& earlier : query->sequence) *request->add_sequence() = std::move(earlier);
  if (ctx.args.Has("prior")) {
    Result<v1::Prior> prior = PriorFromArgs(ctx.args);
    if (!prior.ok()) return Fail(prior.status().message(), 2);
    *request->mutable_prior() = *prior;
  }
  Result<long> top_k = GetPositive(ctx.args, "top-k", 10);
  if (!top_k.ok()) return Fail(top_k.status().message(), 2);
  request->set_top_k(static_cast<uint32_t>(*top_k));
  Result<v1::Method> method = MethodFromArgs(ctx.args);
  if (!method.ok()) return Fail(method.status().message(), 2);
  request->set_method(*method);
  Result<long> verify = GetPositive(ctx.args, "verify", 0);  // 0: the server's default
  if (!verify.ok()) return Fail(verify.status().message(), 2);
  request->set_verify_candidates(static_cast<uint32_t>(std::min<long>(*verify, UINT32_MAX)));
  const std::string exclude = ctx.args.Get("exclude");
  for (size_t begin = 0; begin < exclude.size();) {
    const size_t end = std::min(exclude.find(',', begin), exclude.size());
    if (end > begin) request->add_exclude_map_ids(exclude.substr(begin, end - begin));
    begin = end + 1;
  }
  return 0;
}

void PrintHit(const v1::MapHit& hit) {
  if (hit.verified()) {  // the default method: a verification score and a scan-matched pose
    std::printf("%3u  %-24s score=%.3f", hit.rank(), hit.map_id().c_str(), hit.score());
  } else {
    std::printf("%3u  %-24s K=%.4f  orientation=%3u deg  offset=(%.2f, %.2f) m", hit.rank(), hit.map_id().c_str(),
                hit.score(), hit.orientation_deg(), hit.offset_x(), hit.offset_y());
  }
  if (hit.has_pose()) {
    std::printf("  pose=(%.2f m, %.2f m, %.1f deg)", hit.pose().x(), hit.pose().y(), hit.pose().theta() * 180 / M_PI);
  }
  if (hit.has_collection_pose()) {
    const v1::Pose2& p = hit.collection_pose();
    std::printf("  site=(%.2f m, %.2f m, %.1f deg)", p.x(), p.y(), p.theta() * 180 / M_PI);
  }
  std::printf("%s\n", hit.verified() && hit.agrees_with_best() ? "  same place as the first" : "");
}

// The verdict line of a default-method answer.
void PrintLocalization(const v1::Localization& l, bool json) {
  if (json) {
    std::printf("%s\n", ToJsonLine(l).c_str());
    return;
  }
  std::printf("%s (confidence %.3f: best score %.3f, best rival %.3f, %u other hits agree)\n",
              l.localized() ? "localized: the first hit's pose can be acted on" : "not localized: no hit is sure",
              l.confidence(), l.best_score(), l.rival_score(), l.agreeing());
  if (l.fell_back_to_global()) {
    std::printf("the prior failed (no map near it matched): answered as a global query\n");
  } else if (l.prior_failed()) {
    std::printf("the prior failed: no map near it matched (--fall-back asks for a global query in the same call)\n");
  } else if (l.prior_used()) {
    std::printf("answered within the prior\n");
  }
  if (l.sequence_maps() > 0) {
    std::printf("%u of the sequence's %u earlier maps fit the first hit's pose\n", l.sequence_agreeing(),
                l.sequence_maps());
    if (l.sequence_by_newest()) std::printf("answered by the newest map alone, sure at the sequence's best place\n");
  }
  if (l.has_collection_pose()) {
    const v1::Pose2& p = l.collection_pose();
    std::printf("site pose (%.2f m, %.2f m, %.1f deg), through %s\n", p.x(), p.y(), p.theta() * 180 / M_PI,
                l.collection_pose_map_id().c_str());
  }
  if (l.has_pose_covariance()) {
    const PoseDeviations sd = PoseStandardDeviations(FromProto(l.pose_covariance()));
    std::printf("the first hit's pose is known to %.3f m (its least known direction) and %.2f deg (1 sigma)\n",
                sd.position_m, sd.heading_rad * 180 / M_PI);
  }
}

constexpr const char* kReducedDepthNote =
    "(lmdd was busy and answered at its reduced depth: fewer maps verified; --verify N asks for a depth)";

}  // namespace

int IngestCommand(const CommandContext& ctx) {
  const std::string collection = Required(ctx.args, "collection");
  if (collection.empty()) return 2;
  Result<std::string> input = OneSource(ctx.args, {"log", "bag"}, "the maps to ingest", /*numbered=*/false);
  if (!input.ok()) return Fail(input.status().message(), 2);
  if (Required(ctx.args, *input).empty()) return 2;
  const bool bag = *input == "bag";
  Result<LocalMapOptions> local_maps = LocalMapOptionsFromArgs(ctx.args);
  if (!local_maps.ok()) return Fail(local_maps.status().message(), 2);
  BagLogSummary summary;
  Result<std::vector<LocalMap>> maps =
      bag ? LocalMapsFromBag(ctx.args, *local_maps, &summary) : LocalMapsFromLog(ctx.args, *local_maps);
  if (!maps.ok()) return Fail(maps.status().message() + " (no map stored)");
  const std::string source = bag ? ctx.args.Get("bag") : ctx.args.Get("log");
  size_t evicted = 0;  // by the collection's cap (retain_maps_per_collection)
  std::vector<Pose2> anchors;  // --anchor: each map's first pose in the log's frame, as its pose hint
  if (ctx.args.Switch("anchor")) {
    for (const LocalMap& m : *maps) anchors.push_back(m.truth.global_frame);
  }
  // The log or bag is one robot's route: its maps' order tells lmdd which overlap.
  if (int code = InsertLocalMaps(ctx, collection, *maps, anchors, "ingest " + source, LogName(source), &evicted)) {
    return code;
  }
  if (bag) {
    if (ctx.json) {
      std::printf("%s\n", BagSummaryJsonLine(source, summary, maps->size()).c_str());
    } else {
      std::printf("%s: %s; scans %s (%zu read, %zu without a pose); poses: %s; laser: %s\n", source.c_str(),
                  summary.format.c_str(), summary.scan_topic.c_str(), summary.scans_read,
                  summary.scans_without_pose, summary.pose_source.c_str(), summary.laser_mounting.c_str());
    }
  }
  if (!ctx.json) std::printf("ingested %zu local maps into '%s'\n", maps->size(), collection.c_str());
  if (!ctx.json && evicted > 0) {
    std::printf("lmdd evicted the collection's %zu oldest maps to keep within its cap\n", evicted);
  }
  return 0;
}

int QueryCommand(const CommandContext& ctx) {
  v1::RetrieveRequest request;
  if (int code = FillQuery(ctx, &request)) return code;
  v1::RetrieveResponse response;
  const grpc::Status status = ctx.client.Retrieve(request, &response);
  if (!status.ok()) return FailCall(status);
  for (const auto& hit : response.hits()) {
    if (ctx.json) {
      std::printf("%s\n", ToJsonLine(hit).c_str());
    } else {
      PrintHit(hit);
    }
  }
  if (!ctx.json && response.hits_size() == 0) std::printf("no map of '%s' matches\n", request.collection().c_str());
  if (request.method() == v1::METHOD_DEFAULT) PrintLocalization(response.localization(), ctx.json);
  if (!ctx.json && response.reduced_depth()) std::printf("%s\n", kReducedDepthNote);
  if (ctx.args.Has("mcap")) {
    return WriteResultMcap(ctx, request.collection(), request.map(), {response.hits().begin(), response.hits().end()},
                           {});
  }
  return 0;
}

int ChangesCommand(const CommandContext& ctx) {
  v1::DetectChangesRequest request;
  if (int code = FillQuery(ctx, &request)) return code;
  v1::DetectChangesResponse response;
  const grpc::Status status = ctx.client.DetectChanges(request, &response);
  if (!status.ok()) return FailCall(status);
  for (const auto& hit : response.hits()) {
    if (ctx.json) {
      std::printf("%s\n", ToJsonLine(hit).c_str());
      continue;
    }
    PrintHit(hit.hit());
    for (const auto& mask : hit.masks()) {
      double x = 0, y = 0;
      for (int i = 0; i < mask.x_size(); ++i) {
        x += mask.x(i) / mask.x_size();
        y += mask.y(i) / mask.y_size();
      }
      if (mask.source() == v1::MASK_SOURCE_GEOMETRIC) {
        std::printf("       change %-3u at (%.2f, %.2f) m, %d points the stored map saw as free, evidence %.1f\n",
                    mask.rank(), x, y, mask.x_size(), mask.score());
      } else {
        std::printf("       change %-3u at (%.2f, %.2f) m, %d features, r=%.2f\n", mask.rank(), x, y,
                    mask.x_size(), mask.score());
      }
    }
  }
  if (request.method() == v1::METHOD_DEFAULT) PrintLocalization(response.localization(), ctx.json);
  if (!ctx.json && response.reduced_depth()) std::printf("%s\n", kReducedDepthNote);
  if (ctx.args.Has("mcap")) {
    std::vector<v1::MapHit> hits;
    std::vector<std::vector<v1::ChangeMask>> masks;
    for (const auto& hit : response.hits()) {
      hits.push_back(hit.hit());
      masks.emplace_back(hit.masks().begin(), hit.masks().end());
    }
    return WriteResultMcap(ctx, request.collection(), request.map(), hits, masks);
  }
  return 0;
}

int RenderCommand(const CommandContext& ctx) {
  const std::string out = Required(ctx.args, "out");
  if (out.empty()) return 2;
  v1::DetectChangesRequest request;
  if (int code = FillQuery(ctx, &request)) return code;
  request.set_top_k(1);
  v1::DetectChangesResponse response;
  grpc::Status status = ctx.client.DetectChanges(request, &response);
  if (!status.ok()) return FailCall(status);
  if (response.hits_size() == 0) return Fail("no map of '" + request.collection() + "' matches: nothing to render");
  if (!response.hits(0).hit().has_pose()) {
    return Fail("the top hit of method " + ctx.args.Get("method", "default") +
                " has no pose to render (the default method gives one)");
  }
  const v1::ChangeHit& top = response.hits(0);
  v1::GetMapRequest get;
  get.set_collection(request.collection());
  get.set_map_id(top.hit().map_id());
  v1::GetMapResponse stored;
  status = ctx.client.GetMap(get, &stored);
  if (!status.ok()) return FailCall(status);

  const LocalMap query = FromProto(request.map());
  const LocalMap db = FromProto(stored.map().map());
  ResultPicture picture;
  picture.query = &query;
  picture.db = &db;
  picture.query_in_db = FromProto(top.hit().pose());
  for (const auto& mask : top.masks()) {
    std::vector<Point2> points;
    for (int i = 0; i < mask.x_size(); ++i) points.push_back({mask.x(i), mask.y(i)});
    picture.masks.push_back(std::move(points));
  }
  picture.title = "query against " + request.collection() + "/" + top.hit().map_id();
  std::ofstream file(out);
  file << RenderResultSvg(picture);
  if (!file) return Fail("cannot write " + out);
  std::printf("wrote %s (top hit %s, %d change masks)\n", out.c_str(), top.hit().map_id().c_str(), top.masks_size());
  return 0;
}

}  // namespace lmd::cli
