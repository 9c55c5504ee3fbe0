#include "server/cluster/cluster_node.h"

#include <fstream>
#include <future>
#include <sstream>
#include <unordered_set>

#include <grpcpp/client_context.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <spdlog/spdlog.h>

#include "core/describe/lmd_codec.h"
#include "core/place/place_features.h"
#include "core/util/host_port.h"
#include "core/util/split.h"
#include "server/grpc_status.h"
#include "server/indexing.h"

namespace lmd::server::cluster {
namespace {

using Clock = std::chrono::steady_clock;

constexpr size_t kCopyChunkMaps = 64;
constexpr auto kMaintainEvery = std::chrono::milliseconds(250);
constexpr int kCatchUpTimeoutMs = 600000;  // a whole collection's copy

// A node's copy is of use only to nodes that index as it does (Fingerprint):
// `theirs` (empty: a node older than the check) against `ours`.
Status SameIndexing(const std::string& theirs, const std::string& ours, const std::string& whose) {
  if (theirs.empty() || theirs == ours) return Status::Ok();
  return Status::FailedPrecondition("other indexing settings: " + whose + " uses (" + theirs + "), this node (" + ours +
                                    "); nodes of one cluster must be set alike");
}


// A stored map as a copy receives it, and back.
internal::ReplicatedMap ToReplicated(const MapWrite& write) {
  internal::ReplicatedMap out;
  *out.mutable_map() = write.map;
  out.set_lmd(EncodeLmd(write.lmd));
  out.set_place_features(EncodePlaceFeatures(write.place));
  return out;
}
Result<MapWrite> FromReplicated(const internal::ReplicatedMap& in) {
  MapWrite write;
  write.map = in.map();
  Result<Lmd> lmd = DecodeLmd(in.lmd());
  if (!lmd.ok()) return Status::InvalidArgument("replicated map " + in.map().metadata().map_id() + ": " + lmd.status().message());
  Result<PlaceFeatures> place = DecodePlaceFeatures(in.place_features());
  if (!place.ok()) {
    return Status::InvalidArgument("replicated map " + in.map().metadata().map_id() + ": " + place.status().message());
  }
  write.lmd = std::move(lmd).value();
  write.place = std::move(place).value();
  return write;
}

}  // namespace

void ClusterNode::Prepare(grpc::ClientContext* context, int timeout_ms) const {
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(timeout_ms));
  if (!token_.empty()) context->AddMetadata("authorization", "Bearer " + token_);
}

ClusterNode::ClusterNode(const ServerConfig& config, MapStore* store, std::unique_ptr<EtcdClient> etcd)
    : config_(config),
      store_(store),
      node_id_(!config.cluster_node_id.empty() ? config.cluster_node_id
                                               : (!config.cluster_advertise.empty() ? config.cluster_advertise
                                                                                    : config.listen)),
      prefix_(config.cluster_prefix),
      etcd_(std::move(etcd)) {}

Result<std::unique_ptr<ClusterNode>> ClusterNode::Start(const ServerConfig& config, MapStore* store,
                                                        std::function<void()> on_ready) {
  EtcdClientOptions options;
  options.endpoints = SplitCommas(config.cluster_etcd);
  if (options.endpoints.empty()) return Status::InvalidArgument("cluster_etcd names no etcd endpoint");
  for (const std::string& endpoint : options.endpoints) {
    const Result<HostPort> parsed = ParseHostPort(endpoint, 1, "cluster_etcd endpoint");
    if (!parsed.ok()) return parsed.status();
  }
  if (!config.cluster_advertise.empty()) {
    const Result<HostPort> parsed = ParseHostPort(config.cluster_advertise, 1, "cluster_advertise");
    if (!parsed.ok()) return parsed.status();
  }
  if (config.cluster_prefix.empty() || config.cluster_prefix.back() == '/') {
    return Status::InvalidArgument("cluster_prefix must be non-empty and not end with '/'");
  }
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!config.tls_cert_file.empty()) {  // nodes speak TLS to each other, with their own certificate
    auto read = [](const std::string& path, std::string* out) {
      std::ifstream in(path);
      std::ostringstream text;
      text << in.rdbuf();
      *out = text.str();
      return static_cast<bool>(in) && !out->empty();
    };
    grpc::SslCredentialsOptions tls;
    const std::string ca = !config.cluster_tls_ca_file.empty() ? config.cluster_tls_ca_file : config.tls_client_ca_file;
    if (ca.empty()) return Status::InvalidArgument("with TLS, a cluster needs cluster_tls_ca_file (the CA of the nodes' certificates)");
    if (!read(ca, &tls.pem_root_certs) || !read(config.tls_cert_file, &tls.pem_cert_chain) ||
        !read(config.tls_key_file, &tls.pem_private_key)) {
      return Status::InvalidArgument("cannot read the cluster's TLS files (" + ca + ", tls_cert_file, tls_key_file)");
    }
    credentials = grpc::SslCredentials(tls);
  }
  std::string token;
  if (!config.cluster_token_file.empty()) {
    std::ifstream in(config.cluster_token_file);
    if (!in || !std::getline(in, token) || token.empty()) {
      return Status::InvalidArgument("cannot read a token from cluster_token_file " + config.cluster_token_file);
    }
  }
  Result<std::unique_ptr<EtcdClient>> etcd = EtcdClient::Connect(options);
  if (!etcd.ok()) return Status::Unavailable("cannot reach etcd: " + etcd.status().message());
  std::unique_ptr<ClusterNode> node(new ClusterNode(config, store, std::move(etcd).value()));
  node->token_ = token;
  node->credentials_ = credentials;
  node->tls_server_name_ = config.cluster_tls_server_name;
  node->on_ready_ = std::move(on_ready);
  Status registered = node->Register();
  if (!registered.ok()) return registered;
  Result<EtcdRange> state = node->etcd_->GetPrefix(node->prefix_ + "/");
  if (!state.ok()) return state.status();
  WatchBatch initial;
  initial.reset = true;
  initial.revision = state->revision;
  for (const EtcdKeyValue& kv : state->kvs) initial.events.push_back({WatchEvent::Type::kPut, kv.key, kv.value, kv.mod_revision});
  node->OnWatch(initial);
  node->LeaveInSyncSets();
  ClusterNode* self = node.get();
  node->watcher_ = node->etcd_->WatchPrefix(node->prefix_ + "/", state->revision + 1,
                                            [self](const WatchBatch& batch) { self->OnWatch(batch); });
  node->maintenance_ = std::thread([self] { self->Maintain(); });
  node->catching_up_ = std::thread([self] { self->CatchUpLoop(); });
  spdlog::info("cluster: node {} joined (etcd {})", node->node_id_, config.cluster_etcd);
  return node;
}

