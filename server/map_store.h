// MapStore: lmdd's durable store of local maps, on an embedded RocksDB.
//
// Column families: "maps" (key "<collection>/<map id>" -> lmd.v1.StoredMap),
// "metadata" (same key -> lmd.v1.MapMetadata, so listing reads no points),
// "collections" (collection name -> lmd.internal.CollectionRecord) and "meta"
// (store format version). Every insert or delete is one WriteBatch holding the
// maps and the collection counters it changes, so a map is either wholly
// stored and counted or absent. Thread-safe: writes are serialised by
// write_mutex_; reads go to RocksDB directly.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/status.h"
#include "lmd/internal/store.pb.h"
#include "lmd/v1/lmd.pb.h"

namespace rocksdb {
class ColumnFamilyHandle;
class DB;
}  // namespace rocksdb

namespace lmd::server {

struct MapStoreOptions {
  std::string data_dir;      // created if absent
  bool sync_writes = false;  // fsync the WAL before a write returns
};

class MapStore {
 public:
  // Opens (creating if needed) the store in options.data_dir. IoError or
  // Corruption with RocksDB's message if it cannot; never deletes data.
  static Result<std::unique_ptr<MapStore>> Open(const MapStoreOptions& options);
  ~MapStore();
  MapStore(const MapStore&) = delete;
  MapStore& operator=(const MapStore&) = delete;

  // Flushes and closes RocksDB. Called by the destructor if not before; call
  // it explicitly before main returns. Idempotent.
  Status Close();

  // Writes all maps in one batch, durably (WAL) before returning. Empty map
  // ids are assigned ("m" + 12 digits, increasing per collection) and written
  // back into *maps; an existing id is replaced. Collections are created on
  // first insert; ResourceExhausted if that would exceed max_collections.
  // Maps must already be valid (see validate.h).
  Status InsertMaps(std::vector<v1::StoredMap>* maps, uint32_t max_collections);

  // NotFound naming the collection or the map if absent.
  Result<v1::StoredMap> GetMap(const std::string& collection, const std::string& map_id) const;

  // Deletes one map. NotFound naming the collection or map if absent.
  Status DeleteMap(const std::string& collection, const std::string& map_id);

  // Up to `limit` maps' metadata in id order, starting after `after` (empty:
  // from the first). *next is the last id returned when more may follow, else
  // empty. NotFound for an unknown collection.
  Status ListMaps(const std::string& collection, const std::string& after, uint32_t limit,
                  std::vector<v1::MapMetadata>* out, std::string* next) const;

  // Writes a consistent, openable copy of the whole store into `directory`
  // (RocksDB checkpoint: hard links where possible) and returns its size in
  // bytes. InvalidArgument if the directory exists; IoError on failure.
  // Restore = stop lmdd and start it with --data-dir on the copy.
  Result<uint64_t> Backup(const std::string& directory) const;

  // Every collection with its counters, by name.
  std::vector<v1::CollectionInfo> ListCollections() const;
  bool HasCollection(const std::string& collection) const;

 private:
  MapStore() = default;
  Status LoadCollections();
  // The stored metadata of `key`, or NotFound.
  Result<v1::MapMetadata> ReadMetadata(const std::string& key) const;

  rocksdb::DB* db_ = nullptr;
  rocksdb::ColumnFamilyHandle* maps_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* metadata_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* collections_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* meta_cf_ = nullptr;
  bool sync_writes_ = false;

  mutable std::mutex mutex_;
  // State below is protected by mutex_: a cache of the "collections" column
  // family, changed only together with it.
  std::map<std::string, internal::CollectionRecord> collections_;
};

}  // namespace lmd::server
