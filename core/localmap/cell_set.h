// A flat open-addressing set of 2D integer grid cells (internal helper for
// point deduplication; no per-insert allocation).
#pragma once

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <vector>

namespace lmd {

// Packs cell (ix, iy), |ix|, |iy| < 2^30, into one key (never ~0).
inline uint64_t CellKey(int64_t ix, int64_t iy) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(ix + 0x40000000)) << 32) |
         static_cast<uint32_t>(iy + 0x40000000);
}

// Key of the cell of size `cell` holding (x, y).
inline uint64_t CellKeyOf(double x, double y, double cell) {
  return CellKey(static_cast<int64_t>(std::floor(x / cell)), static_cast<int64_t>(std::floor(y / cell)));
}

inline uint64_t MixKey(uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return k;
}

class CellSet {
 public:
  // Empties the set and sizes it for about `expected` keys.
  void Reset(size_t expected) {
    size_t cap = 16;
    while (cap < expected * 2) cap <<= 1;
    if (slots_.size() != cap) {
      slots_.assign(cap, kEmpty);
    } else {
      std::fill(slots_.begin(), slots_.end(), kEmpty);
    }
    size_ = 0;
  }
  // Inserts key; true if it was not there yet.
  bool Insert(uint64_t key) {
    if ((size_ + 1) * 2 > slots_.size()) Grow();
    const size_t mask = slots_.size() - 1;
    size_t i = MixKey(key) & mask;
    while (slots_[i] != kEmpty) {
      if (slots_[i] == key) return false;
      i = (i + 1) & mask;
    }
    slots_[i] = key;
    ++size_;
    return true;
  }
  bool Contains(uint64_t key) const {
    if (slots_.empty()) return false;
    const size_t mask = slots_.size() - 1;
    size_t i = MixKey(key) & mask;
    while (slots_[i] != kEmpty) {
      if (slots_[i] == key) return true;
      i = (i + 1) & mask;
    }
    return false;
  }
  size_t size() const { return size_; }

 private:
  static constexpr uint64_t kEmpty = ~0ULL;  // no CellKey is ~0
  void Grow() {
    std::vector<uint64_t> old;
    old.swap(slots_);
    slots_.assign(old.empty() ? 16 : old.size() * 2, kEmpty);
    size_ = 0;
    for (uint64_t k : old) {
      if (k != kEmpty) Insert(k);
    }
  }
  std::vector<uint64_t> slots_;
  size_t size_ = 0;
};

}  // namespace lmd