ClusterNode::~ClusterNode() { Stop(); }

void ClusterNode::Stop() {
  int64_t lease = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return;
    stopping_ = true;
    fenced_ = true;
    lease = lease_id_;
    if (catch_up_call_ != nullptr) catch_up_call_->TryCancel();
  }
  wake_cv_.notify_all();
  // The lease first: this node's primaries move now, not once the threads
  // below have finished what they are doing.
  if (lease != 0) {
    Status revoked = etcd_->RevokeLease(lease);
    if (!revoked.ok()) spdlog::warn("cluster: revoking the lease of {}: {}", node_id_, revoked.ToString());
  }
  if (maintenance_.joinable()) maintenance_.join();
  if (catching_up_.joinable()) catching_up_.join();
  watcher_.reset();
  std::unique_ptr<LeaseKeeper> keeper;
  {
    std::lock_guard<std::mutex> lock(mu_);
    keeper = std::move(keeper_);
    if (lease_id_ != lease && lease_id_ != 0) lease = lease_id_;  // registered again meanwhile
    else lease = 0;
  }
  keeper.reset();
  if (lease != 0) etcd_->RevokeLease(lease);
}

// A new lease and this node's key on it. The key of an earlier run of the
// same node (killed, its lease not yet expired) is waited out, so that the
// controller sees the node die and fails its primaries over first.
Status ClusterNode::Register() {
  Result<EtcdLease> lease = etcd_->GrantLease(config_.cluster_lease_ttl_s);
  if (!lease.ok()) return lease.status();
  internal::NodeRecord record;
  record.set_node_id(node_id_);
  record.set_address(config_.cluster_advertise.empty() ? config_.listen : config_.cluster_advertise);
  record.set_zone(config_.cluster_zone);
  const auto give_up = Clock::now() + std::chrono::seconds(2 * lease->ttl_seconds + 2);
  for (;;) {
    Result<bool> put = etcd_->PutIfRevision(Key("nodes", node_id_), record.SerializeAsString(), 0, lease->id);
    if (!put.ok()) return put.status();
    if (*put) break;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stopping_) return Status::Cancelled("node " + node_id_ + " is stopping");
    }
    if (Clock::now() > give_up) {
      return Status::FailedPrecondition("node id '" + node_id_ + "' is registered by a live node (cluster_node_id)");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::unique_ptr<LeaseKeeper> keeper = etcd_->KeepAlive(*lease, [this](const Status& why) {
    spdlog::warn("cluster: node {} lost its lease ({}): no writes as a primary until it registers again", node_id_,
                 why.ToString());
    {
      std::lock_guard<std::mutex> lock(mu_);
      fenced_ = true;
      controller_ = false;
      wake_ = true;
    }
    wake_cv_.notify_all();
  });
  std::lock_guard<std::mutex> lock(mu_);
  lease_id_ = lease->id;
  keeper_ = std::move(keeper);
  fenced_ = stopping_;
  return Status::Ok();
}

void ClusterNode::OnWatch(const WatchBatch& batch) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    const LiveNodes before = live_;
    if (batch.reset) {
      live_.clear();
      placements_.clear();
    }
    const std::string nodes = prefix_ + "/nodes/", placement = prefix_ + "/placement/";
    for (const WatchEvent& e : batch.events) {
      const bool put = e.type == WatchEvent::Type::kPut;
      if (e.key.rfind(nodes, 0) == 0) {
        const std::string id = e.key.substr(nodes.size());
        internal::NodeRecord record;
        if (put && record.ParseFromString(e.value)) live_[id] = record;
        if (!put) live_.erase(id);
      } else if (e.key.rfind(placement, 0) == 0) {
        const std::string name = e.key.substr(placement.size());
        Placed placed;
        if (put && placed.placement.ParseFromString(e.value)) {
          placed.revision = e.mod_revision;
          const auto it = placements_.find(name);  // a CAS of this node's may have cached a newer one
          if (it == placements_.end() || it->second.revision <= placed.revision) placements_[name] = placed;
        }
        if (!put) placements_.erase(name);
      } else if (e.key == prefix_ + "/controller" && !put) {
        controller_ = false;
      }
    }
    const auto now = Clock::now();
    for (const auto& [id, record] : before) {
      if (live_.count(id) == 0) lost_.emplace(id, std::make_pair(record, now));
    }
    for (const auto& [id, record] : live_) lost_.erase(id);
    wake_ = true;
  }
  wake_cv_.notify_all();
}

