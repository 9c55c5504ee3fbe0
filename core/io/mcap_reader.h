// MCAP reader (https://mcap.dev spec, version 0) on Debian's libzstd and
// liblz4: chunked and unchunked files; chunks uncompressed, zstd or lz4;
// with a summary section (channels and chunk indexes read from it, chunks
// without a wanted channel skipped unread) or without one (a recorder that
// crashed leaves none: the data section is scanned record by record). CRCs
// (chunk, data section, summary) are checked when the file records them.
#pragma once

#include <memory>

#include "core/io/bag.h"
#include "core/io/byte_source.h"

namespace lmd {

// True if `head` (the file's first bytes) starts with MCAP's magic.
bool HasMcapMagic(std::string_view head);

// Reads the summary (or scans the data section) of the MCAP file in
// `source`. InvalidArgument if it does not start with MCAP's magic;
// Corruption "<name>: offset N: ..." for a damaged summary, a wrong CRC, or
// a record running past the end of the file (a truncated file).
Result<std::unique_ptr<BagReader>> OpenMcap(std::unique_ptr<ByteSource> source, const BagReadOptions& options = {});

}  // namespace lmd
