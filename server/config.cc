#include "server/config.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <limits>

#include "core/util/host_port.h"

namespace lmd::server {
namespace {

std::string Trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

Status ParseUnsigned(const std::string& key, const std::string& value, uint64_t min, uint64_t max, uint64_t* out) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long parsed = std::strtoull(value.c_str(), &end, 10);
  if (value.empty() || value[0] == '-' || *end != '\0' || errno != 0 || parsed < min || parsed > max) {
    return Status::InvalidArgument(key + " must be a whole number from " + std::to_string(min) + " to " +
                                   std::to_string(max) + ", got '" + value + "'");
  }
  *out = parsed;
  return Status::Ok();
}

// `min` 1 for limits: 0 would refuse every request.
template <typename T>
Status SetUnsigned(const std::string& key, const std::string& value, T* field, uint64_t min = 0,
                   uint64_t max = std::numeric_limits<T>::max()) {
  uint64_t parsed = 0;
  Status status = ParseUnsigned(key, value, min, max, &parsed);
  if (status.ok()) *field = static_cast<T>(parsed);
  return status;
}

// A number for which `valid` holds; `what` describes it in the error (e.g.
// "a number of metres in (0, 50]").
template <typename Valid>
Status SetNumber(const std::string& key, const std::string& value, Valid valid, const std::string& what,
                 double* field) {
  char* end = nullptr;
  const double parsed = std::strtod(value.c_str(), &end);
  if (value.empty() || *end != '\0' || !valid(parsed)) {
    return Status::InvalidArgument(key + " must be " + what + ", got '" + value + "'");
  }
  *field = parsed;
  return Status::Ok();
}

Status SetBool(const std::string& key, const std::string& value, bool* field) {
  if (value == "true" || value == "1" || value == "yes") {
    *field = true;
  } else if (value == "false" || value == "0" || value == "no") {
    *field = false;
  } else {
    return Status::InvalidArgument(key + " must be true or false, got '" + value + "'");
  }
  return Status::Ok();
}

}  // namespace