void ClusterNode::Maintain() {
  for (;;) {
    bool fenced = false;
    {
      std::unique_lock<std::mutex> lock(mu_);
      wake_cv_.wait_for(lock, kMaintainEvery, [&] { return stopping_ || wake_; });
      if (stopping_) return;
      wake_ = false;
      fenced = fenced_;
    }
    if (fenced) {
      std::unique_ptr<LeaseKeeper> old;
      {
        std::lock_guard<std::mutex> lock(mu_);
        old = std::move(keeper_);
      }
      old.reset();
      Status again = Register();
      if (!again.ok()) spdlog::warn("cluster: registering {} again: {}", node_id_, again.ToString());
      continue;
    }
    RunController();
  }
}

// Apart from the controller's thread: copying a large collection takes
// minutes, and failovers must not wait for it.
void ClusterNode::CatchUpLoop() {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      wake_cv_.wait_for(lock, kMaintainEvery, [&] { return stopping_; });
      if (stopping_) return;
      if (fenced_) continue;
    }
    CatchUpAll();
    DropCopiesPlacedElsewhere();
  }
}

// The controller: elected by creating its key on this node's lease; repairs
// placements (placement.h), once its node has been up a lease TTL.
void ClusterNode::RunController() {
  int64_t lease = 0;
  bool controller = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    lease = lease_id_;
    controller = controller_;
  }
  if (!controller) {
    Result<bool> elected = etcd_->PutIfRevision(prefix_ + "/controller", node_id_, 0, lease);
    if (!elected.ok() || !*elected) {
      Result<std::optional<EtcdValue>> holder = etcd_->Get(prefix_ + "/controller");
      if (!holder.ok() || !*holder || (*holder)->value != node_id_ || (*holder)->lease != lease) return;
    }
    std::lock_guard<std::mutex> lock(mu_);
    controller_ = true;
    spdlog::info("cluster: {} is the controller", node_id_);
    return;
  }
  std::vector<std::pair<std::string, Placed>> repairs;
  {
    std::lock_guard<std::mutex> lock(mu_);
    const auto now = Clock::now();
    if (now - started_ < std::chrono::seconds(config_.cluster_lease_ttl_s)) return;
    LiveNodes returning;  // gone so recently that their copies are not yet made elsewhere
    for (auto it = lost_.begin(); it != lost_.end();) {
      if (now - it->second.second >= std::chrono::seconds(config_.cluster_replace_after_s)) {
        it = lost_.erase(it);
      } else {
        returning.emplace(it->first, it->second.first);
        ++it;
      }
    }
    for (const auto& [name, placed] : placements_) {
      std::optional<internal::Placement> next =
          Repaired(name, placed.placement, live_, config_.cluster_replication_factor, returning);
      if (next) repairs.push_back({name, Placed{*next, placed.revision}});
    }
  }
  for (const auto& [name, next] : repairs) {
    Result<bool> swapped = etcd_->PutIfRevision(Key("placement", name), next.placement.SerializeAsString(), next.revision);
    if (swapped.ok() && *swapped) {
      spdlog::info("cluster: placement of '{}': epoch {}, primary {}, {} in sync of {}", name, next.placement.epoch(),
                   next.placement.primary(), next.placement.in_sync_size(), next.placement.replicas_size());
    }
  }
}

ClusterNode::Writer& ClusterNode::WriterOf(const std::string& collection) {
  std::lock_guard<std::mutex> lock(mu_);
  std::unique_ptr<Writer>& writer = writers_[collection];
  if (!writer) writer = std::make_unique<Writer>(size_t{config_.cluster_log_mb} << 20);
  return *writer;
}

std::string ClusterNode::AddressOf(const std::string& node) const {
  const auto it = live_.find(node);
  return it == live_.end() ? std::string() : it->second.address();
}

std::shared_ptr<grpc::Channel> ClusterNode::ChannelTo(const std::string& address) const {
  std::lock_guard<std::mutex> lock(mu_);
  std::shared_ptr<grpc::Channel>& channel = channels_[address];
  if (!channel) {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);  // a copied map is as large as lmdd accepts
    args.SetMaxSendMessageSize(-1);
    if (!tls_server_name_.empty()) args.SetSslTargetNameOverride(tls_server_name_);
    channel = grpc::CreateCustomChannel(address, credentials_, args);
  }
  return channel;
}

std::shared_ptr<internal::Replica::Stub> ClusterNode::StubFor(const std::string& address) const {
  return internal::Replica::NewStub(ChannelTo(address));
}

Result<ClusterNode::Route> ClusterNode::ForWrite(const std::string& collection, bool create) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    internal::Placement fresh;
    {
      std::lock_guard<std::mutex> lock(mu_);
      const auto it = placements_.find(collection);
      if (it != placements_.end()) {
        const internal::Placement& p = it->second.placement;
        if (p.primary() == node_id_) {
          if (fenced_) return Status::Unavailable("node " + node_id_ + " lost its etcd lease; retry");
          return Route{};
        }
        const std::string address = AddressOf(p.primary());
        if (address.empty()) {
          return Status::Unavailable("the primary of collection '" + collection + "' (" + p.primary() +
                                     ") is down; a copy is being promoted: retry");
        }
        return Route{false, address};
      }
      if (!create) return Status::NotFound("unknown collection '" + collection + "'");
      if (fenced_) return Status::Unavailable("node " + node_id_ + " lost its etcd lease; retry");
      // Maps this node already holds (a single node's store joining a
      // cluster): the other copies must copy them before they are in sync.
      fresh = NewPlacement(collection, live_, node_id_, config_.cluster_replication_factor,
                           /*others_in_sync=*/!store_->HasCollection(collection));
    }
    Result<bool> created = etcd_->PutIfRevision(Key("placement", collection), fresh.SerializeAsString(), 0);
    if (!created.ok()) return Status::Unavailable("placing collection '" + collection + "': " + created.status().message());
    RefreshPlacement(collection);
    if (*created) spdlog::info("cluster: collection '{}' placed on {} copies, primary {}", collection, fresh.replicas_size(), node_id_);
  }
  return Status::Unavailable("the placement of collection '" + collection + "' keeps changing; retry");
}

