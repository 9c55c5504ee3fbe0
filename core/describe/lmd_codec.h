// Compact, versioned binary form of an Lmd (what is stored per map).
//   byte 0      format version: 1 (no inner words) or 2
//   varint      feature count n
//   3 x float32 frame origin x, y, heading (little endian)
//   n times     int16 x, int16 y (position / 0.05 m, clamped to +-1638 m),
//               uint16 appearance word, [version 2: uint16 inner word,
//               0xFFFF = none], uint64 change word (60 bits used)
//   14 (version 1) or 16 (version 2) bytes per feature + ~14 bytes; no
//   trailing bytes allowed. Version 1 is written when no feature has an
//   inner word, so descriptors without them keep their size and bytes.
#pragma once

#include <string>

#include "core/status.h"
#include "core/types.h"

namespace lmd {

inline constexpr double kLmdPositionQuantumM = 0.05;  // m per int16 unit
inline constexpr int kLmdCodecVersion = 2;  // newest version (both are read)

// Encodes `lmd`. Positions are rounded to kLmdPositionQuantumM, appearance
// words keep their low 16 bits, inner words their low 15 bits (kNoWord stays
// none), change words their low 60 bits.
std::string EncodeLmd(const Lmd& lmd);

// Decodes bytes made by EncodeLmd. Corruption (never a crash, never an
// allocation larger than the input warrants) on a wrong version, truncation,
// trailing bytes, a count that does not match the length, or a non-finite
// frame.
Result<Lmd> DecodeLmd(const std::string& bytes);

}  // namespace lmd
