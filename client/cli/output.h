// How lmdctl prints: human-readable lines by default, or with --json one JSON
// object per line (protobuf's JSON mapping, proto field names).
#pragma once

#include <string>

#include <google/protobuf/message.h>

namespace lmd::cli {

// One message as a single-line JSON object.
std::string ToJsonLine(const google::protobuf::Message& message);

}  // namespace lmd::cli