Result<ClusterNode::Route> ClusterNode::ForRead(const std::string& collection) {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = placements_.find(collection);
  if (it == placements_.end()) return Route{};
  const internal::Placement& p = it->second.placement;
  if (InSync(p, node_id_) && !fenced_) return Route{};
  const std::string address = AddressOf(p.primary());
  if (address.empty()) {
    return Status::Unavailable("no copy of collection '" + collection + "' is reachable from " + node_id_ + "; retry");
  }
  return Route{false, address};
}

ReplicationMark ClusterNode::StartLog(Writer* writer, const std::string& collection, uint64_t epoch) {
  const ReplicationMark mark = store_->MarkOf(collection);
  // A log from an earlier term as primary, or one that missed writes taken
  // as a follower since, would misjudge a joining copy: start anew.
  if (!writer->log_started || writer->log_epoch != epoch || writer->log.last_seq() != mark.seq) {
    writer->log.Reset(mark.epoch, mark.seq);
    writer->log_started = true;
    writer->log_epoch = epoch;
  }
  return mark;
}

Result<internal::Placement> ClusterNode::PlacementAsPrimary(const std::string& collection) const {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = placements_.find(collection);
  if (fenced_ || it == placements_.end() || it->second.placement.primary() != node_id_) {
    return Status::Unavailable("node " + node_id_ + " is not the primary of collection '" + collection + "'; retry");
  }
  return it->second.placement;
}

Status ClusterNode::WriteAsPrimary(const std::string& collection,
                                   const std::function<Status(const ReplicationMark&, internal::ApplyRequest*)>& apply) {
  Writer& writer = WriterOf(collection);
  std::lock_guard<std::mutex> write_lock(writer.mu);
  Result<internal::Placement> placement = PlacementAsPrimary(collection);
  if (!placement.ok()) return placement.status();
  const ReplicationMark last = StartLog(&writer, collection, placement->epoch());
  const ReplicationMark mark{placement->epoch(), last.seq + 1};
  internal::ApplyRequest write;
  write.set_collection(collection);
  write.set_epoch(mark.epoch);
  write.set_seq(mark.seq);
  write.set_prev_epoch(last.epoch);
  write.set_indexing(Fingerprint(store_->indexing()));
  Status applied = apply(mark, &write);
  if (!applied.ok()) return applied;
  if (write.maps_size() == 0 && write.deleted_map_ids_size() == 0) return Status::Ok();  // nothing written
  Status copied = Replicate(collection, *placement, write);
  writer.log.Append(std::move(write));
  return copied;
}

Status ClusterNode::Insert(const std::string& collection, std::vector<MapWrite>* maps, const InsertLimits& limits,
                           std::vector<v1::MapMetadata>* evicted, const InsertRequestId* request, bool* replayed) {
  return WriteAsPrimary(collection, [&](const ReplicationMark& mark, internal::ApplyRequest* write) {
    std::vector<v1::MapMetadata> gone;
    bool answered = false;
    Status stored = store_->InsertMaps(maps, limits, &gone, &mark, request, &answered);
    if (replayed != nullptr) *replayed = answered;
    if (!stored.ok() || answered) return stored;  // a replay writes nothing: no copy to make
    if (request != nullptr) {
      write->set_request_id(request->id);
      write->set_request_fingerprint(request->fingerprint);
    }
    for (const MapWrite& m : *maps) *write->add_maps() = ToReplicated(m);
    for (const v1::MapMetadata& meta : gone) write->add_deleted_map_ids(meta.map_id());
    if (evicted != nullptr) evicted->insert(evicted->end(), gone.begin(), gone.end());
    return Status::Ok();
  });
}

Status ClusterNode::Delete(const std::string& collection, const std::string& map_id) {
  return WriteAsPrimary(collection, [&](const ReplicationMark& mark, internal::ApplyRequest* write) {
    Status deleted = store_->DeleteMap(collection, map_id, &mark);
    if (deleted.ok()) write->add_deleted_map_ids(map_id);
    return deleted;
  });
}

