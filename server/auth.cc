#include "server/auth.h"

#include <fstream>
#include <sstream>

namespace lmd::server {

Result<TokenAuthorizer> TokenAuthorizer::LoadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Status::IoError("cannot read tokens file " + path);
  TokenAuthorizer auth;
  auth.enabled_ = true;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::string token, collection, right, extra;
    if (!(words >> token)) continue;
    if (!(words >> collection >> right) || (words >> extra) || (right != "read" && right != "write")) {
      return Status::InvalidArgument(path + ":" + std::to_string(number) +
                                     ": expected 'TOKEN COLLECTION read|write'");
    }
    auth.grants_[token].push_back({collection, right == "write"});
  }
  if (auth.grants_.empty()) return Status::InvalidArgument("tokens file " + path + " holds no grant");
  return auth;
}

const std::vector<TokenAuthorizer::Grant>* TokenAuthorizer::Find(const std::string& authorization) const {
  static const std::string kPrefix = "Bearer ";
  if (authorization.compare(0, kPrefix.size(), kPrefix) != 0) return nullptr;
  const auto it = grants_.find(authorization.substr(kPrefix.size()));
  return it == grants_.end() ? nullptr : &it->second;
}

Status TokenAuthorizer::Authenticate(const std::string& authorization) const {
  if (!enabled_) return Status::Ok();
  if (authorization.empty()) return Status::Unauthenticated("missing 'authorization: Bearer TOKEN' metadata");
  if (Find(authorization) == nullptr) return Status::Unauthenticated("unknown bearer token");
  return Status::Ok();
}

Status TokenAuthorizer::Check(const std::string& authorization, const std::string& collection,
                              Access access) const {
  Status known = Authenticate(authorization);
  if (!enabled_ || !known.ok()) return known;
  const std::vector<Grant>* grants = Find(authorization);
  for (const Grant& grant : *grants) {
    const bool covers = grant.collection == "*" || (!collection.empty() && grant.collection == collection);
    if (covers && (access == Access::kRead || grant.write)) return Status::Ok();
  }
  const std::string what = collection.empty() ? "server-wide calls" : "collection '" + collection + "'";
  return Status::PermissionDenied(std::string("token may not ") + (access == Access::kWrite ? "write" : "read") +
                                  " " + what);
}

bool TokenAuthorizer::CanRead(const std::string& authorization, const std::string& collection) const {
  return Check(authorization, collection, Access::kRead).ok();
}

}  // namespace lmd::server