Status SetConfigValue(const std::string& key, const std::string& value, ServerConfig* config) {
  if (key == "listen") { config->listen = value; return Status::Ok(); }
  if (key == "data_dir") { config->data_dir = value; return Status::Ok(); }
  if (key == "log_level") { config->log_level = value; return Status::Ok(); }
  if (key == "max_message_bytes") {
    uint64_t parsed = 0;
    Status status = ParseUnsigned(key, value, 4096, std::numeric_limits<int>::max(), &parsed);
    if (status.ok()) config->max_message_bytes = static_cast<int>(parsed);
    return status;
  }
  if (key == "max_points_per_map") return SetUnsigned(key, value, &config->max_points_per_map, 1);
  if (key == "max_scans_per_map") return SetUnsigned(key, value, &config->max_scans_per_map, 1);
  if (key == "max_beams_per_scan") return SetUnsigned(key, value, &config->max_beams_per_scan, 1);
  if (key == "max_maps_per_batch") return SetUnsigned(key, value, &config->max_maps_per_batch, 1);
  if (key == "max_top_k") return SetUnsigned(key, value, &config->max_top_k, 1);
  if (key == "max_verify_candidates") return SetUnsigned(key, value, &config->max_verify_candidates);
  if (key == "max_collections") return SetUnsigned(key, value, &config->max_collections, 1);
  if (key == "max_sequence_maps") return SetUnsigned(key, value, &config->max_sequence_maps, 1);
  if (key == "max_abs_coordinate_m") {
    return SetNumber(key, value, [](double m) { return m > 0 && m <= 1e9; }, "a positive number of metres",
                     &config->max_abs_coordinate_m);
  }
  if (key == "max_map_extent_m") {
    return SetNumber(key, value, [](double m) { return m > 0 && m <= 1150; }, "a number of metres in (0, 1150]",
                     &config->max_map_extent_m);
  }
  if (key == "max_query_seconds") {
    return SetNumber(key, value, [](double s) { return s >= 0 && s <= 86400; }, "a number of seconds in [0, 86400]",
                     &config->max_query_seconds);
  }
  if (key == "tls_cert_file") { config->tls_cert_file = value; return Status::Ok(); }
  if (key == "tls_key_file") { config->tls_key_file = value; return Status::Ok(); }
  if (key == "tls_client_ca_file") { config->tls_client_ca_file = value; return Status::Ok(); }
  if (key == "tokens_file") { config->tokens_file = value; return Status::Ok(); }
  if (key == "metrics_listen") { config->metrics_listen = value; return Status::Ok(); }
  if (key == "cluster_etcd") { config->cluster_etcd = value; return Status::Ok(); }
  if (key == "cluster_node_id") { config->cluster_node_id = value; return Status::Ok(); }
  if (key == "cluster_advertise") { config->cluster_advertise = value; return Status::Ok(); }
  if (key == "cluster_zone") { config->cluster_zone = value; return Status::Ok(); }
  if (key == "cluster_prefix") { config->cluster_prefix = value; return Status::Ok(); }
  if (key == "cluster_token_file") { config->cluster_token_file = value; return Status::Ok(); }
  if (key == "cluster_tls_ca_file") { config->cluster_tls_ca_file = value; return Status::Ok(); }
  if (key == "cluster_tls_server_name") { config->cluster_tls_server_name = value; return Status::Ok(); }
  if (key == "cluster_replication_factor") return SetUnsigned(key, value, &config->cluster_replication_factor, 1);
  if (key == "cluster_replace_after_s") return SetUnsigned(key, value, &config->cluster_replace_after_s);
  if (key == "cluster_lease_ttl_s") return SetUnsigned(key, value, &config->cluster_lease_ttl_s, 1);
  if (key == "cluster_replicate_timeout_ms") {
    return SetUnsigned(key, value, &config->cluster_replicate_timeout_ms, 1, kMaxReplicateTimeoutMs);
  }
  if (key == "cluster_log_mb") return SetUnsigned(key, value, &config->cluster_log_mb);
  if (key == "worker_threads") return SetUnsigned(key, value, &config->worker_threads, 0, kMaxWorkerThreads);
  if (key == "max_queued_calls") return SetUnsigned(key, value, &config->max_queued_calls, 1);
  if (key == "verify_candidates") return SetUnsigned(key, value, &config->verify_candidates);
  if (key == "retain_maps_per_collection") return SetUnsigned(key, value, &config->retain_maps_per_collection);
  if (key == "insert_request_ids_kept") return SetUnsigned(key, value, &config->insert_request_ids_kept, 1);
  if (key == "busy_queued_calls") return SetUnsigned(key, value, &config->busy_queued_calls);
  if (key == "busy_verify_candidates") return SetUnsigned(key, value, &config->busy_verify_candidates);
  if (key == "busy_search_candidates") return SetUnsigned(key, value, &config->busy_search_candidates);
  for (const char* removed : {"max_maps_scored", "busy_max_maps_scored", "reverse_conflict_weight",
                              "verify_enough_matches", "default_max_offset_m", "bound_skip_postings_per_map"}) {
    if (key == removed) {
      return Status::InvalidArgument(key + " was removed: the default method no longer ranks with the LMD index "
                                           "(core/localize; README 'What a query returns')");
    }
  }
  if (key == "prepared_map_cache_entries") {
    return Status::InvalidArgument(
        "prepared_map_cache_entries was replaced by prepared_map_cache_mb (MiB of prepared maps)");
  }
  if (key == "prepared_map_cache_mb") return SetUnsigned(key, value, &config->prepared_map_cache_mb);
  if (key == "descriptor_cache_entries") return SetUnsigned(key, value, &config->descriptor_cache_entries);
  if (key == "sync_writes") return SetBool(key, value, &config->sync_writes);
  if (key == "inner_words") return SetBool(key, value, &config->inner_words);
  if (key == "paper_index") return SetBool(key, value, &config->paper_index);
  if (key == "allow_insecure_remote") return SetBool(key, value, &config->allow_insecure_remote);
  return Status::InvalidArgument("unknown setting '" + key + "'");
}

Status LoadConfigFile(const std::string& path, ServerConfig* config) {
  std::ifstream in(path);
  if (!in) return Status::IoError("cannot read config file " + path);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    line = Trim(line);
    if (line.empty()) continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      return Status::InvalidArgument(path + ":" + std::to_string(number) + ": expected 'key = value'");
    }
    Status status = SetConfigValue(Trim(line.substr(0, eq)), Trim(line.substr(eq + 1)), config);
    if (!status.ok()) {
      return Status::InvalidArgument(path + ":" + std::to_string(number) + ": " + status.message());
    }
  }
  return Status::Ok();
}

bool IsLoopbackAddress(const std::string& host_port) {
  const Result<HostPort> address = ParseHostPort(host_port, 0, "address");
  if (!address.ok()) return false;
  const std::string& host = address->host;
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

}  // namespace lmd::server