Status ClusterNode::Replicate(const std::string& collection, const internal::Placement& placement,
                              const internal::ApplyRequest& write) {
  std::vector<std::pair<std::string, std::future<grpc::Status>>> calls;
  for (const std::string& node : placement.in_sync()) {
    if (node == node_id_) continue;
    std::string address;
    {
      std::lock_guard<std::mutex> lock(mu_);
      address = AddressOf(node);
    }
    if (address.empty()) {
      std::promise<grpc::Status> down;
      down.set_value(grpc::Status(grpc::StatusCode::UNAVAILABLE, "node is down"));
      calls.push_back({node, down.get_future()});
      continue;
    }
    std::shared_ptr<internal::Replica::Stub> stub = StubFor(address);
    calls.push_back({node, std::async(std::launch::async, [this, stub, &write] {
                       grpc::ClientContext context;
                       Prepare(&context, static_cast<int>(config_.cluster_replicate_timeout_ms));
                       internal::ApplyResponse response;
                       return stub->Apply(&context, write, &response);
                     })});
  }
  std::set<std::string> failed;
  for (auto& [node, call] : calls) {
    const grpc::Status status = call.get();
    if (!status.ok()) {
      spdlog::warn("cluster: copy {} of '{}' did not take write {}: {}", node, collection, write.seq(),
                   status.error_message());
      failed.insert(node);
    }
  }
  if (failed.empty()) return Status::Ok();
  Result<internal::Placement> changed = ChangePlacement(
      collection,
      [&](const internal::Placement& p) { return p.primary() == node_id_ && p.epoch() == placement.epoch(); },
      [&](internal::Placement* p) {
        auto* in_sync = p->mutable_in_sync();
        in_sync->erase(std::remove_if(in_sync->begin(), in_sync->end(),
                                      [&](const std::string& id) { return failed.count(id) != 0; }),
                       in_sync->end());
      });
  if (!changed.ok()) {
    return Status::Unavailable("write " + std::to_string(write.seq()) + " of '" + collection +
                               "' not acknowledged: " + changed.status().message());
  }
  return Status::Ok();
}

Result<internal::Placement> ClusterNode::ChangePlacement(
    const std::string& collection, const std::function<bool(const internal::Placement&)>& still,
    const std::function<void(internal::Placement*)>& change) {
  for (int attempt = 0; attempt < 10; ++attempt) {
    Result<std::optional<EtcdValue>> now = etcd_->Get(Key("placement", collection));
    if (!now.ok()) return now.status();
    internal::Placement p;
    if (!*now || !p.ParseFromString((*now)->value)) return Status::NotFound("collection '" + collection + "' is not placed");
    if (!still(p)) return Status::FailedPrecondition("the placement of '" + collection + "' changed (a new primary)");
    change(&p);
    Result<bool> swapped = etcd_->PutIfRevision(Key("placement", collection), p.SerializeAsString(), (*now)->mod_revision);
    if (!swapped.ok()) return swapped.status();
    if (*swapped) {
      RefreshPlacement(collection);
      return p;
    }
  }
  return Status::Unavailable("the placement of '" + collection + "' keeps changing");
}

void ClusterNode::RefreshPlacement(const std::string& collection) {
  Result<std::optional<EtcdValue>> now = etcd_->Get(Key("placement", collection));
  if (!now.ok() || !*now) return;  // the watch brings it
  Placed placed;
  if (!placed.placement.ParseFromString((*now)->value)) return;
  placed.revision = (*now)->mod_revision;
  std::lock_guard<std::mutex> lock(mu_);
  Placed& cached = placements_[collection];
  if (placed.revision >= cached.revision) cached = placed;
}

Status ClusterNode::Apply(const internal::ApplyRequest& write, internal::ApplyResponse* response) {
  Status alike = SameIndexing(write.indexing(), Fingerprint(store_->indexing()), "the primary");
  if (!alike.ok()) return alike;
  Writer& writer = WriterOf(write.collection());  // one write of a collection at a time, here too
  std::lock_guard<std::mutex> write_lock(writer.mu);
  {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = placements_.find(write.collection());
    if (it != placements_.end() && write.epoch() < it->second.placement.epoch()) {
      return Status::FailedPrecondition("write of epoch " + std::to_string(write.epoch()) + " refused: '" +
                                        write.collection() + "' is at epoch " +
                                        std::to_string(it->second.placement.epoch()));
    }
  }
  const ReplicationMark last = store_->MarkOf(write.collection());
  response->set_applied_seq(last.seq);
  // Two primaries may both reach this copy for a moment (the old one cut off
  // before it learnt of its successor): a write is taken only on top of the
  // very write its primary made before it.
  if (write.epoch() < last.epoch) {
    return Status::FailedPrecondition("write of epoch " + std::to_string(write.epoch()) + " refused: this copy of '" +
                                      write.collection() + "' holds writes of epoch " + std::to_string(last.epoch));
  }
  if (write.seq() == last.seq && write.epoch() == last.epoch) return Status::Ok();  // a retry: applied already
  if (write.seq() != last.seq + 1 || write.prev_epoch() != last.epoch) {
    return Status::FailedPrecondition("write " + std::to_string(write.seq()) + " (epoch " +
                                      std::to_string(write.epoch()) + ") of '" + write.collection() +
                                      "' does not follow this copy's last, " + std::to_string(last.seq) + " (epoch " +
                                      std::to_string(last.epoch) + "): copy needed");
  }
  const ReplicationMark mark{write.epoch(), write.seq()};
  std::vector<MapWrite> maps;
  for (const internal::ReplicatedMap& m : write.maps()) {
    Result<MapWrite> map = FromReplicated(m);
    if (!map.ok()) return map.status();
    maps.push_back(std::move(map).value());
  }
  // Evictions arrive as deletions (this node's own cap is not applied): the
  // copy holds what its primary holds. Their mark comes last, so a crash in
  // between repeats the whole write (inserts replace, deletes of absent maps
  // are skipped).
  const bool deletes = write.deleted_map_ids_size() > 0;
  bool replayed = false;  // kept already (a repeated write): its mark is still to set
  if (!maps.empty()) {
    InsertLimits limits{~0u, 0, config_.insert_request_ids_kept};
    const InsertRequestId request{write.request_id(), write.request_fingerprint()};
    Status stored = store_->InsertMaps(&maps, limits, nullptr, deletes ? nullptr : &mark,
                                       write.request_id().empty() ? nullptr : &request, &replayed);
    if (!stored.ok()) return stored;
  }
  for (const std::string& id : write.deleted_map_ids()) {
    Status deleted = store_->DeleteMap(write.collection(), id);
    if (!deleted.ok() && deleted.code() != Status::Code::kNotFound) return deleted;
  }
  if (deletes || maps.empty() || replayed) {
    Status marked = store_->SetMark(write.collection(), mark);
    if (!marked.ok()) return marked;
  }
  response->set_applied_seq(write.seq());
  return Status::Ok();
}

