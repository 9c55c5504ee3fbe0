// ClusterRoutes: where a client sends a collection's calls in a cluster of
// lmdd nodes (deploy/README.md, "Replicated collections"): writes straight
// to the collection's primary, reads to one of its in-sync copies, instead
// of through whichever node it first reached (which forwards them: an extra
// hop, and a second node's worker held). The view comes from the Cluster
// call, asked of the entry node (then of the other nodes it named), and is
// asked again after a node failed a call or when it is older than a few
// seconds. A collection the view does not place, a node that runs alone, or
// a token that may not read the cluster: calls go to the entry node.
// Thread-safe.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include <grpcpp/channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>

#include "lmd/v1/lmd.grpc.pb.h"

namespace lmd::client {

class ClusterRoutes {
 public:
  // `prepare` gives a Cluster call its deadline and token.
  ClusterRoutes(const std::string& entry, std::shared_ptr<grpc::ChannelCredentials> credentials,
                grpc::ChannelArguments args, std::function<void(grpc::ClientContext*)> prepare);

  // The node for a call on `collection` (empty: a server-wide call, to the
  // entry node).
  v1::LmdService::Stub* For(const std::string& collection, bool write);
  // `stub` did not answer (UNAVAILABLE): the view is asked for again.
  void Failed(const v1::LmdService::Stub* stub);

 private:
  struct Copies {
    std::string primary;               // address
    std::vector<std::string> in_sync;  // addresses
  };
  // Asks the cluster for its placements when the view is stale (one thread
  // at a time; `lock`, on mu_, is released during the calls).
  void Refresh(std::unique_lock<std::mutex>* lock);
  v1::LmdService::Stub* StubAt(const std::string& address);  // holds mu_

  const std::string entry_;
  const std::shared_ptr<grpc::ChannelCredentials> credentials_;
  const grpc::ChannelArguments args_;
  const std::function<void(grpc::ClientContext*)> prepare_;

  std::mutex mu_;
  std::map<std::string, std::unique_ptr<v1::LmdService::Stub>> stubs_;  // by address
  std::map<std::string, Copies> copies_;                                // by collection
  std::vector<std::string> nodes_;                                      // addresses the cluster named
  std::chrono::steady_clock::time_point fetched_{};                     // when the view was last asked for
  bool stale_ = true;
  bool refreshing_ = false;
  std::mt19937 random_{std::random_device{}()};
};

}  // namespace lmd::client
