#include "server/lmd_service.h"

#include <map>
#include <optional>

#include "core/util/fnv1a.h"
#include "proto/convert.h"
#include "server/indexing.h"
#include "server/stream_insert.h"
#include "server/validate.h"

namespace lmd::server {
namespace {

// A batch is one write, so it cannot hold one map twice: which of the two
// should be stored is the client's mistake to say, not lmdd's to guess.
Status DistinctIds(const v1::InsertMapsRequest& request) {
  std::map<std::pair<std::string, std::string>, int> first;  // (collection, id) -> index in the batch
  for (int i = 0; i < request.maps_size(); ++i) {
    const v1::MapMetadata& meta = request.maps(i).metadata();
    if (meta.map_id().empty()) continue;  // lmdd assigns distinct ids
    const auto [at, inserted] = first.emplace(std::make_pair(meta.collection(), meta.map_id()), i);
    if (!inserted) {
      return Status::InvalidArgument("maps[" + std::to_string(at->second) + "] and maps[" + std::to_string(i) +
                                     "] have the same id " + Quoted(meta.map_id()) + " in collection " +
                                     Quoted(meta.collection()));
    }
  }
  return Status::Ok();
}

constexpr uint32_t kDefaultPageSize = 1000;
constexpr uint32_t kMaxReplicationFactor = 9;  // copies of one collection: more only slow its writes
constexpr size_t kRecentFixes = 4096;  // sure localisations remembered to anchor the maps inserted next

// Validates the lookup key of a get / delete.
Status ValidateKey(const std::string& collection, const std::string& map_id) {
  Status s = ValidateCollectionName(collection);
  return s.ok() ? ValidateMapId(map_id, /*allow_empty=*/false) : s;
}

// What a kept request id is checked against: the maps as sent, each by its
// metadata and its content key's FNV half (the map's bytes, hashed once to
// describe it; the same on every node).
uint64_t RequestFingerprint(const std::vector<const v1::InsertMapRequest*>& requests,
                            const std::vector<DescriptorCache::Key>& keys) {
  uint64_t hash = kFnv1aOffset;
  for (size_t i = 0; i < requests.size(); ++i) {
    hash = Fnv1aMix(Fnv1a64(requests[i]->metadata().SerializeAsString(), hash), keys[i].b);
  }
  return hash;
}

// The collection a batch writes to, for logs ("" if none or several).
std::string BatchCollection(const v1::InsertMapsRequest& request) {
  if (request.maps_size() == 0) return "";
  const std::string& first = request.maps(0).metadata().collection();
  for (const auto& map : request.maps()) {
    if (map.metadata().collection() != first) return "";
  }
  return first;
}

}  // namespace

LmdServiceImpl::LmdServiceImpl(const ServerConfig& config, MapStore* store, CallRunner* runner,
                               CallMetrics* metrics)
    : config_(config),
      store_(store),
      runner_(runner),
      metrics_(metrics),
      cache_(config.descriptor_cache_entries),
      prepared_(size_t{config.prepared_map_cache_mb} << 20),
      fixes_(kRecentFixes) {}

std::shared_ptr<const DescribedMap> LmdServiceImpl::Describe(const v1::LocalMap& map, bool with_lmd,
                                                             DescriptorCache::Key* key_out) const {
  const DescriptorCache::Key key = DescriptorCache::KeyOf(map.SerializeAsString());
  if (key_out != nullptr) *key_out = key;
  std::shared_ptr<const DescribedMap> cached = cache_.Find(key);
  if (cached && (cached->lmd || !with_lmd)) return cached;
  std::shared_ptr<const DescribedMap> described;
  if (cached) {  // queried a moment ago, now stored: the descriptor is what is missing
    DescribedMap completed = *cached;
    completed.lmd = DescribeForIndex(MethodView(FromProto(map)), store_->indexing(), &completed.place);
    described = std::make_shared<const DescribedMap>(std::move(completed));
  } else {
    described = std::make_shared<const DescribedMap>(DescribeMap(FromProto(map), store_->indexing(), with_lmd));
  }
  cache_.Put(key, described);
  return described;
}

double LmdServiceImpl::uptime_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
}

