// Random access to the bytes of a bag file, so that readers fetch only the
// records they need (a bag of camera images may be gigabytes) and fuzzers can
// feed them from memory.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/status.h"

namespace lmd {

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  // The name errors use (the file's path).
  virtual const std::string& name() const = 0;
  virtual uint64_t size() const = 0;
  // Exactly n bytes from `offset` into *out. Corruption "<name>: truncated at
  // offset N: ..." when they run past the end (`what` says what was read),
  // IoError when the read fails.
  virtual Status Read(uint64_t offset, uint64_t n, const char* what, std::string* out) const = 0;
};

// The file at `path`, read on demand. NotFound / IoError if it cannot be
// opened or is not a regular file.
Result<std::unique_ptr<ByteSource>> OpenFileSource(const std::string& path);

// `bytes` in memory under `name` (tests, fuzzers).
std::unique_ptr<ByteSource> MemorySource(std::string bytes, std::string name);

}  // namespace lmd
