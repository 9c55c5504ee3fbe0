#include "tests/server/store_fixture.h"

#include "proto/convert.h"
#include "server/indexing.h"

namespace lmd::testing {

std::unique_ptr<server::MapStore> OpenStore(const TempDir& dir) {
  server::MapStoreOptions options;
  options.data_dir = dir.path();
  options.indexing = server::ProductIndexing(false);
  return server::MapStore::Open(options).value();
}

std::vector<server::MapWrite> OneWrite(const server::MapStore& store, int points, const std::string& collection) {
  server::MapWrite write;
  write.map.mutable_metadata()->set_collection(collection);
  *write.map.mutable_map() = SquareRoomMap(points);
  const server::DescribedMap described = server::DescribeMap(FromProto(write.map.map()), store.indexing(), true);
  write.lmd = *described.lmd;
  write.place = described.place.features;
  std::vector<server::MapWrite> maps;
  maps.push_back(std::move(write));
  return maps;
}

}  // namespace lmd::testing
