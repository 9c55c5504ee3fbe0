// lmdctl demo: the main job on the built-in simulated world. Robot 1 drives
// the demo world and its local maps are stored in lmdd; robot 2 then drives
// another route through the same building, objects appear in each of its new
// local maps (the change simulator), and lmdd localises them and reports the
// changes. Every figure printed is checked against the simulator's truth.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "client/cli/commands.h"
#include "core/align/relative_pose.h"
#include "core/eval/ground_truth.h"
#include "core/render/result_svg.h"
#include "core/sim/change.h"
#include "core/sim/simulate.h"
#include "core/util/progress_bar.h"
#include "proto/convert.h"

namespace lmd::cli {
namespace {

constexpr int kBatch = 25;          // maps per InsertMaps call
constexpr int kQueries = 8;         // robot 2's maps sent as queries
constexpr double kChangeHitM = 0.5; // a mask this close to a changed point finds it

v1::InsertMapRequest ToInsert(const std::string& collection, const LocalMap& map, uint64_t sequence) {
  v1::InsertMapRequest insert;
  insert.mutable_metadata()->set_collection(collection);
  insert.mutable_metadata()->set_map_id(map.id);
  insert.mutable_metadata()->set_robot_id("robot-1");
  insert.mutable_metadata()->set_sequence(sequence);
  *insert.mutable_map() = ToProto(map);
  return insert;
}

// Pose of `query`'s own frame in `db`'s own frame, from the simulator's truth.
Pose2 TruePose(const LocalMap& query, const LocalMap& db) {
  return Compose(Inverse(db.truth.global_frame), query.truth.global_frame);
}

double NearestDistance(const Point2& p, const std::vector<Point2>& points) {
  double best = INFINITY;
  for (const Point2& q : points) best = std::min(best, std::hypot(p.x - q.x, p.y - q.y));
  return best;
}

int StoreRobotOne(const CommandContext& ctx, const std::string& collection, const std::vector<LocalMap>& maps) {
  ProgressBar progress("demo: storing robot 1's maps", maps.size());
  for (size_t first = 0; first < maps.size(); first += kBatch) {
    v1::InsertMapsRequest request;
    for (size_t i = first; i < std::min(maps.size(), first + kBatch); ++i) {
      *request.add_maps() = ToInsert(collection, maps[i], i);
    }
    v1::InsertMapsResponse response;
    const grpc::Status status = ctx.client.InsertMaps(request, &response);
    if (!status.ok()) {
      progress.Abandon();
      return FailCall(status);
    }
    progress.Add(response.maps_size());
  }
  progress.Done();
  return 0;
}

}  // namespace

int DemoCommand(const CommandContext& ctx) {
  const std::string collection = ctx.args.Get("collection", "demo");
  const std::string out_dir = ctx.args.Get("out", ".");
  std::fprintf(stderr, "demo: simulating robot 1 in the demo world\n");
  const SimulationOptions robot1 = DefaultDemoOptions();
  const std::vector<LocalMap> stored = SimulateLocalMaps(robot1);
  if (stored.empty()) return Fail("the simulator produced no local maps");
  if (int failed = StoreRobotOne(ctx, collection, stored)) return failed;
  std::map<std::string, const LocalMap*> by_id;
  for (const LocalMap& map : stored) by_id[map.id] = &map;

  // Robot 2: another route through the same building, with new objects.
  SimulationOptions robot2 = robot1;
  robot2.route.seed = robot1.route.seed + 1;
  robot2.route.length_m = 120.0;
  robot2.local_map.id_prefix = "robot2";
  std::vector<LocalMap> queries = SimulateLocalMaps(robot2);
  std::mt19937_64 rng(7);
  std::printf("stored %zu local maps of robot 1 in collection '%s'; robot 2 sends %d new maps with new objects\n\n",
              stored.size(), collection.c_str(), kQueries);

  int right_place = 0, change_found = 0, asked = 0, revisits = 0;
  bool pictured = false;
  for (int n = 0; n < kQueries && !queries.empty(); ++n) {
    LocalMap& query = queries[(n * queries.size()) / kQueries];
    Result<SimulatedChange> change = ApplySimulatedChange(query, rng);
    if (!change.ok()) continue;
    ++asked;
    v1::DetectChangesRequest request;
    request.set_collection(collection);
    *request.mutable_map() = ToProto(query);
    request.set_top_k(5);
    // Robot 2 does not know where it is in robot 1's maps: it asks for a
    // deeper verification than a tracking robot's 10 (4 vs 3 of 8 localised).
    request.set_verify_candidates(40);
    v1::DetectChangesResponse response;
    const grpc::Status status = ctx.client.DetectChanges(request, &response);
    if (!status.ok()) return FailCall(status);
    if (response.hits_size() == 0) {
      std::printf("%-10s no hit\n", query.id.c_str());
      continue;
    }
    // Did robot 1 see this place at all? (the best any stored map can do)
    double best_overlap = 0.0;
    for (const LocalMap& map : stored) best_overlap = std::max(best_overlap, PlaceOverlap(query, map));
    const bool seen = best_overlap >= 0.5;
    revisits += seen;
    const v1::ChangeHit& top = response.hits(0);
    const LocalMap* db = by_id.count(top.hit().map_id()) ? by_id[top.hit().map_id()] : nullptr;
    const double overlap = db ? PlaceOverlap(query, *db) : 0.0;
    const bool place_ok = overlap >= 0.5;
    right_place += place_ok;
    std::printf("%-10s top hit %-10s score=%.3f  %s (%.0f %% of its points on the hit; best stored map %.0f %%)",
                query.id.c_str(), top.hit().map_id().c_str(), top.hit().score(),
                place_ok ? "right place" : seen ? "WRONG place" : "new place", 100 * overlap, 100 * best_overlap);
    if (db && top.hit().has_pose()) {
      const Pose2 truth = TruePose(query, *db);
      const Pose2 got = FromProto(top.hit().pose());
      std::printf(", pose error %.2f m %.1f deg", std::hypot(got.x - truth.x, got.y - truth.y),
                  std::fabs(std::remainder(got.theta - truth.theta, 2 * M_PI)) * 180 / M_PI);
    }
    // The top-ranked mask over the whole response (rank 1), and its hit.
    const v1::ChangeMask* first_mask = nullptr;
    const v1::ChangeHit* first_mask_hit = nullptr;
    int masks = 0;
    for (const auto& hit : response.hits()) {
      masks += hit.masks_size();
      for (const auto& mask : hit.masks()) {
        if (mask.rank() == 1) first_mask = &mask, first_mask_hit = &hit;
      }
    }
    // The mask counts only against a map that shows the query's place.
    const LocalMap* mask_db = first_mask_hit && by_id.count(first_mask_hit->hit().map_id())
                                  ? by_id[first_mask_hit->hit().map_id()]
                                  : nullptr;
    const bool mask_place_ok = mask_db && PlaceOverlap(query, *mask_db) >= 0.5;
    double mask_distance = INFINITY;
    if (first_mask) {
      for (int i = 0; i < first_mask->x_size(); ++i) {
        mask_distance = std::min(mask_distance, NearestDistance({first_mask->x(i), first_mask->y(i)},
                                                                change->changed_points));
      }
    }
    const bool found = mask_place_ok && mask_distance <= kChangeHitM;
    change_found += found;
    std::printf("\n           %d change masks; top mask %.2f m from the new objects: %s\n", masks, mask_distance,
                found ? "change found" : "change missed");

    if (!pictured && db && place_ok && top.hit().has_pose()) {  // the first right localisation
      ResultPicture picture;
      picture.query = &query;
      picture.db = db;
      picture.query_in_db = FromProto(top.hit().pose());
      for (const auto& mask : top.masks()) {
        std::vector<Point2> points;
        for (int i = 0; i < mask.x_size(); ++i) points.push_back({mask.x(i), mask.y(i)});
        picture.masks.push_back(points);
      }
      picture.true_change = change->region_corners;
      picture.title = "query " + query.id + " against stored map " + db->id;
      const std::string path = out_dir + "/result.svg";
      std::ofstream(path) << RenderResultSvg(picture);
      std::printf("           picture: %s\n", path.c_str());
      pictured = true;
    }
  }
  if (!pictured) std::printf("\nno picture: no top hit showed the query's place\n");
  std::printf("\nsummary: %d/%d queries localised at the right place by the top hit (%d of them show a place "
              "robot 1 had mapped); true change in the top mask for %d/%d\n",
              right_place, asked, revisits, change_found, asked);
  return 0;
}

}  // namespace lmd::cli
