// rosbag2 SQLite3 storage reader (.db3, ROS 2 Foxy to Jazzy) on Debian's
// libsqlite3: topics from the `topics` table, messages from `messages` in
// recording (row id) order, as the other containers keep them. The file is
// opened read-only and immutable (bags often sit on read-only media, and
// nothing else may write them while read).
#pragma once

#include <memory>
#include <string>

#include "core/io/bag.h"

namespace lmd {

// True if `head` starts with SQLite's magic ("SQLite format 3\0").
bool HasSqliteMagic(std::string_view head);

// Opens the .db3 file at `path`. InvalidArgument if it is not an SQLite
// database with rosbag2's tables; Corruption for a damaged database.
Result<std::unique_ptr<BagReader>> OpenRosbag2Sqlite(const std::string& path);

// Same from the bytes of a .db3 file (fuzzers, tests); errors name `name`.
Result<std::unique_ptr<BagReader>> OpenRosbag2SqliteBytes(std::string bytes, const std::string& name);

}  // namespace lmd
