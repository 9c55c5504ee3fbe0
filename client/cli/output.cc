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
