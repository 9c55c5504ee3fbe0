// ReplicationLog: the recent writes of one collection on its primary, in
// memory, so that a copy that missed a few (restarted, or timed out once)
// catches up by receiving them instead of the whole collection. A copy may
// resume after (epoch, seq) only if the log can tell that the copy holds
// exactly this primary's history up to there: that write is in the log with
// that epoch, or is the log's base (where the primary's store stood when the
// log started). A copy that applied a write under an older primary which
// this one never had has diverged and is copied whole (the log-matching
// rule of Raft, for a log without elections of its own).
//
// Not thread-safe: the primary holds its collection's write lock.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "lmd/internal/cluster.pb.h"

namespace lmd::server::cluster {

class ReplicationLog {
 public:
  // Keeps at most `max_bytes` of writes (the newest always).
  explicit ReplicationLog(size_t max_bytes) : max_bytes_(max_bytes) {}

  // Starts the log anew after the write (epoch, seq).
  void Reset(uint64_t epoch, uint64_t seq);

  // Appends a write; one that does not follow the last resets the log to it.
  void Append(internal::ApplyRequest write);

  // The writes after (epoch, seq), oldest first, or nothing if the log
  // cannot tell that a copy at (epoch, seq) holds this primary's history.
  std::optional<std::vector<internal::ApplyRequest>> After(uint64_t epoch, uint64_t seq) const;

  // The last write's number (the base's when empty).
  uint64_t last_seq() const { return writes_.empty() ? base_seq_ : writes_.back().first.seq(); }

 private:
  size_t max_bytes_;
  size_t bytes_ = 0;
  uint64_t base_epoch_ = 0, base_seq_ = 0;  // the write just before the first kept
  std::deque<std::pair<internal::ApplyRequest, size_t>> writes_;  // with their sizes
};

}  // namespace lmd::server::cluster
