// Retrieve and DetectChanges of LmdServiceImpl. The default method is the
// localisation pipeline of core/localize over the collection
// (StoreMapSource); the paper's methods describe the query the way the store
// described its maps, ask the collection's LMD index, and (for changes) run
// the paper's change detector against each hit's stored descriptor.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <unordered_map>
#include <unordered_set>

#include <spdlog/fmt/fmt.h>

#include "core/align/relative_pose.h"
#include "core/index/index.h"
#include "proto/convert.h"
#include "core/localize/prior.h"
#include "core/localize/sequence.h"
#include "server/indexing.h"
#include "server/lmd_service.h"
#include "server/store_map_source.h"
#include "server/validate.h"

namespace lmd::server {
namespace {

constexpr uint32_t kDefaultTopK = 10;

// CPU time of the calling thread, ms (a call runs on one worker thread).
double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// The core method for a paper method, or InvalidArgument if this store's
// index cannot serve it (it indexes one planner's descriptors).
Result<Method> PaperMethod(v1::Method method, Planner indexed_planner) {
  switch (method) {
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

// hit_ids: the returned hits' map ids (empty: deleted meanwhile).
void ToWire(const Verdict& verdict, const std::vector<std::string>& hit_ids, v1::Localization* out) {
  out->set_localized(verdict.sure);
  out->set_confidence(verdict.confidence);
  out->set_best_score(verdict.best_score);
  out->set_rival_score(verdict.rival_score);
  out->set_agreeing(static_cast<uint32_t>(verdict.agreeing));
  out->set_prior_used(verdict.prior_used);
  out->set_prior_failed(verdict.prior_failed);
  out->set_fell_back_to_global(verdict.fell_back_to_global);
  out->set_sequence_maps(static_cast<uint32_t>(verdict.sequence_maps));
  out->set_sequence_agreeing(static_cast<uint32_t>(verdict.sequence_agreeing));
  out->set_sequence_by_newest(verdict.sequence_by_newest);
  out->set_slide_margin(verdict.slide_margin);
  if (verdict.vote_lead) out->set_vote_lead(*verdict.vote_lead);
  if (!hit_ids.empty()) *out->mutable_pose_covariance() = ToProto(verdict.pose_covariance);
  if (verdict.collection_pose && verdict.collection_pose_hit < hit_ids.size() &&
      !hit_ids[verdict.collection_pose_hit].empty()) {
    *out->mutable_collection_pose() = ToProto(*verdict.collection_pose);
    out->set_collection_pose_map_id(hit_ids[verdict.collection_pose_hit]);
    if (verdict.collection_pose_covariance) {
      *out->mutable_collection_pose_covariance() = ToProto(*verdict.collection_pose_covariance);
    }
  }
}

}  // namespace

template <typename Request>
LmdServiceImpl::QueryRequest LmdServiceImpl::QueryOf(const Request& request, bool with_changes) {
  QueryRequest q;
  q.collection = &request.collection();
  q.map = &request.map();
  q.top_k = request.top_k();
  q.method = request.method();
  q.exclude = &request.exclude_map_ids();
  q.verify_candidates = request.verify_candidates();
  q.prior = request.has_prior() ? &request.prior() : nullptr;
  q.sequence = &request.sequence();
  q.with_changes = with_changes;
  return q;
}

bool LmdServiceImpl::AnchorIsGiven(const std::string& collection, const std::string& map_id) const {
  Result<v1::MapMetadata> meta = store_->GetMetadata(collection, map_id);
  return meta.ok() && meta->has_anchor() && !meta->anchor().derived();
}

Result<Localization> LmdServiceImpl::Localise(const QueryRequest& request, const LocalQuery& query,
                                              const LocalizeOptions& options,
                                              const std::function<bool()>& stop) const {
  const std::unordered_set<std::string> excluded(request.exclude->begin(), request.exclude->end());
  const StoreMapSource source(store_, &prepared_, *request.collection, excluded);
  if (request.prior != nullptr) {
    const v1::Prior& wire = *request.prior;
    Prior prior;
    prior.pose = FromProto(wire.pose());
    prior.radius_m = wire.radius_m();
    prior.heading_sigma_rad = wire.heading_sigma_rad();
    Localization near = LocalizeNear(query, source, options, prior, {}, stop, request.with_changes);
    if (!near.verdict.prior_failed) return near;
    if (!wire.fall_back_to_global()) {
      // Maps near a wrong prior matched at their best pose anyway: those
      // that explain nothing of the query would only be noise to a robot.
      near.hits.erase(std::remove_if(near.hits.begin(), near.hits.end(),
                                     [](const LocalizedHit& h) { return h.score <= 0; }),
                      near.hits.end());
      return near;
    }
    // Over the anchored maps: the robot asked for a pose in the site frame,
    // and only they give one (a prior needs anchored maps).
    LocalizeOptions site = options;
    site.search.anchored_only = true;
    Localization global = Localize(query, source, site, {}, stop, request.with_changes);
    global.verdict.prior_used = global.verdict.prior_failed = global.verdict.fell_back_to_global = true;
    return global;
  }
  if (!request.sequence->empty()) {
    std::vector<SequenceStep> steps;
    for (const v1::SequenceMap& wire : *request.sequence) {
      SequenceStep step;
      step.query = PrepareLocalQuery(MethodView(FromProto(wire.map())), options, &Describe(wire.map(), /*with_lmd=*/false)->place);
      step.in_newest = FromProto(wire.in_query());
      step.travel_m = wire.travel_m();
      steps.push_back(std::move(step));
    }
    return LocalizeSequence(query, steps, source, options, {}, stop, request.with_changes);
  }
  return Localize(query, source, options, {}, stop, request.with_changes);
}

Result<LmdServiceImpl::Query> LmdServiceImpl::RunQuery(const QueryRequest& request,
                                                       grpc::CallbackServerContext* context) const {
  const auto give_up_at = std::chrono::steady_clock::now() + std::chrono::duration<double>(config_.max_query_seconds);
  bool out_of_time = false;
  auto stop = [&] {
    out_of_time = out_of_time || (config_.max_query_seconds > 0 && std::chrono::steady_clock::now() >= give_up_at);
    return out_of_time || context->IsCancelled();
  };
  const std::string& collection = *request.collection;
  Status valid = ValidateCollectionName(collection);
  if (valid.ok()) valid = ValidateLocalMap(*request.map, config_, "query map");
  if (!valid.ok()) return valid;
  if (request.top_k > config_.max_top_k) {
    return Status::InvalidArgument("top_k " + std::to_string(request.top_k) + " exceeds max_top_k (" +
                                   std::to_string(config_.max_top_k) + ")");
  }
  if (static_cast<size_t>(request.exclude->size()) > config_.max_top_k) {
    return Status::InvalidArgument(std::to_string(request.exclude->size()) + " exclude_map_ids exceed max_top_k (" +
                                   std::to_string(config_.max_top_k) + ")");
  }
  if (request.verify_candidates > config_.max_verify_candidates) {
    return Status::InvalidArgument("verify_candidates " + std::to_string(request.verify_candidates) +
                                   " exceeds max_verify_candidates (" +
                                   std::to_string(config_.max_verify_candidates) + ")");
  }
  valid = ValidatePriorAndSequence(request.prior != nullptr, request.prior ? *request.prior : v1::Prior(),
                                   *request.sequence, config_);
  if (!valid.ok()) return valid;
  const bool default_method = request.method == v1::METHOD_DEFAULT;
  if (!default_method && (request.prior != nullptr || !request.sequence->empty())) {
    return Status::InvalidArgument("priors and sequences are answered by the default method only");
  }
  Result<Method> paper_method = Method::kLmd;
  if (!default_method) {
    paper_method = PaperMethod(request.method, store_->indexing().viewpoint.planner);
    if (!paper_method.ok()) return paper_method.status();
    if (!store_->indexing().paper_index) {
      return Status::FailedPrecondition(
          "this lmdd keeps no index for the paper's methods (paper_index = false): ask with the default method");
    }
  }
  if (!store_->HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");
  if (request.prior != nullptr && !store_->HasAnchors(collection)) {
    return Status::FailedPrecondition("collection '" + collection +
                                      "' has no anchored maps: a prior needs maps inserted with a pose_hint");
  }

  Query query;
  DescriptorCache::Key key;
  query.described = Describe(*request.map, /*with_lmd=*/!default_method, &key);
  const size_t wanted = request.top_k == 0 ? kDefaultTopK : request.top_k;
  if (default_method) {
    LocalizeOptions options = store_->indexing().localize;
    options.top_k = wanted;
    options.verify_maps = request.verify_candidates > 0 ? request.verify_candidates : config_.verify_candidates;
    const bool busy = request.verify_candidates == 0 && config_.busy_queued_calls > 0 &&
                      runner_->pool().queued() >= config_.busy_queued_calls;
    if (busy && config_.busy_verify_candidates < options.verify_maps) {
      options.verify_maps = config_.busy_verify_candidates;
      options.passed_over_retries = 0;  // retries are depth too
      options.fit_rank_maps = 0;        // and so is reading the grids of maps it will not verify
      options.second_round_hypotheses = 0;
      query.reduced_depth = true;
    }
    if (busy && config_.busy_search_candidates > 0 &&
        (options.search.max_candidates == 0 || config_.busy_search_candidates < options.search.max_candidates)) {
      options.search.max_candidates = config_.busy_search_candidates;
      options.search.min_candidates_per_map = 0;  // a busy lmdd's bound is the bound
      query.reduced_depth = true;
    }
    const LocalQuery local = PrepareLocalQuery(MethodView(FromProto(*request.map)), options, &query.described->place);
    Result<Localization> localization = Localise(request, local, options, stop);
    if (!localization.ok()) return localization.status();
    query.localization = std::move(localization).value();
    if (out_of_time) {
      return Status::DeadlineExceeded(
          fmt::format("the query was given up after max_query_seconds ({:g} s) of scan matching",
                      config_.max_query_seconds));
    }
    if (context->IsCancelled()) return Status::Cancelled("call cancelled during verification");
    for (const LocalizedHit& hit : query.localization.hits) {
      Result<IndexedEntry> entry = store_->Indexed(collection, hit.map_id);
      query.hit_ids.push_back(entry.ok() ? entry->map_id : std::string());  // empty: deleted meanwhile
    }
    // A sure answer whose site pose comes from a map anchored by a given
    // pose anchors this map if it is stored next. Not from a derived anchor:
    // one wrong sure answer would otherwise anchor a robot's every later map
    // on its own wrong ones (measured: lmd-bench load --mode fleet, robots
    // locked 13-24 m off).
    const Localization& l = query.localization;
    const std::string* from = l.verdict.collection_pose ? &query.hit_ids[l.verdict.collection_pose_hit] : nullptr;
    if (l.verdict.sure && from != nullptr && !from->empty() && AnchorIsGiven(collection, *from)) {
      v1::MapAnchor fix;
      *fix.mutable_pose() = ToProto(*l.verdict.collection_pose);
      fix.set_derived(true);
      fix.set_from_map_id(*from);
      fix.set_confidence(l.verdict.confidence);
      fixes_.Put(collection, key, fix);
    }
    metrics_->RecordQueryWork(l.stats.search.candidates, l.stats.maps_matched, query.reduced_depth);
    metrics_->RecordAnswer(l.verdict);
    return query;
  }
  const std::unordered_set<std::string> excluded(request.exclude->begin(), request.exclude->end());
  RetrieveOptions options;
  options.top_k = wanted + request.exclude->size();  // excluded maps may take places in the ranking
  options.method = *paper_method;
  Result<std::vector<StoreHit>> hits = store_->Retrieve(collection, *query.described->lmd, options);
  if (!hits.ok()) return hits.status();
  hits->erase(std::remove_if(hits->begin(), hits->end(),
                             [&](const StoreHit& hit) { return excluded.count(hit.map_id) != 0; }),
              hits->end());
  if (hits->size() > wanted) hits->resize(wanted);
  query.paper_hits = std::move(hits).value();
  return query;
}

v1::MapHit LmdServiceImpl::PaperWireHit(const std::string& collection, const Query& query, const StoreHit& hit,
                                        size_t rank, const Lmd* db, v1::Method method) const {
  v1::MapHit out;
  out.set_rank(static_cast<uint32_t>(rank + 1));
  out.set_map_id(hit.map_id);
  out.set_score(hit.hit.score);
  out.set_orientation_deg(static_cast<uint32_t>(hit.hit.orientation * 90));
  out.set_offset_x(hit.hit.offset.x);
  out.set_offset_y(hit.hit.offset.y);
  Result<v1::MapMetadata> meta = store_->GetMetadata(collection, hit.map_id);
  if (meta.ok()) *out.mutable_metadata() = std::move(meta).value();  // absent if deleted meanwhile
  if (db != nullptr && method != v1::METHOD_BOW) {
    *out.mutable_pose() =
        ToProto(RelativePose(query.described->lmd->frame, db->frame, hit.hit.orientation, hit.hit.offset));
  }
  return out;
}

grpc::ServerUnaryReactor* LmdServiceImpl::Retrieve(grpc::CallbackServerContext* context,
                                                   const v1::RetrieveRequest* request,
                                                   v1::RetrieveResponse* response) {
  return runner_->Unary(context, "Retrieve", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kRead), [=] {
    if (auto elsewhere = ServedElsewhere(false, request->collection(), context, &v1::LmdService::Stub::Retrieve,
                                         *request, response)) {
      return *elsewhere;
    }
    const double cpu_start = ThreadCpuMs();
    Result<Query> query = RunQuery(QueryOf(*request, false), context);
    if (!query.ok()) return query.status();
    response->set_reduced_depth(query->reduced_depth);
    if (request->method() == v1::METHOD_DEFAULT) {
      ToWire(query->localization.verdict, query->hit_ids, response->mutable_localization());
      for (size_t i = 0; i < query->localization.hits.size(); ++i) {
        if (query->hit_ids[i].empty()) continue;
        *response->add_hits() = DefaultWireHit(request->collection(), query->localization.hits[i],
                                               query->hit_ids[i], response->hits_size());
      }
    } else {
      for (size_t rank = 0; rank < query->paper_hits.size(); ++rank) {
        if (context->IsCancelled()) return Status::Cancelled("call cancelled");
        const StoreHit& hit = query->paper_hits[rank];
        Result<Lmd> db = store_->GetDescriptor(request->collection(), hit.map_id);
        *response->add_hits() = PaperWireHit(request->collection(), *query, hit, rank, db.ok() ? &*db : nullptr,
                                             request->method());
      }
    }
    response->set_server_cpu_ms(ThreadCpuMs() - cpu_start);
    return Status::Ok();
  });
}

v1::MapHit LmdServiceImpl::DefaultWireHit(const std::string& collection, const LocalizedHit& hit,
                                          const std::string& map_id, int rank) const {
  v1::MapHit out;
  out.set_rank(static_cast<uint32_t>(rank + 1));
  out.set_map_id(map_id);
  out.set_score(hit.score);
  out.set_verified(true);
  out.set_agrees_with_best(hit.agrees_with_best);
  *out.mutable_pose() = ToProto(hit.pose);
  if (hit.collection_pose) *out.mutable_collection_pose() = ToProto(*hit.collection_pose);
  out.set_sequence_agreeing(static_cast<uint32_t>(hit.sequence_agreeing));
  Result<v1::MapMetadata> meta = store_->GetMetadata(collection, map_id);
  if (meta.ok()) *out.mutable_metadata() = std::move(meta).value();
  return out;
}

grpc::ServerUnaryReactor* LmdServiceImpl::DetectChanges(grpc::CallbackServerContext* context,
                                                        const v1::DetectChangesRequest* request,
                                                        v1::DetectChangesResponse* response) {
  return runner_->Unary(context, "DetectChanges", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kRead), [=] {
    const double cpu_start = ThreadCpuMs();
    if (!(request->threshold() >= 0) || !std::isfinite(request->threshold())) {
      return Status::InvalidArgument("threshold must be a finite number >= 0 (0: the default)");
    }
    if (auto elsewhere = ServedElsewhere(false, request->collection(), context,
                                         &v1::LmdService::Stub::DetectChanges, *request, response)) {
      return *elsewhere;
    }
    Result<Query> query = RunQuery(QueryOf(*request, true), context);
    if (!query.ok()) return query.status();
    if (context->IsCancelled()) return Status::Cancelled("call cancelled");
    response->set_reduced_depth(query->reduced_depth);
    uint32_t rank = 0;
    auto add_mask = [&](v1::ChangeHit* hit, const ChangeMask& mask, v1::MaskSource source) {
      if (request->max_masks_per_hit() > 0 && static_cast<uint32_t>(hit->masks_size()) >= request->max_masks_per_hit()) {
        return;
      }
      v1::ChangeMask* wire = hit->add_masks();
      wire->set_rank(++rank);
      wire->set_score(mask.score);
      wire->set_source(source);
      for (const Point2& p : mask.points) {
        wire->add_x(static_cast<float>(p.x));
        wire->add_y(static_cast<float>(p.y));
      }
    };

    if (request->method() == v1::METHOD_DEFAULT) {
      const Localization& localization = query->localization;
      ToWire(localization.verdict, query->hit_ids, response->mutable_localization());
      std::unordered_map<uint64_t, v1::ChangeHit*> by_id;
      for (size_t i = 0; i < localization.hits.size(); ++i) {
        if (query->hit_ids[i].empty()) continue;
        v1::ChangeHit* hit = response->add_hits();
        *hit->mutable_hit() = DefaultWireHit(request->collection(), localization.hits[i], query->hit_ids[i],
                                             response->hits_size() - 1);
        by_id[localization.hits[i].map_id] = hit;
      }
      for (const ChangeMask& mask : localization.changes) {  // best first
        const auto it = by_id.find(mask.db_map_id);
        if (it != by_id.end()) add_mask(it->second, mask, v1::MASK_SOURCE_GEOMETRIC);
      }
      response->set_server_cpu_ms(ThreadCpuMs() - cpu_start);
      return Status::Ok();
    }

    std::vector<Lmd> dbs;  // descriptors of the hits still stored
    std::vector<const StoreHit*> kept;
    for (const StoreHit& hit : query->paper_hits) {
      Result<Lmd> db = store_->GetDescriptor(request->collection(), hit.map_id);
      if (!db.ok()) continue;  // deleted since retrieval
      dbs.push_back(std::move(db).value());
      kept.push_back(&hit);
    }
    std::vector<ChangeCandidate> candidates;
    for (size_t i = 0; i < kept.size(); ++i) {
      MapHit aligned = kept[i]->hit;
      aligned.rank = i;
      candidates.push_back({aligned, &dbs[i]});
    }
    ChangeDetectorOptions options;
    if (request->threshold() > 0) options.threshold = request->threshold();
    Result<std::vector<ChangeMask>> masks = lmd::DetectChanges(*query->described->lmd, candidates, options);
    if (!masks.ok()) return masks.status();
    std::vector<v1::ChangeHit*> wire_hits;
    for (size_t i = 0; i < kept.size(); ++i) {
      v1::ChangeHit* change_hit = response->add_hits();
      *change_hit->mutable_hit() = PaperWireHit(request->collection(), *query, *kept[i], i, &dbs[i], request->method());
      wire_hits.push_back(change_hit);
    }
    for (const ChangeMask& mask : *masks) {  // ranked by the hit's K, then r
      size_t i = 0;
      while (i < kept.size() && kept[i]->hit.map_id != mask.db_map_id) ++i;
      if (i < kept.size()) add_mask(wire_hits[i], mask, v1::MASK_SOURCE_DESCRIPTOR);
    }
    response->set_server_cpu_ms(ThreadCpuMs() - cpu_start);
    return Status::Ok();
  });
}

}  // namespace lmd::server
