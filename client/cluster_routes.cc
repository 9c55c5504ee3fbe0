#include "client/cluster_routes.h"

#include <algorithm>
#include <optional>

#include <grpcpp/create_channel.h>

namespace lmd::client {
namespace {

using Clock = std::chrono::steady_clock;

// A view this old is asked for again: placements change when nodes fail.
constexpr auto kViewLifetime = std::chrono::seconds(5);
// At most one Cluster call per this long, even while nodes keep failing.
constexpr auto kMinRefreshInterval = std::chrono::milliseconds(200);

}  // namespace

ClusterRoutes::ClusterRoutes(const std::string& entry, std::shared_ptr<grpc::ChannelCredentials> credentials,
                             grpc::ChannelArguments args, std::function<void(grpc::ClientContext*)> prepare)
    : entry_(entry), credentials_(std::move(credentials)), args_(std::move(args)), prepare_(std::move(prepare)) {}

v1::LmdService::Stub* ClusterRoutes::StubAt(const std::string& address) {
  std::unique_ptr<v1::LmdService::Stub>& stub = stubs_[address];
  if (!stub) stub = v1::LmdService::NewStub(grpc::CreateCustomChannel(address, credentials_, args_));
  return stub.get();
}

void ClusterRoutes::Refresh(std::unique_lock<std::mutex>* lock) {
  const auto now = Clock::now();
  if (refreshing_ || (!stale_ && now - fetched_ < kViewLifetime) || now - fetched_ < kMinRefreshInterval) return;
  refreshing_ = true;
  fetched_ = now;
  std::vector<v1::LmdService::Stub*> askable{StubAt(entry_)};
  for (const std::string& address : nodes_) askable.push_back(StubAt(address));
  lock->unlock();  // calls meanwhile use the view as it is
  std::optional<v1::ClusterResponse> answer;
  for (v1::LmdService::Stub* stub : askable) {
    grpc::ClientContext context;
    prepare_(&context);
    v1::ClusterResponse cluster;
    if (stub->Cluster(&context, v1::ClusterRequest(), &cluster).ok()) {
      answer = std::move(cluster);
      break;
    }
  }
  lock->lock();
  refreshing_ = false;
  if (!answer) return;
  std::map<std::string, std::string> address_of;  // node id -> address
  nodes_.clear();
  for (const v1::ClusterNodeInfo& node : answer->nodes()) {
    address_of[node.node_id()] = node.address();
    nodes_.push_back(node.address());
  }
  copies_.clear();
  for (const v1::ClusterPlacement& placement : answer->placements()) {
    Copies copies;
    for (const v1::ClusterCopy& copy : placement.copies()) {
      const auto it = address_of.find(copy.node_id());
      if (it == address_of.end()) continue;  // down
      if (copy.primary()) copies.primary = it->second;
      if (copy.in_sync()) copies.in_sync.push_back(it->second);
    }
    copies_[placement.collection()] = std::move(copies);
  }
  stale_ = false;
}

v1::LmdService::Stub* ClusterRoutes::For(const std::string& collection, bool write) {
  std::unique_lock<std::mutex> lock(mu_);
  if (collection.empty()) return StubAt(entry_);
  Refresh(&lock);
  const auto it = copies_.find(collection);
  if (it == copies_.end()) return StubAt(entry_);
  const Copies& copies = it->second;
  if (write || copies.in_sync.empty()) return StubAt(copies.primary.empty() ? entry_ : copies.primary);
  std::uniform_int_distribution<size_t> pick(0, copies.in_sync.size() - 1);
  return StubAt(copies.in_sync[pick(random_)]);
}

void ClusterRoutes::Failed(const v1::LmdService::Stub* stub) {
  std::lock_guard<std::mutex> lock(mu_);
  for (auto& [address, known] : stubs_) {
    if (known.get() != stub) continue;
    stale_ = true;
    // Until the view says otherwise, its collections go to the entry node.
    for (auto& [collection, copies] : copies_) {
      if (copies.primary == address) copies.primary.clear();
      copies.in_sync.erase(std::remove(copies.in_sync.begin(), copies.in_sync.end(), address), copies.in_sync.end());
    }
  }
}

}  // namespace lmd::client
