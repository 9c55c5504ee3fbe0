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

std::string MapJsonLine(const v1::MapMetadata& metadata) {
  google::protobuf::StringValue id;  // its JSON form is the escaped string
  id.set_value(metadata.map_id());
  return "{\"id\":" + ToJsonLine(id) + "," + ToJsonLine(metadata).substr(1);
}

}  // namespace lmd::cli
