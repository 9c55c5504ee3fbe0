#include "server/cluster/replication_log.h"

namespace lmd::server::cluster {

void ReplicationLog::Reset(uint64_t epoch, uint64_t seq) {
  writes_.clear();
  bytes_ = 0;
  base_epoch_ = epoch;
  base_seq_ = seq;
}

void ReplicationLog::Append(internal::ApplyRequest write) {
  const uint64_t last = last_seq();
  if (write.seq() != last + 1) Reset(~uint64_t{0}, write.seq() - 1);  // the epoch before it is unknown: matches none
  const size_t size = write.ByteSizeLong();
  bytes_ += size;
  writes_.emplace_back(std::move(write), size);
  while (writes_.size() > 1 && bytes_ > max_bytes_) {
    base_epoch_ = writes_.front().first.epoch();
    base_seq_ = writes_.front().first.seq();
    bytes_ -= writes_.front().second;
    writes_.pop_front();
  }
}

std::optional<std::vector<internal::ApplyRequest>> ReplicationLog::After(uint64_t epoch, uint64_t seq) const {
  const uint64_t last = last_seq();
  if (seq < base_seq_ || seq > last) return std::nullopt;
  if (seq == base_seq_) {
    if (epoch != base_epoch_) return std::nullopt;
  } else if (writes_[seq - base_seq_ - 1].first.epoch() != epoch) {
    return std::nullopt;
  }
  std::vector<internal::ApplyRequest> after;
  for (uint64_t s = seq + 1; s <= last; ++s) after.push_back(writes_[s - base_seq_ - 1].first);
  return after;
}

}  // namespace lmd::server::cluster
