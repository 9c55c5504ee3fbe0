// A MapStore opened directly (no lmdd), and writes for it, for tests of the
// store itself.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "server/map_store.h"
#include "tests/server/test_server.h"

namespace lmd::testing {

// A store in `dir` with the product's indexing (no paper descriptor).
std::unique_ptr<server::MapStore> OpenStore(const TempDir& dir);

// One square room of `points` points for `collection`, described as lmdd
// describes it (id empty: the store assigns one).
std::vector<server::MapWrite> OneWrite(const server::MapStore& store, int points,
                                       const std::string& collection = "site");

}  // namespace lmd::testing
