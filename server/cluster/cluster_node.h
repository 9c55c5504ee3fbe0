// ClusterNode: one lmdd's part in a cluster of lmdd nodes that keep every
// collection on several nodes (deploy/README.md, "Replicated collections").
//
// etcd holds the cluster's state; nodes agree through it only:
//   <prefix>/nodes/<id>        NodeRecord, on the node's lease (gone when it stops renewing)
//   <prefix>/placement/<name>  Placement of a collection, changed by compare-and-swap only
//   <prefix>/controller        the elected controller's id, on its lease
// A write goes to the collection's primary, which applies it (one RocksDB
// batch, with the write's number) and sends it to every other in-sync copy;
// the client is acknowledged once all of them wrote it. A copy that does not
// answer in time is taken out of the in-sync set (compare-and-swap) before
// the acknowledgement, and catches up later. The controller promotes an
// in-sync copy (epoch + 1) when a primary's lease expires; copies refuse
// writes of an older epoch, so a primary that was cut off cannot get a write
// acknowledged after its successor took over.
//
// Thread-safe. Its threads: the etcd lease keeper and watcher, one for
// registration and controller duties, one for catching up.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/channel.h>
#include <grpcpp/security/credentials.h>

#include "core/status.h"
#include "lmd/internal/cluster.grpc.pb.h"
#include "lmd/v1/lmd.pb.h"
#include "server/cluster/etcd_client.h"
#include "server/cluster/placement.h"
#include "server/cluster/replication_log.h"
#include "server/config.h"
#include "server/map_store.h"

namespace lmd::server::cluster {

class ClusterNode {
 public:
  // Connects to etcd (config.cluster_etcd), registers this node under a new
  // lease (waiting up to two lease TTLs for an earlier run's key to expire)
  // and starts following the cluster. InvalidArgument for bad settings;
  // Unavailable when etcd cannot be reached. `store` must outlive the node.
  // `on_ready` is called once, from the node's thread, when none of its
  // copies needs catching up any more (readiness: lmdd reports SERVING only
  // then).
  static Result<std::unique_ptr<ClusterNode>> Start(const ServerConfig& config, MapStore* store,
                                                    std::function<void()> on_ready);
  ~ClusterNode();
  ClusterNode(const ClusterNode&) = delete;
  ClusterNode& operator=(const ClusterNode&) = delete;

  // Leaves the cluster: revokes the lease, so that the node's primaries fail
  // over at once instead of after a TTL. Idempotent.
  void Stop();

  const std::string& node_id() const { return node_id_; }
  // on_ready has been called.
  bool ready() const { return ready_; }

  // Where a call on `collection` is served: here, or forwarded to `address`.
  struct Route {
    bool here = true;
    std::string address;
  };
  // Writes go to the primary. A collection without a placement gets one,
  // with this node as its primary, when `create` (inserts); else NotFound.
  // Unavailable while the primary is down (a copy is being promoted: retry).
  Result<Route> ForWrite(const std::string& collection, bool create = true);
  // Reads are served by any in-sync copy, else by the primary. A collection
  // with no placement is read here (the store answers NOT_FOUND).
  Result<Route> ForRead(const std::string& collection);

  // On the primary (ForWrite said here): the write applied here and on
  // every in-sync copy, as MapStore::InsertMaps / DeleteMap.
  Status Insert(const std::string& collection, std::vector<MapWrite>* maps, const InsertLimits& limits,
                std::vector<v1::MapMetadata>* evicted, const InsertRequestId* request = nullptr,
                bool* replayed = nullptr);
  Status Delete(const std::string& collection, const std::string& map_id);

  // The Replica service (replica_service.h).
  // A copy applies its primary's write. FailedPrecondition for a stale
  // epoch, a gap in the numbers, or a write that does not follow this copy's
  // own last one (it applied another primary's write of that number: it has
  // diverged); the primary then drops it from in-sync and it catches up.
  // Apply, Copy and Join refuse (FailedPrecondition) a node that indexes
  // otherwise (server/indexing.h's Fingerprint): such a copy could not
  // answer as its primary does, so it never joins.
  Status Apply(const internal::ApplyRequest& write, internal::ApplyResponse* response);
  internal::ReplicaStateResponse State(const std::string& collection) const;
  // On the primary: the collection from one snapshot, to a catching-up copy.
  Status Copy(const internal::CopyRequest& request, const std::function<bool(const internal::CopyChunk&)>& send);
  // On the primary: sends `request.node_id` the writes after its mark and
  // adds it to the in-sync set, with no write in between. FailedPrecondition
  // "copy needed" when the log cannot bring it up to date.
  Status Join(const internal::JoinRequest& request);

  // Nodes and placements as this node sees them, with each copy's lag.
  void Describe(v1::ClusterResponse* out) const;
  // Sets the copies wanted of a placed collection (NotFound if unplaced);
  // the controller then adds or removes copies. *out: the placement written.
  Status SetReplication(const std::string& collection, uint32_t copies, v1::ClusterPlacement* out);

