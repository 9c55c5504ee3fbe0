// Retrieve and DetectChanges of LmdServiceImpl: describe the query map the
// way the store's maps were described, ask the collection's index, and (for
// changes) run the change detector against each hit's stored descriptor.
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "core/align/relative_pose.h"
#include "core/change/geometric_changes.h"
#include "core/index/index.h"
#include "proto/convert.h"
#include "server/indexing.h"
#include "server/lmd_service.h"
#include "server/validate.h"

namespace lmd::server {
namespace {

constexpr uint32_t kDefaultTopK = 10;
// Verification score (overlap - 2 conflicts, verify_hits.h) from which a hit
// is taken to show the query's place, so that geometry may name changes. Low
// because the change itself adds conflicts; lmd-eval's best uses 0 on its own
// consistency score (with reverse conflicts; bench/eval, docs/results.md).
// Masks are held against such hits within kPlaceHitsWindow of the best.
constexpr double kShowsPlaceScore = 0.2;

// The core method for a wire method, or InvalidArgument if this store's
// index cannot serve it (it indexes one planner's descriptors).
Result<Method> CoreMethod(v1::Method method, Planner indexed_planner) {
  switch (method) {
    case v1::METHOD_DEFAULT: return Method::kLmd;
    case v1::METHOD_BOW: return Method::kBow;
    case v1::METHOD_LMD_COR:
    case v1::METHOD_LMD_COG: {
      const Planner wanted = method == v1::METHOD_LMD_COR ? Planner::kCoR : Planner::kCoG;
      if (wanted != indexed_planner) {
        return Status::InvalidArgument(std::string(v1::Method_Name(method)) + " is not served: this lmdd indexes " +
                                       PlannerName(indexed_planner) + " viewpoints");
      }
      return Method::kLmd;
    }
    default: return Status::InvalidArgument("unknown method " + std::to_string(method));
  }
}

// The change detector predicts db positions through a quarter-turn
// orientation and an offset between planned frames; a scan-matched pose
// gives both far more precisely than the index's offset bins.
void AlignFromPose(const Frame& query_frame, const Frame& db_frame, const Pose2& pose, MapHit* hit) {
  const double turn = std::remainder(pose.theta + query_frame.heading - db_frame.heading, 2 * M_PI);
  hit->orientation = static_cast<int>(std::lround(turn / (M_PI / 2)) + 4) % 4;
  hit->offset = ToFrame(db_frame, TransformPoint(pose, query_frame.origin));
}

// The smaller of two max_maps_scored settings, where 0 means no limit.
size_t FewerMapsScored(size_t a, size_t b) {
  if (a == 0) return b;
  if (b == 0) return a;
  return std::min(a, b);
}

}  // namespace

Result<LmdServiceImpl::Query> LmdServiceImpl::RunQuery(
    const std::string& collection, const v1::LocalMap& map, uint32_t top_k, v1::Method method,
    const google::protobuf::RepeatedPtrField<std::string>& exclude, uint32_t verify_candidates,
    grpc::CallbackServerContext* context) const {
  Status valid = ValidateCollectionName(collection);
  if (valid.ok()) valid = ValidateLocalMap(map, config_, "query map");
  if (!valid.ok()) return valid;
  if (top_k > config_.max_top_k) {
    return Status::InvalidArgument("top_k " + std::to_string(top_k) + " exceeds max_top_k (" +
                                   std::to_string(config_.max_top_k) + ")");
  }
  if (static_cast<size_t>(exclude.size()) > config_.max_top_k) {
    return Status::InvalidArgument(std::to_string(exclude.size()) + " exclude_map_ids exceed max_top_k (" +
                                   std::to_string(config_.max_top_k) + ")");
  }
  if (verify_candidates > config_.max_verify_candidates) {
    return Status::InvalidArgument("verify_candidates " + std::to_string(verify_candidates) +
                                   " exceeds max_verify_candidates (" +
                                   std::to_string(config_.max_verify_candidates) + ")");
  }
  Result<Method> core_method = CoreMethod(method, store_->indexing().viewpoint.planner);
  if (!core_method.ok()) return core_method.status();
  if (!store_->HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");

  Query query;
  query.map = MethodView(FromProto(map));
  const DescriptorCache::Key key = DescriptorCache::KeyOf(map.SerializeAsString());
  query.lmd = Describe(map, key);
  const bool busy = method == v1::METHOD_DEFAULT && verify_candidates == 0 && config_.busy_queued_calls > 0 &&
                    runner_->pool().queued() >= config_.busy_queued_calls;
  RetrieveOptions options;
  const size_t wanted = top_k == 0 ? kDefaultTopK : top_k;
  size_t verify_depth = verify_candidates > 0 ? verify_candidates : config_.verify_candidates;
  if (busy && config_.busy_verify_candidates < verify_depth) {
    verify_depth = config_.busy_verify_candidates;
    query.reduced_depth = true;
  }
  const bool verify = method == v1::METHOD_DEFAULT && verify_depth > 0;
  const size_t depth = verify ? std::max(wanted, verify_depth) : wanted;
  // Excluded maps may take places in the index's ranking: ask for that many more.
  options.top_k = depth + exclude.size();
  options.method = *core_method;
  if (method == v1::METHOD_DEFAULT) {
    options.max_offset_m = config_.default_max_offset_m;
    options.max_maps_scored = config_.max_maps_scored;
    options.bound_skip_postings_per_map = config_.bound_skip_postings_per_map;
    const size_t busy_maps_scored = FewerMapsScored(options.max_maps_scored, config_.busy_max_maps_scored);
    if (busy && busy_maps_scored != options.max_maps_scored) {
      options.max_maps_scored = busy_maps_scored;
      query.reduced_depth = true;
    }
  }
  RetrieveStats work;
  Result<std::vector<StoreHit>> hits = store_->Retrieve(collection, query.lmd, options, &work);
  if (!hits.ok()) return hits.status();
  if (!exclude.empty()) {
    const std::unordered_set<std::string> excluded(exclude.begin(), exclude.end());
    hits->erase(std::remove_if(hits->begin(), hits->end(),
                               [&](const StoreHit& hit) { return excluded.count(hit.map_id) != 0; }),
                hits->end());
    if (hits->size() > depth) hits->resize(depth);
  }
  if (verify) {
    Result<std::vector<VerifiedStoreHit>> verified =
        verifier_.Verify(collection, query.map, key, query.lmd, *hits, verify_depth,
                         config_.verify_enough_matches, config_.reverse_conflict_weight,
                         [context] { return context->IsCancelled(); });
    if (!verified.ok()) return verified.status();
    query.hits = std::move(verified).value();
  } else {
    for (const StoreHit& hit : *hits) query.hits.push_back({hit, false, hit.hit.score, {}, nullptr});
  }
  size_t verified = 0;
  for (const VerifiedStoreHit& hit : query.hits) verified += hit.verified;
  metrics_->RecordQueryWork(work.maps_touched, work.maps_scored, work.postings_read, verified, query.reduced_depth);
  if (query.hits.size() > wanted) query.hits.resize(wanted);
  return query;
}

Result<v1::MapHit> LmdServiceImpl::ToWireHit(const std::string& collection, const Query& query,
                                             const VerifiedStoreHit& hit, size_t rank, const Lmd* db,
                                             v1::Method method) const {
  v1::MapHit out;
  out.set_rank(static_cast<uint32_t>(rank + 1));
  out.set_map_id(hit.hit.map_id);
  out.set_score(hit.score);
  out.set_orientation_deg(static_cast<uint32_t>(hit.hit.hit.orientation * 90));
  out.set_offset_x(hit.hit.hit.offset.x);
  out.set_offset_y(hit.hit.hit.offset.y);
  Result<v1::MapMetadata> meta = store_->GetMetadata(collection, hit.hit.map_id);
  if (meta.ok()) *out.mutable_metadata() = std::move(meta).value();  // absent if deleted meanwhile
  out.set_verified(hit.verified);
  if (hit.verified) {
    *out.mutable_pose() = ToProto(hit.pose);
  } else if (db != nullptr && method != v1::METHOD_BOW) {
    *out.mutable_pose() =
        ToProto(RelativePose(query.lmd.frame, db->frame, hit.hit.hit.orientation, hit.hit.hit.offset));
  }
  return out;
}

grpc::ServerUnaryReactor* LmdServiceImpl::Retrieve(grpc::CallbackServerContext* context,
                                                   const v1::RetrieveRequest* request,
                                                   v1::RetrieveResponse* response) {
  return runner_->Unary(context, "Retrieve", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kRead), [=] {
    Result<Query> query = RunQuery(request->collection(), request->map(), request->top_k(), request->method(),
                                   request->exclude_map_ids(), request->verify_candidates(), context);
    if (!query.ok()) return query.status();
    response->set_reduced_depth(query->reduced_depth);
    for (size_t rank = 0; rank < query->hits.size(); ++rank) {
      if (context->IsCancelled()) return Status::Cancelled("call cancelled");
      const VerifiedStoreHit& hit = query->hits[rank];
      Result<Lmd> db = store_->GetDescriptor(request->collection(), hit.hit.map_id);
      Result<v1::MapHit> wire = ToWireHit(request->collection(), *query, hit, rank, db.ok() ? &*db : nullptr,
                                          request->method());
      if (!wire.ok()) return wire.status();
      *response->add_hits() = std::move(wire).value();
    }
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::DetectChanges(grpc::CallbackServerContext* context,
                                                        const v1::DetectChangesRequest* request,
                                                        v1::DetectChangesResponse* response) {
  return runner_->Unary(context, "DetectChanges", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kRead), [=] {
    if (!(request->threshold() >= 0) || !std::isfinite(request->threshold())) {
      return Status::InvalidArgument("threshold must be a finite number >= 0 (0: the default)");
    }
    Result<Query> query = RunQuery(request->collection(), request->map(), request->top_k(), request->method(),
                                   request->exclude_map_ids(), request->verify_candidates(), context);
    if (!query.ok()) return query.status();
    if (context->IsCancelled()) return Status::Cancelled("call cancelled");
    response->set_reduced_depth(query->reduced_depth);

    std::vector<Lmd> dbs;  // descriptors of the hits still stored
    std::vector<const VerifiedStoreHit*> kept;
    dbs.reserve(query->hits.size());
    for (const VerifiedStoreHit& hit : query->hits) {
      Result<Lmd> db = store_->GetDescriptor(request->collection(), hit.hit.map_id);
      if (!db.ok()) continue;  // deleted since retrieval
      dbs.push_back(std::move(db).value());
      kept.push_back(&hit);
    }
    std::vector<ChangeCandidate> candidates;
    for (size_t i = 0; i < kept.size(); ++i) {
      MapHit aligned = kept[i]->hit.hit;
      aligned.rank = i;
      aligned.score = kept[i]->score;
      if (kept[i]->verified) AlignFromPose(query->lmd.frame, dbs[i].frame, kept[i]->pose, &aligned);
      candidates.push_back({aligned, &dbs[i]});
    }
    ChangeDetectorOptions options;
    if (request->threshold() > 0) options.threshold = request->threshold();
    Result<std::vector<ChangeMask>> masks = lmd::DetectChanges(query->lmd, candidates, options);
    if (!masks.ok()) return masks.status();

    std::vector<size_t> per_hit(kept.size(), 0);
    std::vector<v1::ChangeHit*> wire_hits;
    for (size_t i = 0; i < kept.size(); ++i) {
      Result<v1::MapHit> wire = ToWireHit(request->collection(), *query, *kept[i], i, &dbs[i], request->method());
      if (!wire.ok()) return wire.status();
      v1::ChangeHit* change_hit = response->add_hits();
      *change_hit->mutable_hit() = std::move(wire).value();
      wire_hits.push_back(change_hit);
    }
    uint32_t rank = 0;
    auto add_mask = [&](size_t i, const ChangeMask& mask, v1::MaskSource source) {
      if (request->max_masks_per_hit() > 0 && per_hit[i] >= request->max_masks_per_hit()) return;
      ++per_hit[i];
      v1::ChangeMask* wire = wire_hits[i]->add_masks();
      wire->set_rank(++rank);
      wire->set_score(mask.score);
      wire->set_source(source);
      for (const Point2& p : mask.points) {
        wire->add_x(static_cast<float>(p.x));
        wire->add_y(static_cast<float>(p.y));
      }
    };
    // Geometric masks against the verified hits that show the query's place (id = position in kept).
    std::vector<double> verified_scores;
    for (const VerifiedStoreHit* hit : kept) {
      verified_scores.push_back(hit->verified && hit->prepared ? hit->score : -std::numeric_limits<double>::infinity());
    }
    std::vector<AlignedMap> place;
    for (size_t i : PlaceHits(verified_scores, kShowsPlaceScore, kPlaceHitsWindow)) {
      place.push_back({kept[i]->prepared.get(), kept[i]->pose, i});
    }
    for (const ChangeMask& mask : GeometricChanges(query->map.points, query->map.trajectory, query->map.scans, place)) {
      add_mask(mask.db_map_id, mask, v1::MASK_SOURCE_GEOMETRIC);
    }
    for (const ChangeMask& mask : *masks) {  // ranked by the hit's K, then r
      size_t i = 0;
      while (i < kept.size() && kept[i]->hit.hit.map_id != mask.db_map_id) ++i;
      if (i < kept.size()) add_mask(i, mask, v1::MASK_SOURCE_DESCRIPTOR);
    }
    return Status::Ok();
  });
}

}  // namespace lmd::server
