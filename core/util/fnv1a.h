// FNV-1a, 64 bits: a hash that is the same in every build and on every host
// (std::hash is not), for keys and fingerprints that are stored, sent to
// other nodes, or compared between them.
#pragma once

#include <cstdint>
#include <string_view>

namespace lmd {

inline constexpr uint64_t kFnv1aOffset = 0xcbf29ce484222325ULL;

// One step: `hash` with `value` (a byte, or a whole word) mixed in.
inline uint64_t Fnv1aMix(uint64_t hash, uint64_t value) { return (hash ^ value) * 0x100000001b3ULL; }

inline uint64_t Fnv1a64(std::string_view bytes, uint64_t hash = kFnv1aOffset) {
  for (unsigned char c : bytes) hash = Fnv1aMix(hash, c);
  return hash;
}

}  // namespace lmd