Status LmdServiceImpl::Insert(std::vector<const v1::InsertMapRequest*> requests, size_t first_index,
                              const std::string& request_id, v1::InsertMapsResponse* response) {
  std::vector<MapWrite> maps;
  maps.reserve(requests.size());
  for (size_t i = 0; i < requests.size(); ++i) {
    Status valid = ValidateInsert(*requests[i], config_, first_index + i);
    if (!valid.ok()) return valid;
  }
  Status valid_id = ValidateRequestId(request_id);
  if (!valid_id.ok()) return valid_id;
  std::vector<std::shared_ptr<const DescribedMap>> described;
  std::vector<DescriptorCache::Key> keys;
  for (const v1::InsertMapRequest* request : requests) {  // described outside the store's lock
    MapWrite write;
    *write.map.mutable_metadata() = request->metadata();
    *write.map.mutable_map() = request->map();
    DescriptorCache::Key& key = keys.emplace_back();
    described.push_back(Describe(request->map(), /*with_lmd=*/store_->indexing().paper_index, &key));
    // The anchor (output only): the robot's pose hint, or where lmdd has
    // just localised this very map against the collection's anchored maps.
    v1::MapMetadata* meta = write.map.mutable_metadata();
    meta->clear_anchor();
    if (meta->has_pose_hint()) {
      *meta->mutable_anchor()->mutable_pose() = meta->pose_hint();
    } else if (std::optional<v1::MapAnchor> fix = fixes_.Find(meta->collection(), key)) {
      *meta->mutable_anchor() = *fix;
    }
    write.lmd = described.back()->lmd.value_or(Lmd{});  // empty without the paper's index
    write.place = described.back()->place.features;
    maps.push_back(std::move(write));
  }
  InsertLimits limits;
  limits.max_collections = config_.max_collections;
  limits.retain_maps = config_.retain_maps_per_collection;
  limits.request_ids_kept = config_.insert_request_ids_kept;
  std::vector<v1::MapMetadata> evicted;
  bool replayed = false;
  std::optional<InsertRequestId> request;
  if (!request_id.empty()) request = InsertRequestId{request_id, RequestFingerprint(requests, keys)};
  const InsertRequestId* kept = request ? &*request : nullptr;
  Status stored;
  if (cluster_ != nullptr) {  // the stream's maps too: each of its batches holds one map
    const std::string& collection = maps.front().map.metadata().collection();
    for (const MapWrite& write : maps) {
      if (write.map.metadata().collection() != collection) {
        return Status::InvalidArgument("in a cluster, one write holds maps of one collection");
      }
    }
    Result<cluster::ClusterNode::Route> route = cluster_->ForWrite(collection);
    if (!route.ok()) return route.status();
    if (!route->here) {
      return Status::Unavailable("this node is not the primary of collection '" + collection + "': send to " +
                                 route->address);
    }
    stored = cluster_->Insert(collection, &maps, limits, &evicted, kept, &replayed);
  } else {
    stored = store_->InsertMaps(&maps, limits, &evicted, nullptr, kept, &replayed);
  }
  if (!stored.ok()) return stored;
  if (replayed) response->set_replayed(true);  // a stream's messages add up
  // Prepared for scan matching already: the first query that hits them reuses it.
  for (size_t i = 0; i < maps.size() && !replayed; ++i) {
    prepared_.Put(maps[i].map.metadata().collection(), maps[i].index_id, described[i]->place.map);
  }
  for (const MapWrite& write : maps) *response->add_maps() = write.map.metadata();
  for (v1::MapMetadata& meta : evicted) *response->add_evicted() = std::move(meta);
  metrics_->RecordEvicted(evicted.size());
  return Status::Ok();
}

