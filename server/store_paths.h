// Where a store and its backups may lie: the checks lmdd makes before
// RocksDB touches a directory, so that a wrong one is refused with the
// reason and left as it was.
#pragma once

#include <string>

#include "core/status.h"

namespace lmd::server {

// A new store is created only in a missing or empty directory; an existing
// one has its CURRENT file. FailedPrecondition (nothing changed) otherwise.
Status CheckDataDirectory(const std::string& data_dir);

// A backup directory a client asked for: InvalidArgument if its path cannot
// name a directory (control characters, too long), already exists, has no
// existing parent or lies inside the store in `data_dir`;
// FailedPrecondition if lmdd cannot create it (the system's reason).
Status CheckBackupDirectory(const std::string& directory, const std::string& data_dir);

// `message` with every occurrence of `path` quoted short (core/util/quoted.h):
// a status message travels in a header of at most 8 KiB.
std::string ShortenPath(std::string message, const std::string& path);

}  // namespace lmd::server
