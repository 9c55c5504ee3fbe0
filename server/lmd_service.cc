#include "server/lmd_service.h"

#include <spdlog/spdlog.h>

#include "server/grpc_status.h"
#include "server/validate.h"

namespace lmd::server {
namespace {

constexpr uint32_t kDefaultPageSize = 1000;

v1::StoredMap ToStoredMap(const v1::InsertMapRequest& request) {
  v1::StoredMap stored;
  *stored.mutable_metadata() = request.metadata();
  *stored.mutable_map() = request.map();
  return stored;
}

// Validates the lookup key of a get / delete.
Status ValidateKey(const std::string& collection, const std::string& map_id) {
  Status s = ValidateCollectionName(collection);
  return s.ok() ? ValidateMapId(map_id, /*allow_empty=*/false) : s;
}

}  // namespace

LmdServiceImpl::LmdServiceImpl(const ServerConfig& config, MapStore* store) : config_(config), store_(store) {}

grpc::Status LmdServiceImpl::InsertMaps(grpc::ServerContext*, const v1::InsertMapsRequest* request,
                                        v1::InsertMapsResponse* response) {
  if (request->maps_size() == 0) return ToGrpcStatus(Status::InvalidArgument("the request holds no maps"));
  if (static_cast<uint32_t>(request->maps_size()) > config_.max_maps_per_batch) {
    return ToGrpcStatus(Status::InvalidArgument(std::to_string(request->maps_size()) +
                                                " maps exceed max_maps_per_batch (" +
                                                std::to_string(config_.max_maps_per_batch) + ")"));
  }
  std::vector<v1::StoredMap> maps;
  maps.reserve(request->maps_size());
  for (int i = 0; i < request->maps_size(); ++i) {
    Status valid = ValidateInsert(request->maps(i), config_, i);
    if (!valid.ok()) return ToGrpcStatus(valid);
    maps.push_back(ToStoredMap(request->maps(i)));
  }
  Status stored = store_->InsertMaps(&maps, config_.max_collections);
  if (!stored.ok()) return ToGrpcStatus(stored);
  for (const v1::StoredMap& map : maps) *response->add_maps() = map.metadata();
  spdlog::debug("InsertMaps: stored {} maps", maps.size());
  return grpc::Status::OK;
}

grpc::Status LmdServiceImpl::StreamInsertMaps(grpc::ServerContext*, grpc::ServerReader<v1::InsertMapRequest>* reader,
                                              v1::InsertMapsResponse* response) {
  v1::InsertMapRequest request;
  for (size_t index = 0; reader->Read(&request); ++index) {
    Status status = ValidateInsert(request, config_, index);
    std::vector<v1::StoredMap> maps = {ToStoredMap(request)};
    if (status.ok()) status = store_->InsertMaps(&maps, config_.max_collections);
    if (!status.ok()) return ToGrpcStatus(status);
    *response->add_maps() = maps.front().metadata();
  }
  return grpc::Status::OK;
}

grpc::Status LmdServiceImpl::GetMap(grpc::ServerContext*, const v1::GetMapRequest* request,
                                    v1::GetMapResponse* response) {
  Status valid = ValidateKey(request->collection(), request->map_id());
  if (!valid.ok()) return ToGrpcStatus(valid);
  Result<v1::StoredMap> map = store_->GetMap(request->collection(), request->map_id());
  if (!map.ok()) return ToGrpcStatus(map.status());
  *response->mutable_map() = std::move(map).value();
  return grpc::Status::OK;
}

grpc::Status LmdServiceImpl::DeleteMap(grpc::ServerContext*, const v1::DeleteMapRequest* request,
                                       v1::DeleteMapResponse*) {
  Status status = ValidateKey(request->collection(), request->map_id());
  if (status.ok()) status = store_->DeleteMap(request->collection(), request->map_id());
  return ToGrpcStatus(status);
}

grpc::Status LmdServiceImpl::ListMaps(grpc::ServerContext*, const v1::ListMapsRequest* request,
                                      v1::ListMapsResponse* response) {
  Status status = ValidateCollectionName(request->collection());
  if (status.ok() && !request->page_token().empty()) status = ValidateMapId(request->page_token(), false);
  if (!status.ok()) return ToGrpcStatus(status);
  const uint32_t page_size = request->page_size() == 0 ? kDefaultPageSize
                                                       : std::min(request->page_size(), 10 * kDefaultPageSize);
  std::vector<v1::MapMetadata> maps;
  std::string next;
  status = store_->ListMaps(request->collection(), request->page_token(), page_size, &maps, &next);
  if (!status.ok()) return ToGrpcStatus(status);
  for (auto& meta : maps) *response->add_maps() = std::move(meta);
  response->set_next_page_token(next);
  return grpc::Status::OK;
}

grpc::Status LmdServiceImpl::ListCollections(grpc::ServerContext*, const v1::ListCollectionsRequest*,
                                             v1::ListCollectionsResponse* response) {
  for (auto& info : store_->ListCollections()) *response->add_collections() = std::move(info);
  return grpc::Status::OK;
}

grpc::Status LmdServiceImpl::Stats(grpc::ServerContext*, const v1::StatsRequest* request,
                                   v1::StatsResponse* response) {
  if (!request->collection().empty() && !store_->HasCollection(request->collection())) {
    return ToGrpcStatus(Status::NotFound("unknown collection '" + request->collection() + "'"));
  }
  for (auto& info : store_->ListCollections()) {
    if (request->collection().empty() || info.name() == request->collection()) {
      *response->add_collections() = std::move(info);
    }
  }
  response->set_uptime_s(std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count());
  response->set_version(LMD_VERSION);
  return grpc::Status::OK;
}

}  // namespace lmd::server