grpc::ServerUnaryReactor* LmdServiceImpl::InsertMaps(grpc::CallbackServerContext* context,
                                                     const v1::InsertMapsRequest* request,
                                                     v1::InsertMapsResponse* response) {
  // Every collection of the batch needs write access.
  Status allowed = runner_->auth().Authenticate(CallRunner::Authorization(context));
  for (const auto& map : request->maps()) {
    if (allowed.ok()) allowed = runner_->Authorize(context, map.metadata().collection(), Access::kWrite);
  }
  return runner_->Unary(context, "InsertMaps", BatchCollection(*request), allowed, [=] {
    if (request->maps_size() == 0) return Status::InvalidArgument("the request holds no maps");
    if (static_cast<uint32_t>(request->maps_size()) > config_.max_maps_per_batch) {
      return Status::InvalidArgument(std::to_string(request->maps_size()) + " maps exceed max_maps_per_batch (" +
                                     std::to_string(config_.max_maps_per_batch) + ")");
    }
    Status unique = DistinctIds(*request);
    if (!unique.ok()) return unique;
    if (cluster_ != nullptr && BatchCollection(*request).empty()) {
      return Status::InvalidArgument("in a cluster, one InsertMaps call holds maps of one collection");
    }
    for (int i = 0; i < request->maps_size(); ++i) {
      if (!request->maps(i).request_id().empty()) {
        return Status::InvalidArgument("maps[" + std::to_string(i) +
                                       "].request_id is for StreamInsertMaps: InsertMaps takes the request's request_id");
      }
    }
    if (!request->request_id().empty() && BatchCollection(*request).empty()) {
      return Status::InvalidArgument("an InsertMaps call with a request_id holds maps of one collection");
    }
    if (auto elsewhere = ServedElsewhere(true, BatchCollection(*request), context, &v1::LmdService::Stub::InsertMaps,
                                         *request, response)) {
      return *elsewhere;
    }
    std::vector<const v1::InsertMapRequest*> maps;
    for (const auto& map : request->maps()) maps.push_back(&map);
    return Insert(maps, 0, request->request_id(), response);
  });
}

grpc::ServerReadReactor<grpc::ByteBuffer>* LmdServiceImpl::StreamInsertMaps(grpc::CallbackServerContext* context,
                                                                             grpc::ByteBuffer* response) {
  return new StreamInsertReactor(context, response, this, runner_);
}

