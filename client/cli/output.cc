#include "client/cli/output.h"

#include <google/protobuf/util/json_util.h>
#include <google/protobuf/wrappers.pb.h>

namespace lmd::cli {

std::string ToJsonLine(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string json;
  const auto status = google::protobuf::util::MessageToJsonString(message, &json, options);
  return status.ok() ? json : "{}";
}

namespace {

std::string JsonString(const std::string& value) {
  google::protobuf::StringValue wrapped;  // its JSON form is the escaped string
  wrapped.set_value(value);
  return ToJsonLine(wrapped);
}

}  // namespace

std::string MapJsonLine(const v1::MapMetadata& metadata) {
  return "{\"id\":" + JsonString(metadata.map_id()) + "," + ToJsonLine(metadata).substr(1);
}

std::string EvictedJsonLine(const v1::MapMetadata& metadata) {
  return "{\"evicted\":" + JsonString(metadata.map_id()) + ",\"collection\":" + JsonString(metadata.collection()) +
         "}";
}

}  // namespace lmd::cli

namespace lmd::cli {

std::string BagSummaryJsonLine(const std::string& bag, const BagLogSummary& summary, size_t maps) {
  return "{\"bag\":" + JsonString(bag) + ",\"format\":" + JsonString(summary.format) +
         ",\"scan_topic\":" + JsonString(summary.scan_topic) + ",\"scans_read\":" +
         std::to_string(summary.scans_read) + ",\"scans_without_pose\":" + std::to_string(summary.scans_without_pose) +
         ",\"pose_source\":" + JsonString(summary.pose_source) + ",\"laser_mounting\":" +
         JsonString(summary.laser_mounting) + ",\"maps\":" + std::to_string(maps) + "}";
}

ProgressBar TerminalProgress(std::string label, size_t total) {
  return ProgressBar(std::move(label), total, stderr, ProgressBar::OffTerminal::kNothing);
}

}  // namespace lmd::cli
