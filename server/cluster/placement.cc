#include "server/cluster/placement.h"

#include <algorithm>
#include <tuple>
#include <vector>

#include "core/util/fnv1a.h"

namespace lmd::server::cluster {
namespace {

uint64_t Rank(const std::string& collection, const std::string& node) {
  return Fnv1a64(collection + "/" + node);  // the same on every node
}

bool Contains(const google::protobuf::RepeatedPtrField<std::string>& list, const std::string& id) {
  return std::find(list.begin(), list.end(), id) != list.end();
}

// Live nodes not in `taken`, best first for the collection: zones not in
// `zones` before the others, then by rank.
std::vector<std::string> Spares(const std::string& collection, const LiveNodes& live,
                                const std::set<std::string>& taken, const std::set<std::string>& zones) {
  std::vector<std::string> spares;
  for (const auto& [id, node] : live) {
    if (taken.count(id) == 0) spares.push_back(id);
  }
  auto fresh_zone = [&](const std::string& id) {
    const std::string& zone = live.at(id).zone();
    return zone.empty() || zones.count(zone) == 0;
  };
  std::sort(spares.begin(), spares.end(), [&](const std::string& a, const std::string& b) {
    if (fresh_zone(a) != fresh_zone(b)) return fresh_zone(a);
    return Rank(collection, a) > Rank(collection, b);
  });
  return spares;
}

// Adds spares as replicas (not in sync) one at a time, each choice seeing
// the zones the earlier ones took.
void AddSpares(const std::string& collection, const LiveNodes& live, size_t wanted, bool in_sync,
               internal::Placement* placement) {
  std::set<std::string> taken(placement->replicas().begin(), placement->replicas().end());
  std::set<std::string> zones;
  size_t live_replicas = 0;
  for (const std::string& id : placement->replicas()) {
    const auto it = live.find(id);
    if (it == live.end()) continue;
    ++live_replicas;
    if (!it->second.zone().empty()) zones.insert(it->second.zone());
  }
  while (live_replicas < wanted) {
    const std::vector<std::string> spares = Spares(collection, live, taken, zones);
    if (spares.empty()) return;
    const std::string& id = spares.front();
    placement->add_replicas(id);
    if (in_sync) placement->add_in_sync(id);
    taken.insert(id);
    if (!live.at(id).zone().empty()) zones.insert(live.at(id).zone());
    ++live_replicas;
  }
}

// Removes replicas beyond `wanted` (Repaired says which), only while at
// least `wanted` copies stay in sync.
void Trim(const std::string& collection, const LiveNodes& live, size_t wanted, internal::Placement* placement) {
  if (static_cast<size_t>(placement->in_sync_size()) < wanted) return;
  std::vector<std::string> leaving;  // the first to leave first
  for (const std::string& id : placement->replicas()) {
    if (id != placement->primary()) leaving.push_back(id);
  }
  auto order = [&](const std::string& id) {
    const bool in_sync = Contains(placement->in_sync(), id);
    return std::make_tuple(in_sync, live.count(id) != 0, Rank(collection, id));
  };
  std::sort(leaving.begin(), leaving.end(), [&](const std::string& a, const std::string& b) { return order(a) < order(b); });
  for (const std::string& id : leaving) {
    if (static_cast<size_t>(placement->replicas_size()) <= wanted) return;
    const bool in_sync = Contains(placement->in_sync(), id);
    if (in_sync && static_cast<size_t>(placement->in_sync_size()) <= wanted) return;
    for (auto* list : {placement->mutable_replicas(), placement->mutable_in_sync()}) {
      list->erase(std::remove(list->begin(), list->end(), id), list->end());
    }
  }
}

}  // namespace

size_t WantedCopies(const internal::Placement& placement, size_t default_replication_factor) {
  return std::max<size_t>(1, placement.replication_factor() > 0 ? placement.replication_factor()
                                                                  : default_replication_factor);
}

internal::Placement NewPlacement(const std::string& collection, const LiveNodes& live, const std::string& creator,
                                 size_t replication_factor, bool others_in_sync) {
  internal::Placement placement;
  placement.set_epoch(1);
  placement.set_primary(creator);
  placement.add_in_sync(creator);
  placement.add_replicas(creator);
  LiveNodes with_creator = live;
  with_creator.emplace(creator, internal::NodeRecord());
  AddSpares(collection, with_creator, std::max<size_t>(1, replication_factor), others_in_sync, &placement);
  return placement;
}

std::optional<internal::Placement> Repaired(const std::string& collection, const internal::Placement& current,
                                            const LiveNodes& live, size_t default_replication_factor) {
  const size_t wanted = WantedCopies(current, default_replication_factor);
  internal::Placement next = current;
  auto alive = [&](const std::string& id) { return live.count(id) != 0; };
  if (!alive(current.primary())) {
    const auto heir = std::find_if(current.in_sync().begin(), current.in_sync().end(),
                                   [&](const std::string& id) { return id != current.primary() && alive(id); });
    if (heir != current.in_sync().end()) {
      next.set_primary(*heir);
      next.set_epoch(current.epoch() + 1);
    }
  }
  // In sync: the primary first, then the live others in their order.
  next.clear_in_sync();
  next.add_in_sync(next.primary());
  for (const std::string& id : current.in_sync()) {
    if (id != next.primary() && alive(id)) next.add_in_sync(id);
  }
  if (!alive(next.primary())) return std::nullopt;  // no live copy to promote: wait for one
  AddSpares(collection, live, wanted, /*in_sync=*/false, &next);
  Trim(collection, live, wanted, &next);
  if (next.SerializeAsString() == current.SerializeAsString()) return std::nullopt;
  return next;
}

bool InSync(const internal::Placement& placement, const std::string& node) {
  return Contains(placement.in_sync(), node);
}

}  // namespace lmd::server::cluster