internal::ReplicaStateResponse ClusterNode::State(const std::string& collection) const {
  internal::ReplicaStateResponse out;
  const ReplicationMark mark = store_->MarkOf(collection);
  out.set_epoch(mark.epoch);
  out.set_seq(mark.seq);
  for (const v1::CollectionInfo& info : store_->ListCollections()) {
    if (info.name() == collection) out.set_maps(info.maps());
  }
  return out;
}

Status ClusterNode::Copy(const internal::CopyRequest& request,
                         const std::function<bool(const internal::CopyChunk&)>& send) {
  Status alike = SameIndexing(request.indexing(), Fingerprint(store_->indexing()), "the copying node");
  if (!alike.ok()) return alike;
  const std::string& collection = request.collection();
  ReplicationMark mark;
  Status walked = store_->ForEachMap(
      collection, kCopyChunkMaps,
      [&](std::vector<StoredEntry>&& entries) {
        internal::CopyChunk chunk;
        for (StoredEntry& e : entries) {
          internal::ReplicatedMap* m = chunk.add_maps();
          *m->mutable_map() = std::move(e.map);
          m->set_lmd(e.indexed.lmd());
          m->set_place_features(e.indexed.place_features());
        }
        return send(chunk);
      },
      [&](std::vector<KeptRequest>&& requests) {
        internal::CopyChunk chunk;
        for (KeptRequest& r : requests) {
          internal::KeptRequest* kept = chunk.add_requests();
          kept->set_request_id(std::move(r.id));
          *kept->mutable_record() = std::move(r.record);
        }
        return send(chunk);
      },
      &mark);
  if (!walked.ok() && walked.code() != Status::Code::kNotFound) return walked;
  internal::CopyChunk last;
  last.set_last(true);
  last.set_epoch(mark.epoch);
  last.set_seq(mark.seq);
  if (!send(last)) return Status::Cancelled("the copy's receiver went away");
  return Status::Ok();
}

Status ClusterNode::Join(const internal::JoinRequest& request) {
  Status alike = SameIndexing(request.indexing(), Fingerprint(store_->indexing()), "node " + request.node_id());
  if (!alike.ok()) return alike;
  const std::string& collection = request.collection();
  Writer& writer = WriterOf(collection);
  std::lock_guard<std::mutex> write_lock(writer.mu);
  Result<internal::Placement> placement = PlacementAsPrimary(collection);
  if (!placement.ok()) return placement.status();
  std::string address;
  {
    std::lock_guard<std::mutex> lock(mu_);
    address = AddressOf(request.node_id());
  }
  if (address.empty()) return Status::Unavailable("node " + request.node_id() + " is not live");
  StartLog(&writer, collection, placement->epoch());
  std::optional<std::vector<internal::ApplyRequest>> missing = writer.log.After(request.epoch(), request.seq());
  if (!missing) return Status::FailedPrecondition("copy needed: the log does not bring its mark up to date");
  std::shared_ptr<internal::Replica::Stub> stub = StubFor(address);
  for (const internal::ApplyRequest& write : *missing) {
    grpc::ClientContext context;
    Prepare(&context, static_cast<int>(config_.cluster_replicate_timeout_ms));
    internal::ApplyResponse response;
    const grpc::Status sent = stub->Apply(&context, write, &response);
    if (sent.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
      return Status::FailedPrecondition("copy needed: " + sent.error_message());
    }
    if (!sent.ok()) return Status::Unavailable("sending write " + std::to_string(write.seq()) + ": " + sent.error_message());
  }
  // In sync in etcd and in this node's own view before the next write (which
  // waits for this lock), so that the next write goes to the new copy too.
  Result<internal::Placement> joined = ChangePlacement(
      collection, [&](const internal::Placement& p) { return p.primary() == node_id_; },
      [&](internal::Placement* p) {
        if (!InSync(*p, request.node_id())) p->add_in_sync(request.node_id());
      });
  if (!joined.ok()) return Status::Unavailable("adding it to the in-sync set: " + joined.status().message());
  spdlog::info("cluster: {} caught up on '{}' ({} writes sent) and is in sync", request.node_id(), collection,
               missing->size());
  return Status::Ok();
}

bool ClusterNode::Track(grpc::ClientContext* call) {
  std::lock_guard<std::mutex> lock(mu_);
  if (call != nullptr && stopping_) return false;
  catch_up_call_ = call;
  return true;
}