  // The channel to another node (TLS with this node's certificate when lmdd
  // serves TLS), shared by every call there.
  std::shared_ptr<grpc::Channel> ChannelTo(const std::string& address) const;

 private:
  struct Placed {
    internal::Placement placement;
    int64_t revision = 0;  // of its etcd key: the compare-and-swap's expectation
  };
  // A collection this node is the primary of: writes are serialised here.
  // A collection's writes, one at a time: as its primary (and the log of
  // them), or as a copy applying them.
  struct Writer {
    std::mutex mu;
    bool log_started = false;  // guarded by mu
    uint64_t log_epoch = 0;    // guarded by mu: the epoch the log was started for
    ReplicationLog log;        // guarded by mu
    explicit Writer(size_t bytes) : log(bytes) {}
  };

  ClusterNode(const ServerConfig& config, MapStore* store, std::unique_ptr<EtcdClient> etcd);
  // The placement's copies and the copies it wants (no progress: Describe asks the nodes).
  void DescribePlacement(const std::string& collection, const internal::Placement& p,
                         v1::ClusterPlacement* out) const;
  Status Register();
  void OnWatch(const WatchBatch& batch);
  void LeaveInSyncSets();
  // Registers the catch-up call in flight (null: none), for Stop to cancel;
  // false when stopping.
  bool Track(grpc::ClientContext* call);
  void Maintain();
  void CatchUpLoop();
  void RunController();
  void CatchUpAll();
  void DropCopiesPlacedElsewhere();
  Status CatchUp(const std::string& collection, const internal::Placement& placement);
  Status CopyFrom(const std::string& collection, const std::string& address, ReplicationMark* mark);

  // This node's placement of `collection` if it is its primary (and holds its
  // lease); else Unavailable.
  Result<internal::Placement> PlacementAsPrimary(const std::string& collection) const;
  // The log of a writer (held) made valid for `epoch`; the store's mark.
  ReplicationMark StartLog(Writer* writer, const std::string& collection, uint64_t epoch);
  // A write as the primary: numbered, applied here by `apply` (which fills
  // the copies' request), sent to the in-sync copies, logged.
  Status WriteAsPrimary(const std::string& collection,
                        const std::function<Status(const ReplicationMark&, internal::ApplyRequest*)>& apply);
  // The placement as etcd holds it now, into the cache unless it is older.
  void RefreshPlacement(const std::string& collection);
  // The write as the primary applied it, on every other in-sync copy; takes
  // the copies that failed out of the in-sync set. Called holding the writer.
  Status Replicate(const std::string& collection, const internal::Placement& placement,
                   const internal::ApplyRequest& write);
  // Compare-and-swap of a placement by `change`, retried on conflicts while
  // `still` holds for the current one; the placement written.
  Result<internal::Placement> ChangePlacement(
      const std::string& collection, const std::function<bool(const internal::Placement&)>& still,
      const std::function<void(internal::Placement*)>& change);
  Writer& WriterOf(const std::string& collection);
  std::shared_ptr<internal::Replica::Stub> StubFor(const std::string& address) const;
  std::string AddressOf(const std::string& node) const;  // guarded by mu_ (caller holds it)
  // A call to another node: its deadline and this node's token.
  void Prepare(grpc::ClientContext* context, int timeout_ms) const;
  std::string Key(const std::string& kind, const std::string& name) const { return prefix_ + "/" + kind + "/" + name; }

  const ServerConfig config_;
  MapStore* const store_;
  const std::string node_id_;
  const std::string prefix_;
  std::unique_ptr<EtcdClient> etcd_;
  std::string token_;  // sent on calls to other nodes (cluster_token_file); set once at start
  std::function<void()> on_ready_;  // set once at start
  std::atomic<bool> ready_{false};

  mutable std::mutex mu_;
  // State below is guarded by mu_.
  LiveNodes live_;
  // Nodes gone from live_, with when: the controller copies their
  // collections elsewhere only after cluster_replace_after_s.
  std::map<std::string, std::pair<internal::NodeRecord, std::chrono::steady_clock::time_point>> lost_;
  std::map<std::string, Placed> placements_;
  bool fenced_ = true;              // no lease: serves no writes as a primary
  bool controller_ = false;
  // A controller repairs placements only once its node has been up a lease
  // TTL: nodes starting together are not taken for dead (a controller taking
  // over from a dead one acts at once).
  const std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  std::unique_ptr<LeaseKeeper> keeper_;
  int64_t lease_id_ = 0;
  bool stopping_ = false;
  grpc::ClientContext* catch_up_call_ = nullptr;
  bool wake_ = false;
  std::condition_variable wake_cv_;
  std::map<std::string, std::unique_ptr<Writer>> writers_;
  mutable std::map<std::string, std::shared_ptr<grpc::Channel>> channels_;
  std::shared_ptr<grpc::ChannelCredentials> credentials_;  // set once at start
  std::string tls_server_name_;                            // set once at start

  std::unique_ptr<PrefixWatcher> watcher_;
  std::thread maintenance_;  // registration and controller duties
  std::thread catching_up_;  // this node's copies that are not in sync
};

}  // namespace lmd::server::cluster
