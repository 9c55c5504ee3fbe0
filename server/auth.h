// Bearer tokens per collection, with read or write rights.
//
// The tokens file holds one grant per line: `TOKEN COLLECTION RIGHT`, where
// COLLECTION is a name or `*` (every collection, and the server-wide calls:
// ListCollections, Stats of all collections, Backup) and RIGHT is `read` or
// `write` (write includes read). '#' starts a comment. A client sends
// `authorization: Bearer TOKEN` metadata. With no tokens file, every call is
// allowed (lmdd then listens on loopback only, unless told otherwise).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/status.h"

namespace lmd::server {

enum class Access { kRead, kWrite };

class TokenAuthorizer {
 public:
  // An authorizer that allows everything.
  TokenAuthorizer() = default;

  // Loads a tokens file. IoError if unreadable; InvalidArgument naming
  // file:line for a malformed line; InvalidArgument if it holds no grant.
  static Result<TokenAuthorizer> LoadFile(const std::string& path);

  bool enabled() const { return enabled_; }

  // OK if `authorization` (the metadata value, "Bearer TOKEN") grants
  // `access` to `collection` ("" for the server-wide calls, which need a `*`
  // grant). Unauthenticated if the token is missing or unknown;
  // PermissionDenied if it lacks the right.
  Status Check(const std::string& authorization, const std::string& collection, Access access) const;

  // OK if `authorization` holds a known token (or checks are off);
  // Unauthenticated otherwise.
  Status Authenticate(const std::string& authorization) const;

  // True if the token in `authorization` may read `collection` (used to filter
  // ListCollections). Always true when disabled.
  bool CanRead(const std::string& authorization, const std::string& collection) const;

 private:
  struct Grant {
    std::string collection;  // or "*"
    bool write = false;
  };
  // The grants of the token in `authorization`, or nullptr if unknown.
  const std::vector<Grant>* Find(const std::string& authorization) const;

  bool enabled_ = false;
  std::map<std::string, std::vector<Grant>> grants_;  // by token
};

}  // namespace lmd::server
