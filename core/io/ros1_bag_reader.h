// ROS 1 bag v2.0 reader (the rosbag format, wiki.ros.org/Bags/Format/2.0) on
// Debian's liblz4 and libbz2: chunks uncompressed, lz4 or bz2. An indexed
// bag (index_pos set) is read through its connection and chunk-info records:
// chunks are fetched at their recorded positions and those without a wanted
// connection are skipped unread, so a wrong length in the index-data records
// between chunks does no harm. An unindexed bag (a recorder that died) is
// walked record by record. Connections that share a topic are one topic.
#pragma once

#include <memory>

#include "core/io/bag.h"
#include "core/io/byte_source.h"

namespace lmd {

// True if `head` starts with "#ROSBAG V2.0\n".
bool HasRos1BagMagic(std::string_view head);

// InvalidArgument if `source` is not a ROS 1 bag v2.0 (a v1.2 bag is named
// as such); Corruption "<name>: offset N: ..." for damaged records.
Result<std::unique_ptr<BagReader>> OpenRos1Bag(std::unique_ptr<ByteSource> source, const BagReadOptions& options = {});

}  // namespace lmd
