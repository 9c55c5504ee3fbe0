#include "server/store_paths.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>

#include "core/util/quoted.h"

namespace lmd::server {
namespace {

// Files RocksDB writes into a directory at every open, before a new store's
// CURRENT exists: its lock and its info logs. They hold no maps, so a first
// start that failed after writing them may be retried.
bool HoldsNoMaps(const std::string& file_name) {
  return file_name == "LOCK" || file_name == "LOG" || file_name.rfind("LOG.old.", 0) == 0;
}

// Longest backup directory path: PATH_MAX less room for what RocksDB adds
// (".tmp" while it writes, then "/MANIFEST-" and a number, say).
constexpr size_t kMaxBackupPathBytes = PATH_MAX - 64;
// Longest name in it: RocksDB writes the checkpoint into "NAME.tmp" first.
constexpr size_t kMaxBackupNameBytes = NAME_MAX - 4;

// InvalidArgument if `directory` cannot name a directory: control
// characters, longer than the system takes, or a name in it too long.
Status CheckBackupName(const std::string& directory) {
  if (!std::all_of(directory.begin(), directory.end(), [](char c) { return c >= 0x20 && c != 0x7f; })) {
    return Status::InvalidArgument("backup directory " + Quoted(directory) + " holds control characters");
  }
  if (directory.size() > kMaxBackupPathBytes) {
    return Status::InvalidArgument("backup directory " + Quoted(directory) + " is " +
                                   std::to_string(directory.size()) + " bytes long; at most " +
                                   std::to_string(kMaxBackupPathBytes));
  }
  for (const std::filesystem::path& name : std::filesystem::path(directory)) {
    if (name.native().size() > kMaxBackupNameBytes) {
      return Status::InvalidArgument("backup directory " + Quoted(directory) + ": the name " + Quoted(name.string()) +
                                     " is longer than " + std::to_string(kMaxBackupNameBytes) + " bytes");
    }
  }
  return Status::Ok();
}

// InvalidArgument unless `directory`'s parent exists and is outside the
// store in `data_dir`: a copy inside the live store would be copied into the
// next backup, and lost with the store.
Status CheckBackupPlace(const std::string& directory, const std::string& data_dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path target(directory);
  if (!fs::is_directory(target.parent_path(), error)) {
    return Status::InvalidArgument("backup directory " + Quoted(directory) + ": its parent " +
                                   Quoted(target.parent_path().string()) + " is not an existing directory");
  }
  const fs::path parent = fs::weakly_canonical(target.parent_path(), error);
  const fs::path store = fs::weakly_canonical(data_dir, error);
  const bool inside = std::mismatch(store.begin(), store.end(), parent.begin(), parent.end()).first == store.end();
  if (!error && inside) {
    return Status::InvalidArgument("backup directory " + Quoted(directory) + " is inside lmdd's data directory " +
                                   data_dir);
  }
  return Status::Ok();
}

// Creates `directory` and removes it again: a directory the client chose
// that lmdd cannot create (read-only, /proc, no permission) is refused with
// the system's reason, as the client's to fix, before RocksDB fails on it.
Status ProbeCreatable(const std::string& directory) {
  if (mkdir(directory.c_str(), 0700) != 0) {
    const int error = errno;
    if (error == EEXIST) return Status::InvalidArgument("backup directory " + Quoted(directory) + " already exists");
    return Status::FailedPrecondition("cannot create backup directory " + Quoted(directory) + ": " +
                                      std::strerror(error));
  }
  if (rmdir(directory.c_str()) != 0) {
    return Status::IoError("cannot remove backup directory " + Quoted(directory) + " after creating it: " +
                           std::strerror(errno));
  }
  return Status::Ok();
}

}  // namespace

// A new store is created only in a missing or empty directory. RocksDB, told
// to create a store where another store's files lie without their CURRENT
// (a damaged or half-copied store), deletes those files as obsolete; and
// where it cannot, it leaves a new CURRENT among them.
Status CheckDataDirectory(const std::string& data_dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status status = fs::status(data_dir, error);
  if (status.type() == fs::file_type::not_found) return Status::Ok();
  if (error) return Status::IoError("cannot read the data directory " + data_dir + ": " + error.message());
  if (!fs::is_directory(status)) return Status::FailedPrecondition("data directory " + data_dir + " is not a directory");
  if (fs::exists(fs::path(data_dir) / "CURRENT", error)) return Status::Ok();
  for (fs::directory_iterator it(data_dir, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (HoldsNoMaps(name)) continue;
    return Status::FailedPrecondition("data directory " + data_dir + " holds " + Quoted(name) +
                                      " but no CURRENT file: a damaged store, or no store; lmdd creates a store "
                                      "only in an empty or missing directory (nothing was changed)");
  }
  if (error) return Status::IoError("cannot list the data directory " + data_dir + ": " + error.message());
  return Status::Ok();
}

Status CheckBackupDirectory(const std::string& directory, const std::string& data_dir) {
  Status status = CheckBackupName(directory);
  if (status.ok()) status = CheckBackupPlace(directory, data_dir);
  if (status.ok()) status = ProbeCreatable(directory);
  return status;
}

// `message` with `path` quoted short wherever it stands: RocksDB's errors
// name the backup directory, which a client may make kilobytes long (and a
// status message goes back in a header of at most 8 KiB).
std::string ShortenPath(std::string message, const std::string& path) {
  const std::string quoted = Quoted(path);
  for (size_t at = path.empty() ? std::string::npos : message.find(path); at != std::string::npos;
       at = message.find(path, at + quoted.size())) {
    message.replace(at, path.size(), quoted);
  }
  return message;
}

}  // namespace lmd::server