// A node that starts again may have lost writes its copies acknowledged (a
// disk replaced, a WAL not yet synced when the machine died): it leaves
// every in-sync set where another live copy is in sync, hands over its
// primaries to such a copy, and catches up like any returning copy.
void ClusterNode::LeaveInSyncSets() {
  std::vector<std::string> names;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& [name, placed] : placements_) {
      if (InSync(placed.placement, node_id_)) names.push_back(name);
    }
  }
  for (const std::string& name : names) {
    Result<internal::Placement> left = ChangePlacement(
        name,
        [&](const internal::Placement& p) {
          std::lock_guard<std::mutex> lock(mu_);
          return std::any_of(p.in_sync().begin(), p.in_sync().end(),
                             [&](const std::string& id) { return id != node_id_ && live_.count(id) != 0; });
        },
        [&](internal::Placement* p) {
          std::vector<std::string> kept;
          for (const std::string& id : p->in_sync()) {
            if (id != node_id_) kept.push_back(id);
          }
          if (p->primary() == node_id_) {  // `still` saw a live one among them
            std::lock_guard<std::mutex> lock(mu_);
            const auto heir = std::find_if(kept.begin(), kept.end(), [&](const std::string& id) { return live_.count(id) != 0; });
            p->set_primary(*heir);
            p->set_epoch(p->epoch() + 1);
            std::rotate(kept.begin(), heir, heir + 1);  // the primary first
          }
          p->clear_in_sync();
          for (const std::string& id : kept) p->add_in_sync(id);
        });
    if (!left.ok() && left.status().code() != Status::Code::kFailedPrecondition) {
      spdlog::warn("cluster: {} leaving the in-sync set of '{}': {}", node_id_, name, left.status().ToString());
    }
  }
}

// Each placement that lists this node as a copy that is not in sync.
void ClusterNode::CatchUpAll() {
  std::vector<std::pair<std::string, internal::Placement>> behind;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& [name, placed] : placements_) {
      const internal::Placement& p = placed.placement;
      const bool replica = std::find(p.replicas().begin(), p.replicas().end(), node_id_) != p.replicas().end();
      if (replica && p.primary() != node_id_ && !InSync(p, node_id_) && !AddressOf(p.primary()).empty()) {
        behind.push_back({name, p});
      }
    }
  }
  for (const auto& [name, placement] : behind) {
    Status caught = CatchUp(name, placement);
    if (!caught.ok()) spdlog::warn("cluster: {} catching up on '{}': {}", node_id_, name, caught.ToString());
  }
  if (behind.empty() && !ready_.exchange(true)) {
    spdlog::info("cluster: {} holds every write of its copies: ready", node_id_);
    if (on_ready_) on_ready_();
  }
}

// A copy the controller moved off this node (rebalancing, a lowered factor)
// is deleted once etcd confirms that the placement lists this node nowhere
// and that other in-sync copies hold the collection. A collection without a
// placement (a store from before the cluster, an etcd that lost its keys) is
// never touched.
void ClusterNode::DropCopiesPlacedElsewhere() {
  auto elsewhere = [&](const internal::Placement& p) {
    const bool listed = p.primary() == node_id_ || InSync(p, node_id_) ||
                        std::find(p.replicas().begin(), p.replicas().end(), node_id_) != p.replicas().end();
    return !listed && !p.primary().empty() && p.in_sync_size() > 0;
  };
  std::vector<std::string> candidates;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& [name, placed] : placements_) {
      if (elsewhere(placed.placement)) candidates.push_back(name);
    }
  }
  for (const std::string& name : candidates) {
    if (!store_->HasCollection(name)) continue;
    Writer& writer = WriterOf(name);  // no write of it applied here meanwhile
    std::lock_guard<std::mutex> write_lock(writer.mu);
    Result<std::optional<EtcdValue>> now = etcd_->Get(Key("placement", name));
    internal::Placement placement;
    if (!now.ok() || !*now || !placement.ParseFromString((*now)->value) || !elsewhere(placement)) continue;
    Status dropped = store_->DropCollection(name);
    if (dropped.ok()) {
      spdlog::info("cluster: {} deleted its copy of '{}' ({} in-sync copies elsewhere, primary {})", node_id_, name,
                   placement.in_sync_size(), placement.primary());
    } else if (dropped.code() != Status::Code::kNotFound) {
      spdlog::warn("cluster: {} deleting its copy of '{}': {}", node_id_, name, dropped.ToString());
    }
  }
}

Status ClusterNode::CatchUp(const std::string& collection, const internal::Placement& placement) {
  std::string address;
  {
    std::lock_guard<std::mutex> lock(mu_);
    address = AddressOf(placement.primary());
  }
  std::shared_ptr<internal::Replica::Stub> stub = StubFor(address);
  auto join = [&](const ReplicationMark& mark) {
    internal::JoinRequest request;
    request.set_collection(collection);
    request.set_node_id(node_id_);
    request.set_epoch(mark.epoch);
    request.set_seq(mark.seq);
    request.set_indexing(Fingerprint(store_->indexing()));
    grpc::ClientContext context;
    Prepare(&context, kCatchUpTimeoutMs);
    internal::JoinResponse response;
    if (!Track(&context)) return Status::Cancelled("stopping");
    const Status joined = FromGrpcStatus(stub->Join(&context, request, &response));
    Track(nullptr);
    return joined;
  };
  Status joined = join(store_->MarkOf(collection));
  if (joined.code() != Status::Code::kFailedPrecondition) return joined;
  spdlog::info("cluster: {} copies '{}' whole from {} ({})", node_id_, collection, placement.primary(), joined.message());
  ReplicationMark mark;
  Status copied = CopyFrom(collection, address, &mark);
  if (!copied.ok()) return copied;
  return join(mark);
}

