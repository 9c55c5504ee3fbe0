// Placement decisions for replicated collections, as pure functions of the
// cluster's state, so that they can be tested without etcd: which nodes hold
// a new collection, and how a placement is repaired when nodes die or join.
// The elected controller (cluster_node.h) applies repairs by compare-and-swap.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "lmd/internal/cluster.pb.h"

namespace lmd::server::cluster {

// Live nodes by id (their etcd key exists: their lease is renewed).
using LiveNodes = std::map<std::string, internal::NodeRecord>;

// Where a collection's copies belong: its primary, then the wanted - 1
// nodes of `placeable` that rank highest for the collection (rendezvous
// hashing: collections spread evenly, and a node joining or leaving moves
// few copies), preferring zones not yet used.
std::vector<std::string> TargetCopies(const std::string& collection, const std::string& primary,
                                      const LiveNodes& placeable, size_t wanted);

// The placement of a collection created by a write to `creator` (which
// becomes its primary: the write needs no forward): its TargetCopies among
// the live nodes. The other copies are in sync when `others_in_sync` (a
// new, empty collection); else they copy it first (the creator already held
// maps of it). Epoch 1.
internal::Placement NewPlacement(const std::string& collection, const LiveNodes& live, const std::string& creator,
                                 size_t replication_factor, bool others_in_sync = true);

// The repaired placement, or nothing when `current` needs no change:
// - a dead primary is replaced by the first live in-sync node (epoch + 1);
//   with none, the placement stays (the collection takes no writes until
//   one of its in-sync nodes returns);
// - dead nodes leave the in-sync set (they stay replicas and catch up when
//   they return);
// - the nodes of its TargetCopies among the live nodes and the `returning`
//   ones (replicas gone briefly: their copy is expected back, so no other
//   node starts copying) join as replicas when they hold none (not in sync:
//   they copy the collection). A node joining the cluster so takes the
//   copies it ranks highest for (rebalancing), and a lowered factor
//   shrinks the target;
// - replicas outside the target leave once the copies wanted are in sync
//   without them: dead ones first, then those catching up, then the
//   lowest-ranked; never the primary (it is the target's first).
// The copies wanted: the placement's replication_factor, else
// `default_replication_factor`.
std::optional<internal::Placement> Repaired(const std::string& collection, const internal::Placement& current,
                                            const LiveNodes& live, size_t default_replication_factor,
                                            const LiveNodes& returning = {});

// The copies a placement wants.
size_t WantedCopies(const internal::Placement& placement, size_t default_replication_factor);

// Whether `node` is in the placement's in-sync set.
bool InSync(const internal::Placement& placement, const std::string& node);

}  // namespace lmd::server::cluster
