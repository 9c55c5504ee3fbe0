// Compression of bag chunks (MCAP: zstd, lz4; ROS 1: lz4, bz2). Decompression
// fills a buffer of the size the chunk declares, growing only as bytes are
// produced, so a chunk that claims gigabytes but holds little costs little.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/status.h"

namespace lmd {

enum class Compression { kNone, kZstd, kLz4Frame, kBz2 };

// "zstd", "lz4", "bz2", "none".
const char* CompressionName(Compression c);

// Decompresses `in` (one or more zstd frames, one LZ4 frame, or one bzip2
// stream) into *out, which must come to exactly `expected_size` bytes.
// Corruption "<what>: ..." when the data is damaged, ends early, or
// decompresses to another size than expected (naming both sizes);
// ResourceExhausted when expected_size exceeds max_size. kNone copies `in`
// (its size must match too).
Status Decompress(Compression compression, std::string_view in, uint64_t expected_size, uint64_t max_size,
                  const std::string& what, std::string* out);

// Compresses `in` into one zstd frame, one LZ4 frame or one bzip2 stream
// (kNone copies). Internal if the library fails.
Status Compress(Compression compression, std::string_view in, std::string* out);

}  // namespace lmd
