// The gRPC service (callback API): one handler per RPC. Each handler names
// the collection and access it needs and hands a few lines of work to the
// CallRunner (auth, worker pool, deadline, metrics); the work translates the
// wire message, calls the store, and translates back.
#pragma once

#include <chrono>
#include <optional>
#include <string>

#include "lmd/v1/lmd.grpc.pb.h"
#include "server/call_runner.h"
#include "server/config.h"
#include "core/change/change_detector.h"
#include "core/localize/localizer.h"
#include "core/localize/prepared_map_cache.h"
#include "server/cluster/cluster_node.h"
#include "server/cluster/forwarder.h"
#include "server/descriptor_cache.h"
#include "server/map_store.h"
#include "server/recent_fixes.h"

namespace lmd::server {

// StreamInsertMaps reads its messages as bytes (stream_insert.h).
class LmdServiceImpl final : public v1::LmdService::WithRawCallbackMethod_StreamInsertMaps<v1::LmdService::CallbackService> {
 public:
  // `store`, `runner` and `metrics` must outlive the service.
  LmdServiceImpl(const ServerConfig& config, MapStore* store, CallRunner* runner, CallMetrics* metrics);

  grpc::ServerUnaryReactor* InsertMaps(grpc::CallbackServerContext* context, const v1::InsertMapsRequest* request,
                                       v1::InsertMapsResponse* response) override;
  grpc::ServerReadReactor<grpc::ByteBuffer>* StreamInsertMaps(grpc::CallbackServerContext* context,
                                                              grpc::ByteBuffer* response) override;
  grpc::ServerUnaryReactor* GetMap(grpc::CallbackServerContext* context, const v1::GetMapRequest* request,
                                   v1::GetMapResponse* response) override;
  grpc::ServerUnaryReactor* DeleteMap(grpc::CallbackServerContext* context, const v1::DeleteMapRequest* request,
                                      v1::DeleteMapResponse* response) override;
  grpc::ServerUnaryReactor* ListMaps(grpc::CallbackServerContext* context, const v1::ListMapsRequest* request,
                                     v1::ListMapsResponse* response) override;
  grpc::ServerUnaryReactor* ListCollections(grpc::CallbackServerContext* context,
                                            const v1::ListCollectionsRequest* request,
                                            v1::ListCollectionsResponse* response) override;
  grpc::ServerUnaryReactor* Stats(grpc::CallbackServerContext* context, const v1::StatsRequest* request,
                                  v1::StatsResponse* response) override;
  grpc::ServerUnaryReactor* Backup(grpc::CallbackServerContext* context, const v1::BackupRequest* request,
                                   v1::BackupResponse* response) override;
  grpc::ServerUnaryReactor* Retrieve(grpc::CallbackServerContext* context, const v1::RetrieveRequest* request,
                                     v1::RetrieveResponse* response) override;
  grpc::ServerUnaryReactor* DetectChanges(grpc::CallbackServerContext* context,
                                          const v1::DetectChangesRequest* request,
                                          v1::DetectChangesResponse* response) override;
  grpc::ServerUnaryReactor* Cluster(grpc::CallbackServerContext* context, const v1::ClusterRequest* request,
                                    v1::ClusterResponse* response) override;
  grpc::ServerUnaryReactor* SetReplication(grpc::CallbackServerContext* context,
                                           const v1::SetReplicationRequest* request,
                                           v1::SetReplicationResponse* response) override;

  // In a cluster (server/cluster): calls on collections this node does not
  // serve are forwarded, and writes are replicated. `node` outlives the service.
  void SetCluster(cluster::ClusterNode* node) { cluster_ = node; }

  // Validates and stores one batch (also used per message by the stream),
  // once per non-empty `request_id` (InsertMapsRequest.request_id).
  Status Insert(std::vector<const v1::InsertMapRequest*> requests, size_t first_index,
                const std::string& request_id, v1::InsertMapsResponse* response);

  const ServerConfig& config() const { return config_; }