grpc::ServerUnaryReactor* LmdServiceImpl::GetMap(grpc::CallbackServerContext* context,
                                                 const v1::GetMapRequest* request, v1::GetMapResponse* response) {
  return runner_->Unary(context, "GetMap", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kRead), [=] {
    Status valid = ValidateKey(request->collection(), request->map_id());
    if (!valid.ok()) return valid;
    if (auto elsewhere = ServedElsewhere(false, request->collection(), context, &v1::LmdService::Stub::GetMap, *request,
                                         response)) {
      return *elsewhere;
    }
    Result<v1::StoredMap> map = store_->GetMap(request->collection(), request->map_id());
    if (!map.ok()) return map.status();
    *response->mutable_map() = std::move(map).value();
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::DeleteMap(grpc::CallbackServerContext* context,
                                                    const v1::DeleteMapRequest* request,
                                                    v1::DeleteMapResponse* response) {
  return runner_->Unary(context, "DeleteMap", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kWrite), [=] {
    Status status = ValidateKey(request->collection(), request->map_id());
    if (!status.ok()) return status;
    if (auto elsewhere = ServedElsewhere(true, request->collection(), context, &v1::LmdService::Stub::DeleteMap,
                                         *request, response, /*create=*/false)) {
      return *elsewhere;
    }
    if (cluster_ != nullptr) return cluster_->Delete(request->collection(), request->map_id());
    return store_->DeleteMap(request->collection(), request->map_id());
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::ListMaps(grpc::CallbackServerContext* context,
                                                   const v1::ListMapsRequest* request,
                                                   v1::ListMapsResponse* response) {
  return runner_->Unary(context, "ListMaps", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kRead), [=] {
    Status status = ValidateCollectionName(request->collection());
    if (status.ok()) status = ValidatePageToken(request->page_token());
    if (!status.ok()) return status;
    if (auto elsewhere = ServedElsewhere(false, request->collection(), context, &v1::LmdService::Stub::ListMaps,
                                         *request, response)) {
      return *elsewhere;
    }
    const uint32_t page_size =
        request->page_size() == 0 ? kDefaultPageSize : std::min(request->page_size(), 10 * kDefaultPageSize);
    std::vector<v1::MapMetadata> maps;
    std::string next;
    status = store_->ListMaps(request->collection(), request->page_token(), page_size, &maps, &next);
    if (!status.ok()) return status;
    for (auto& meta : maps) *response->add_maps() = std::move(meta);
    response->set_next_page_token(next);
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::ListCollections(grpc::CallbackServerContext* context,
                                                          const v1::ListCollectionsRequest*,
                                                          v1::ListCollectionsResponse* response) {
  // Any known token may list; it sees only the collections it may read.
  const std::string authorization = CallRunner::Authorization(context);
  return runner_->Unary(context, "ListCollections", "", runner_->auth().Authenticate(authorization), [=] {
    for (auto& info : store_->ListCollections()) {
      if (runner_->auth().CanRead(authorization, info.name())) *response->add_collections() = std::move(info);
    }
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::Stats(grpc::CallbackServerContext* context,
                                                const v1::StatsRequest* request, v1::StatsResponse* response) {
  const Status allowed = request->collection().empty()
                            ? runner_->AuthorizeServerWide(context, Access::kRead)
                            : runner_->Authorize(context, request->collection(), Access::kRead);
  return runner_->Unary(context, "Stats", request->collection(), allowed, [=] {
    if (!request->collection().empty() && !store_->HasCollection(request->collection())) {
      return Status::NotFound("unknown collection '" + request->collection() + "'");
    }
    for (auto& info : store_->ListCollections()) {
      if (request->collection().empty() || info.name() == request->collection()) {
        *response->add_collections() = std::move(info);
      }
    }
    for (auto& method : metrics_->Snapshot()) *response->add_methods() = std::move(method);
    response->set_uptime_s(uptime_s());
    response->set_cpu_seconds(ProcessCpuSeconds());
    response->set_version(LMD_VERSION);
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::Backup(grpc::CallbackServerContext* context,
                                                 const v1::BackupRequest* request, v1::BackupResponse* response) {
  // A backup copies every collection: it needs a server-wide write grant.
  return runner_->Unary(context, "Backup", "", runner_->AuthorizeServerWide(context, Access::kWrite), [=] {
    if (request->directory().empty() || request->directory().front() != '/') {
      return Status::InvalidArgument("directory must be an absolute path on the server");
    }
    Result<uint64_t> bytes = store_->Backup(request->directory());
    if (!bytes.ok()) return bytes.status();
    response->set_directory(request->directory());
    response->set_bytes(*bytes);
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::Cluster(grpc::CallbackServerContext* context, const v1::ClusterRequest*,
                                                  v1::ClusterResponse* response) {
  return runner_->Unary(context, "Cluster", "", runner_->AuthorizeServerWide(context, Access::kRead), [=] {
    if (cluster_ != nullptr) cluster_->Describe(response);
    return Status::Ok();
  });
}

grpc::ServerUnaryReactor* LmdServiceImpl::SetReplication(grpc::CallbackServerContext* context,
                                                         const v1::SetReplicationRequest* request,
                                                         v1::SetReplicationResponse* response) {
  return runner_->Unary(context, "SetReplication", request->collection(),
                        runner_->Authorize(context, request->collection(), Access::kWrite), [=] {
    Status valid = ValidateCollectionName(request->collection());
    if (!valid.ok()) return valid;
    if (request->replication_factor() < 1 || request->replication_factor() > kMaxReplicationFactor) {
      return Status::InvalidArgument("replication_factor must be 1 to " + std::to_string(kMaxReplicationFactor) +
                                     ", not " + std::to_string(request->replication_factor()));
    }
    if (cluster_ == nullptr) {
      return Status::FailedPrecondition("this lmdd runs alone (cluster_etcd is not set): it keeps one copy");
    }
    return cluster_->SetReplication(request->collection(), request->replication_factor(),
                                    response->mutable_placement());
  });
}

}  // namespace lmd::server
