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

// Removes replicas the target does not hold, those not in sync (dead ones
// first) before those in sync, the lowest-ranked first, only while at least
// `wanted` copies stay in sync: a node leaves a placement only once the
// copies that replace it have caught up.
void Trim(const std::string& collection, const LiveNodes& live, const std::vector<std::string>& target,
          size_t wanted, internal::Placement* placement) {
  std::vector<std::string> leaving;  // the first to leave first
  for (const std::string& id : placement->replicas()) {
    if (std::find(target.begin(), target.end(), id) == target.end()) leaving.push_back(id);
  }
  auto order = [&](const std::string& id) {
    return std::make_tuple(Contains(placement->in_sync(), id), live.count(id) != 0, Rank(collection, id));
  };
  std::sort(leaving.begin(), leaving.end(), [&](const std::string& a, const std::string& b) { return order(a) < order(b); });
  for (const std::string& id : leaving) {
    const size_t in_sync = static_cast<size_t>(placement->in_sync_size());
    if (in_sync < wanted || (Contains(placement->in_sync(), id) && in_sync <= wanted)) return;
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

std::vector<std::string> TargetCopies(const std::string& collection, const std::string& primary,
                                      const LiveNodes& placeable, size_t wanted) {
  std::vector<std::string> target{primary};
  std::set<std::string> taken{primary};
  std::set<std::string> zones;
  if (const auto it = placeable.find(primary); it != placeable.end() && !it->second.zone().empty()) {
    zones.insert(it->second.zone());
  }
  while (target.size() < wanted) {  // one at a time: each choice sees the zones the earlier ones took
    const std::vector<std::string> spares = Spares(collection, placeable, taken, zones);
    if (spares.empty()) break;
    const std::string& id = spares.front();
    target.push_back(id);
    taken.insert(id);
    if (!placeable.at(id).zone().empty()) zones.insert(placeable.at(id).zone());
  }
  return target;
}

internal::Placement NewPlacement(const std::string& collection, const LiveNodes& live, const std::string& creator,
                                 size_t replication_factor, bool others_in_sync) {
  internal::Placement placement;
  placement.set_epoch(1);
  placement.set_primary(creator);
  LiveNodes with_creator = live;
  with_creator.emplace(creator, internal::NodeRecord());
  for (const std::string& id : TargetCopies(collection, creator, with_creator, std::max<size_t>(1, replication_factor))) {
    placement.add_replicas(id);
    if (id == creator || others_in_sync) placement.add_in_sync(id);
  }
  return placement;
}

std::optional<internal::Placement> Repaired(const std::string& collection, const internal::Placement& current,
                                            const LiveNodes& live, size_t default_replication_factor,
                                            const LiveNodes& returning) {
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
  // Where the copies belong: live nodes, and replicas gone only briefly.
  LiveNodes placeable = live;
  for (const auto& [id, record] : returning) {
    if (Contains(current.replicas(), id)) placeable.emplace(id, record);
  }
  const std::vector<std::string> target = TargetCopies(collection, next.primary(), placeable, wanted);
  for (const std::string& id : target) {
    if (!Contains(next.replicas(), id)) next.add_replicas(id);  // catches up before it counts
  }
  Trim(collection, live, target, wanted, &next);
  if (next.SerializeAsString() == current.SerializeAsString()) return std::nullopt;
  return next;
}

bool InSync(const internal::Placement& placement, const std::string& node) {
  return Contains(placement.in_sync(), node);
}

}  // namespace lmd::server::cluster
