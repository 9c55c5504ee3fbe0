// lmdctl demo: the fleet case on the built-in simulated world. Robot 1 maps
// the building: its local maps are stored anchored in the site frame (its own
// SLAM poses). Robot 2 then drives another route through it and sends a map
// every 5 m, with new objects in each. It starts lost and relocalises with
// sequence queries (the map and the ones it sent before, up to four, with
// its odometry between them); once lmdd is sure, it tracks, each query
// carrying a prior from its last fix and its drifting odometry, with a global
// answer asked for in the same call should the prior fail; after an answer
// lmdd was not sure of it is lost again. Every figure printed is
// checked against the simulator's truth, never assumed.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>

#include "client/cli/commands.h"
#include "client/cli/output.h"
#include "core/eval/ground_truth.h"
#include "core/localmap/pose_ops.h"
#include "core/render/result_svg.h"
#include "core/render/site_svg.h"
#include "core/sim/change.h"
#include "core/sim/odometry_drift.h"
#include "core/sim/simulate.h"
#include "proto/convert.h"

namespace lmd::cli {
namespace {

constexpr int kBatch = 25;            // maps per InsertMaps call
constexpr size_t kSendStep = 5;       // robot 2 sends every 5th map (1 m each)
constexpr size_t kMaxEarlier = 4;     // earlier maps in a sequence query, at most
constexpr double kChangeHitM = 0.5;   // a mask this close to a changed point finds it
// Robot 2's odometry: off by up to 2 % of the distance, and its heading by
// up to 0.5 deg per metre (OdometryDrift's defaults).
const OdometryDrift kDrift;

v1::InsertMapRequest ToInsert(const std::string& collection, const LocalMap& map, uint64_t sequence) {
  v1::InsertMapRequest insert;
  insert.mutable_metadata()->set_collection(collection);
  insert.mutable_metadata()->set_map_id(map.id);
  insert.mutable_metadata()->set_robot_id("robot-1");
  insert.mutable_metadata()->set_sequence(sequence);
  *insert.mutable_metadata()->mutable_pose_hint() = ToProto(map.truth.global_frame);
  *insert.mutable_map() = ToProto(map);
  return insert;
}

int StoreRobotOne(const CommandContext& ctx, const std::string& collection, const std::vector<LocalMap>& maps) {
  ProgressBar progress = TerminalProgress("demo: storing robot 1's maps", maps.size());
  for (size_t first = 0; first < maps.size(); first += kBatch) {
    v1::InsertMapsRequest request;
    for (size_t i = first; i < std::min(maps.size(), first + kBatch); ++i) {
      *request.add_maps() = ToInsert(collection, maps[i], i + 1);
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

double PoseErrorM(const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double PoseErrorDeg(const Pose2& a, const Pose2& b) {
  return std::abs(std::remainder(a.theta - b.theta, 2 * M_PI)) * 180 / M_PI;
}

double NearestDistance(const Point2& p, const std::vector<Point2>& points) {
  double best = INFINITY;
  for (const Point2& q : points) best = std::min(best, std::hypot(p.x - q.x, p.y - q.y));
  return best;
}

Point2 Centroid(const v1::ChangeMask& mask) {
  Point2 c{0, 0};
  for (int i = 0; i < mask.x_size(); ++i) c.x += mask.x(i) / mask.x_size(), c.y += mask.y(i) / mask.y_size();
  return c;
}

// The response's first-ranked change mask and the hit it was found against.
std::pair<const v1::ChangeMask*, const v1::ChangeHit*> FirstMask(const v1::DetectChangesResponse& response) {
  for (const auto& hit : response.hits()) {
    for (const auto& mask : hit.masks()) {
      if (mask.rank() == 1) return {&mask, &hit};
    }
  }
  return {nullptr, nullptr};
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
  std::vector<LocalMap> route = SimulateLocalMaps(robot2);
  std::vector<size_t> sends;  // the maps robot 2 sends, by their index on its route
  for (size_t i = 2 * kSendStep; i < route.size(); i += kSendStep) sends.push_back(i);
  if (sends.empty()) return Fail("the simulator gave robot 2 too short a route");
  std::printf("stored %zu local maps of robot 1, anchored in the site frame, in collection '%s'; robot 2 starts "
              "lost and sends %zu maps with new objects, one every %zu m, tracking with priors from its odometry "
              "(off by 2 %% of the distance and 0.5 deg per metre) once it is sure\n\n",
              stored.size(), collection.c_str(), sends.size(), kSendStep);

  std::mt19937_64 rng(7);
  SitePicture site;
  for (const LocalMap& map : stored) site.maps.push_back({&map, map.truth.global_frame});
  for (const LocalMap& map : route) site.route.push_back({map.truth.global_frame.x, map.truth.global_frame.y});
  site.title = "robot 2 on the site map of robot 1 (collection " + collection + ")";

  bool lost = true;
  Pose2 fix;               // robot 2's last sure pose in the site frame
  const LocalMap* fixed_at = nullptr;  // ... and the map it was of
  int right = 0, sure = 0, sure_wrong = 0, change_found = 0, asked = 0, revisits = 0;
  // Why the others missed: no hit, a place robot 1 never mapped, or a wrong
  // pose lmdd was not sure of (of those, how many were turned by 45 deg or
  // more: the simulated building's corridors and rooms repeat by 90 deg).
  int no_hit = 0, new_place = 0, unsure_lookalike = 0, turned = 0;
  bool pictured = false;
  for (size_t n = 0; n < sends.size(); ++n) {
    const size_t index = sends[n];
    LocalMap query = route[index];  // a copy: the change goes into this one
    Result<SimulatedChange> change = ApplySimulatedChange(query, rng);
    if (!change.ok()) continue;
    ++asked;
    v1::DetectChangesRequest request;
    request.set_collection(collection);
    *request.mutable_map() = ToProto(query);
    request.set_top_k(5);
    std::string how;
    if (lost) {  // the maps it sent before (and, at the start, the two before those)
      size_t earlier_maps = 0;
      for (size_t before = index; before >= kSendStep && earlier_maps < kMaxEarlier; ++earlier_maps) {
        before -= kSendStep;
        v1::SequenceMap* earlier = request.add_sequence();
        *earlier->mutable_map() = ToProto(route[before]);
        *earlier->mutable_in_query() = ToProto(DriftedOdometry(
            route[before].truth.global_frame, query.truth.global_frame,
            query.truth.travel_start - route[before].truth.travel_start, kDrift, rng));
        earlier->set_travel_m(query.truth.travel_start - route[before].truth.travel_start);
      }
      how = "lost: sequence of " + std::to_string(earlier_maps + 1) + " maps";
    } else {
      const double travel = query.truth.travel_start - fixed_at->truth.travel_start;
      v1::Prior* prior = request.mutable_prior();
      const Pose2 odometry = DriftedOdometry(fixed_at->truth.global_frame, query.truth.global_frame, travel, kDrift, rng);
      *prior->mutable_pose() = ToProto(Compose(fix, Inverse(odometry)));
      prior->set_radius_m(DriftRadius(travel, kDrift));
      prior->set_heading_sigma_rad(2 * M_PI / 180 + kDrift.heading_rad_per_m * travel);
      prior->set_fall_back_to_global(true);
      char text[64];
      std::snprintf(text, sizeof text, "prior, %.0f m since the last fix, radius %.1f m", travel, prior->radius_m());
      how = text;
    }
    v1::DetectChangesResponse response;
    const grpc::Status status = ctx.client.DetectChanges(request, &response);
    if (!status.ok()) return FailCall(status);

    // Did robot 1 see this place at all? (the best any stored map can do)
    double best_overlap = 0.0;
    for (const LocalMap& map : stored) best_overlap = std::max(best_overlap, PlaceOverlap(query, map));
    const bool seen = best_overlap >= 0.5;
    revisits += seen;
    const v1::Localization& verdict = response.localization();
    const Pose2 truth = query.truth.global_frame;
    std::printf("%-10s %s", query.id.c_str(), how.c_str());
    if (verdict.fell_back_to_global()) std::printf(" (failed: answered globally)");
    if (response.hits_size() == 0 || !response.hits(0).hit().has_collection_pose()) {
      std::printf("\n           no hit%s\n", seen ? "" : " (a place robot 1 never mapped)");
      ++no_hit;
      lost = true;
      site.fixes.push_back({truth, FixOutcome::kUnsure, std::to_string(n + 1)});
      continue;
    }
    const v1::MapHit& top = response.hits(0).hit();
    const Pose2 got = FromProto(top.collection_pose());
    const double error_m = PoseErrorM(got, truth), error_deg = PoseErrorDeg(got, truth);
    const bool pose_right = error_m <= 0.2 && error_deg <= 1.0;
    right += pose_right;
    sure += verdict.localized();
    sure_wrong += verdict.localized() && !pose_right;
    if (!pose_right && !verdict.localized() && !seen) ++new_place;
    if (!pose_right && !verdict.localized() && seen) {
      ++unsure_lookalike;
      turned += error_deg >= 45.0;
    }
    std::printf("\n           top hit %-10s score %.3f, %s (confidence %.2f); site pose error %.2f m %.1f deg: "
                "%s%s\n",
                top.map_id().c_str(), top.score(), verdict.localized() ? "sure" : "NOT sure", verdict.confidence(),
                error_m, error_deg, pose_right ? "right" : seen ? "WRONG" : "new place",
                verdict.sequence_maps() > 0 ? (", " + std::to_string(verdict.sequence_agreeing()) + " of " +
                                               std::to_string(verdict.sequence_maps()) + " earlier maps agree")
                                                  .c_str()
                                            : "");
    site.fixes.push_back({got, pose_right ? (verdict.localized() ? FixOutcome::kRight : FixOutcome::kUnsure)
                                          : (verdict.localized() ? FixOutcome::kWrong : FixOutcome::kUnsure),
                          std::to_string(n + 1)});
    lost = !verdict.localized();
    if (!lost) fix = got, fixed_at = &route[index];

    // The first-ranked mask counts only against a map that shows the place.
    const auto [mask, mask_hit] = FirstMask(response);
    const LocalMap* mask_db = mask_hit && by_id.count(mask_hit->hit().map_id()) ? by_id[mask_hit->hit().map_id()]
                                                                                  : nullptr;
    double mask_distance = INFINITY;
    if (mask) {
      for (int i = 0; i < mask->x_size(); ++i) {
        mask_distance = std::min(mask_distance, NearestDistance({mask->x(i), mask->y(i)}, change->changed_points));
      }
      site.changes.push_back(TransformPoint(got, Centroid(*mask)));
    }
    const bool found = mask_db && PlaceOverlap(query, *mask_db) >= 0.5 && mask_distance <= kChangeHitM;
    change_found += found;
    std::vector<Point2> region;
    for (const Point2& p : change->region_corners) region.push_back(TransformPoint(truth, p));
    site.true_changes.push_back(region);
    int masks = 0;
    for (const auto& hit : response.hits()) masks += hit.masks_size();
    std::printf("           %d change masks; the first %.2f m from the new objects: %s\n", masks, mask_distance,
                found ? "change found" : "change missed");

    const LocalMap* db = by_id.count(top.map_id()) ? by_id[top.map_id()] : nullptr;
    if (!pictured && db && pose_right && top.has_pose()) {  // the first right fix, in detail
      ResultPicture picture;
      picture.query = &query;
      picture.db = db;
      picture.query_in_db = FromProto(top.pose());
      for (const auto& m : response.hits(0).masks()) {
        std::vector<Point2> points;
        for (int i = 0; i < m.x_size(); ++i) points.push_back({m.x(i), m.y(i)});
        picture.masks.push_back(points);
      }
      picture.true_change = change->region_corners;
      picture.title = "query " + query.id + " against stored map " + db->id;
      std::ofstream(out_dir + "/result.svg") << RenderResultSvg(picture);
      pictured = true;
    }
  }
  int left_out = 0;
  const std::string site_path = out_dir + "/site.svg";
  std::ofstream(site_path) << RenderSiteSvg(site, &left_out);
  std::printf("\npictures: %s (robot 2's route, fixes and changes on the site map)%s\n", site_path.c_str(),
              pictured ? (", " + out_dir + "/result.svg (its first right fix in detail)").c_str() : "");
  if (left_out > 0) std::printf("(%d labels found no free place in the picture and were left out)\n", left_out);
  std::printf("\nsummary: %d/%d of robot 2's maps at the right place and pose (0.2 m, 1 deg; %d show a place robot 1 "
              "had mapped); lmdd was sure of %d, %d of them wrong; true change in the first mask for %d/%d\n",
              right, asked, revisits, sure, sure_wrong, change_found, asked);
  std::printf("misses: %d with no hit, %d at places robot 1 never mapped, %d wrong poses lmdd was not sure of (%d of "
              "them turned by 45 deg or more: look-alike corridors), %d sure and wrong\n",
              no_hit, new_place, unsure_lookalike, turned, sure_wrong);
  return 0;
}

}  // namespace lmd::cli