 private:
  // In a cluster, when another node serves `collection` (a write: its
  // primary; a read: any in-sync copy): the call forwarded there, with its
  // status. Nothing when the call is served here (always, without a cluster).
  // A write to a collection not placed yet places it only when `create`.
  template <typename Request, typename Response>
  std::optional<Status> ServedElsewhere(bool write, const std::string& collection,
                                        const grpc::CallbackServerContext* context,
                                        grpc::Status (v1::LmdService::Stub::*method)(grpc::ClientContext*,
                                                                                    const Request&, Response*),
                                        const Request& request, Response* response, bool create = true) {
    if (cluster_ == nullptr || (!write && cluster::WantsLocal(context))) return std::nullopt;
    Result<cluster::ClusterNode::Route> route =
        write ? cluster_->ForWrite(collection, create) : cluster_->ForRead(collection);
    if (!route.ok()) return route.status();
    if (route->here) return std::nullopt;
    return cluster::Forward(cluster_->ChannelTo(route->address), context, method, request, response);
  }

  // What lmdd computes from `map` (the default method's preparation, and
  // the paper's descriptor when `with_lmd`), from the cache when the same map
  // was seen recently; `key` (if not null) receives its content key.
  std::shared_ptr<const DescribedMap> Describe(const v1::LocalMap& map, bool with_lmd,
                                               DescriptorCache::Key* key = nullptr) const;

  // A query: validated, described, and answered against its collection.
  struct Query {
    std::shared_ptr<const DescribedMap> described;
    // METHOD_DEFAULT: the localisation, and the map id of each of its hits
    // (empty where the map was deleted meanwhile).
    Localization localization;
    std::vector<std::string> hit_ids;
    std::vector<StoreHit> paper_hits;  // paper methods: the LMD index's ranking
    bool reduced_depth = false;        // answered at the busy depth (config.h busy_*)
  };
  // What Retrieve and DetectChanges ask alike.
  struct QueryRequest {
    const std::string* collection;
    const v1::LocalMap* map;
    uint32_t top_k = 0;
    v1::Method method = v1::METHOD_DEFAULT;
    const google::protobuf::RepeatedPtrField<std::string>* exclude;
    uint32_t verify_candidates = 0;  // 0: the server's, reduced while the server is busy
    const v1::Prior* prior = nullptr;  // null: none
    const google::protobuf::RepeatedPtrField<v1::SequenceMap>* sequence;
    bool with_changes = false;  // the default method's change masks too
  };
  template <typename Request>
  static QueryRequest QueryOf(const Request& request, bool with_changes);
  // Maps whose id is in `exclude` are left out of the hits. Cancelled once
  // `context` is, DEADLINE_EXCEEDED past config max_query_seconds (both
  // polled during scan matches).
  Result<Query> RunQuery(const QueryRequest& request, grpc::CallbackServerContext* context) const;
  // True when `map_id`'s anchor was given (a pose_hint), not derived by lmdd.
  bool AnchorIsGiven(const std::string& collection, const std::string& map_id) const;
  // The default method's answer to `request` (prior, sequence or global),
  // given up (an incomplete answer) once `stop` returns true.
  Result<Localization> Localise(const QueryRequest& request, const LocalQuery& query, const LocalizeOptions& options,
                                const std::function<bool()>& stop) const;
  // The wire form of a hit: of the default method, and of a paper method
  // (with the pose the planned viewpoints imply, except for BoW).
  v1::MapHit DefaultWireHit(const std::string& collection, const LocalizedHit& hit, const std::string& map_id,
                            int rank) const;
  v1::MapHit PaperWireHit(const std::string& collection, const Query& query, const StoreHit& hit, size_t rank,
                          const Lmd* db, v1::Method method) const;

 public:
  double uptime_s() const;
  const PreparedMapCache& prepared_maps() const { return prepared_; }

 private:
  const ServerConfig config_;
  MapStore* const store_;
  CallRunner* const runner_;
  CallMetrics* const metrics_;
  const std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  mutable DescriptorCache cache_;
  mutable PreparedMapCache prepared_;
  mutable RecentFixes fixes_;
  cluster::ClusterNode* cluster_ = nullptr;
};

}  // namespace lmd::server