// Replaces this node's copy of the collection by the primary's snapshot:
// every map it holds, the maps it does not hold deleted, its mark last.
Status ClusterNode::CopyFrom(const std::string& collection, const std::string& address, ReplicationMark* mark) {
  std::shared_ptr<internal::Replica::Stub> stub = StubFor(address);
  // Until the copy is whole, this copy's mark matches no primary's history:
  // a crash midway makes the next catch-up copy again.
  Status invalidated = store_->SetMark(collection, {~uint64_t{0}, 0});
  if (!invalidated.ok()) return invalidated;
  grpc::ClientContext context;
  Prepare(&context, kCatchUpTimeoutMs);
  internal::CopyRequest request;
  request.set_collection(collection);
  request.set_indexing(Fingerprint(store_->indexing()));
  if (!Track(&context)) return Status::Cancelled("stopping");
  struct Untrack {
    ClusterNode* node;
    ~Untrack() { node->Track(nullptr); }
  } untrack{this};
  std::unique_ptr<grpc::ClientReader<internal::CopyChunk>> reader = stub->Copy(&context, request);
  std::unordered_set<std::string> kept;
  std::vector<KeptRequest> requests;
  internal::CopyChunk chunk;
  bool complete = false;
  while (reader->Read(&chunk)) {
    if (chunk.last()) {
      *mark = {chunk.epoch(), chunk.seq()};
      complete = true;
      continue;
    }
    for (internal::KeptRequest& r : *chunk.mutable_requests()) {
      requests.push_back({std::move(*r.mutable_request_id()), std::move(*r.mutable_record())});
    }
    std::vector<MapWrite> maps;
    for (const internal::ReplicatedMap& m : chunk.maps()) {
      Result<MapWrite> map = FromReplicated(m);
      if (!map.ok()) return map.status();
      kept.insert(m.map().metadata().map_id());
      maps.push_back(std::move(map).value());
    }
    if (maps.empty()) continue;
    Status stored = store_->InsertMaps(&maps, InsertLimits{~0u, 0});
    if (!stored.ok()) return stored;
  }
  const grpc::Status finished = reader->Finish();
  if (!finished.ok()) return FromGrpcStatus(finished);
  if (!complete) return Status::Unavailable("the copy of '" + collection + "' ended early");
  // Maps this copy held that the primary does not: writes never acknowledged.
  std::vector<std::string> stale;
  std::string after;
  for (;;) {
    std::vector<v1::MapMetadata> page;
    std::string next;
    if (!store_->ListMaps(collection, after, 1000, &page, &next).ok()) break;
    for (const v1::MapMetadata& meta : page) {
      if (kept.count(meta.map_id()) == 0) stale.push_back(meta.map_id());
    }
    if (next.empty()) break;
    after = next;
  }
  for (const std::string& id : stale) {
    Status deleted = store_->DeleteMap(collection, id);
    if (!deleted.ok() && deleted.code() != Status::Code::kNotFound) return deleted;
  }
  return store_->SetMark(collection, *mark, &requests);
}

void ClusterNode::DescribePlacement(const std::string& collection, const internal::Placement& p,
                                    v1::ClusterPlacement* out) const {
  out->set_collection(collection);
  out->set_epoch(p.epoch());
  out->set_copies_wanted(static_cast<uint32_t>(WantedCopies(p, config_.cluster_replication_factor)));
  for (const std::string& id : p.replicas()) {
    v1::ClusterCopy* copy = out->add_copies();
    copy->set_node_id(id);
    copy->set_primary(id == p.primary());
    copy->set_in_sync(InSync(p, id));
  }
}

Status ClusterNode::SetReplication(const std::string& collection, uint32_t copies, v1::ClusterPlacement* out) {
  Result<internal::Placement> changed = ChangePlacement(
      collection, [](const internal::Placement&) { return true; },
      [&](internal::Placement* p) { p->set_replication_factor(copies); });
  if (!changed.ok()) {
    if (changed.status().code() != Status::Code::kNotFound) return changed.status();
    return Status::NotFound("collection '" + collection + "' has no placement: write to it first");
  }
  spdlog::info("cluster: '{}' wants {} copies", collection, copies);
  DescribePlacement(collection, *changed, out);
  return Status::Ok();
}

void ClusterNode::Describe(v1::ClusterResponse* out) const {
  out->set_enabled(true);
  out->set_node_id(node_id_);
  std::map<std::string, Placed> placements;
  std::map<std::string, std::string> addresses;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& [id, node] : live_) {
      v1::ClusterNodeInfo* info = out->add_nodes();
      info->set_node_id(id);
      info->set_address(node.address());
      info->set_zone(node.zone());
      addresses[id] = node.address();
    }
    placements = placements_;
  }
  Result<std::optional<EtcdValue>> controller = etcd_->Get(prefix_ + "/controller");
  if (controller.ok() && *controller) out->set_controller((*controller)->value);
  for (const auto& [name, placed] : placements) {
    v1::ClusterPlacement* wire = out->add_placements();
    DescribePlacement(name, placed.placement, wire);
    uint64_t primary_seq = 0;
    for (v1::ClusterCopy& copy : *wire->mutable_copies()) {  // each copy's progress, asked of its node
      const auto address = addresses.find(copy.node_id());
      if (address == addresses.end()) continue;
      grpc::ClientContext context;
      Prepare(&context, 500);
      internal::ReplicaStateRequest request;
      request.set_collection(name);
      internal::ReplicaStateResponse state;
      if (!StubFor(address->second)->State(&context, request, &state).ok()) continue;
      copy.set_reachable(true);
      copy.set_seq(state.seq());
      if (copy.primary()) primary_seq = state.seq();
    }
    for (v1::ClusterCopy& copy : *wire->mutable_copies()) {
      if (copy.reachable()) copy.set_lag(primary_seq > copy.seq() ? primary_seq - copy.seq() : 0);
    }
  }
}

}  // namespace lmd::server::cluster
