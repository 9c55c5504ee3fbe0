// MapStore: lmdd's durable store of local maps on an embedded RocksDB, and
// the in-memory index of every collection rebuilt from it.
//
// Column families, keys "<collection>/<map id>" unless said otherwise:
//   maps         -> lmd.v1.StoredMap (points, trajectory, scans, metadata)
//   metadata     -> lmd.v1.MapMetadata (so listing reads no points)
//   descriptors  -> lmd.internal.IndexedMap (index id + encoded LMD)
//   postings     "<collection>/" + posting key (core/index/postings.h) -> value
//   collections  collection name -> lmd.internal.CollectionRecord (counters)
//   requests     kept insert request ids (lmd.internal.InsertRequestRecord)
//   meta         "format", "indexing" (fingerprint of the indexing settings)
// Every insert or delete is ONE WriteBatch holding all of that for its maps,
// so a map is either wholly stored, described, indexed and counted, or
// absent. The in-memory index is changed only after the batch is written.
// At open the indexes are rebuilt from the descriptors and checked against
// the counters; a mismatch is reported, never repaired by deleting data.
//
// Concurrency: writers are serialised by write_mutex_ (RocksDB serialises
// its WAL anyway), held through their RocksDB reads and write. Readers never
// take it: the collection table has its own readers-writer lock, which a
// writer holds exclusively only to publish counters, and each collection's
// index has one, which a writer holds only to add or remove postings. So
// queries run concurrently with each other and wait only for those short
// in-memory steps, never for RocksDB I/O (nor an fsync with sync_writes).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <unordered_set>
#include <vector>

#include "core/index/retrieve_options.h"
#include "core/localize/map_source.h"
#include "core/place/place_index.h"
#include "core/status.h"
#include "core/types.h"
#include "lmd/internal/store.pb.h"
#include "lmd/v1/lmd.pb.h"
#include "server/indexing.h"

namespace rocksdb {
class ColumnFamilyHandle;
class DB;
}  // namespace rocksdb

namespace lmd {
struct RetrieveStats;  // core/index/index.h
}  // namespace lmd

namespace lmd::server {

struct MapStoreOptions {
  std::string data_dir;      // created if absent (see Open)
  bool sync_writes = false;  // fsync the WAL before a write returns
  IndexingConfig indexing;   // must match the store's (checked at open)
};

// A map to insert with its descriptor and place features (computed by the
// caller, outside locks).
struct MapWrite {
  v1::StoredMap map;  // its metadata's anchor, if set, is stored and indexed
  Lmd lmd;
  PlaceFeatures place;
  uint64_t index_id = 0;  // set by InsertMaps: the map's id inside its collection's indexes
};

// A stored map as the default method's indexes know it.
struct IndexedEntry {
  std::string map_id;
  double heading = 0.0;  // its place features' compass heading
};

// A retrieved map: its id in the collection and the index's hit.
struct StoreHit {
  std::string map_id;
  MapHit hit;
};

// Limits of one insert, from lmdd's config.
struct InsertLimits {
  uint32_t max_collections = 1000;
  // A collection keeps at most this many maps: an insert that would exceed it
  // deletes the collection's oldest maps (in insertion order) in the same
  // write, at most 256 more than the insert adds (a lowered cap is reached
  // over several inserts). 0: no cap.
  uint32_t retain_maps = 0;
  // Insert request ids a collection keeps (insert_request_ids_kept): the
  // oldest beyond are forgotten, a few per insert.
  uint32_t request_ids_kept = 10000;
};

// An insert's request id (InsertMapsRequest.request_id) and the fingerprint
// of its maps as sent (computed by the service that took the request).
struct InsertRequestId {
  std::string id;
  uint64_t fingerprint = 0;
};

// A replicated collection's last write (server/cluster): its primary's
// epoch and the write's number. Written in the same batch as the write.
struct ReplicationMark {
  uint64_t epoch = 0;
  uint64_t seq = 0;
};

// A kept insert request id with its record, as a replica copies it.
struct KeptRequest {
  std::string id;
  internal::InsertRequestRecord record;
};

// A stored map with what lmdd computed from it, as a replica copies it.
struct StoredEntry {
  v1::StoredMap map;
  internal::IndexedMap indexed;  // its descriptor and place features (index_id is the source's own)
};

struct CollectionState;

class MapStore {
 public:
  // Opens (creating if needed) the store and rebuilds its indexes. IoError or
  // Corruption with the reason if it cannot (unreadable, other format or
  // indexing settings, inconsistent counters); never deletes data.
  // FailedPrecondition, touching nothing, if data_dir is not a directory, or
  // holds files but no store (no CURRENT): a store is created only in an
  // empty or missing directory.
  static Result<std::unique_ptr<MapStore>> Open(const MapStoreOptions& options);
  ~MapStore();
  MapStore(const MapStore&) = delete;
  MapStore& operator=(const MapStore&) = delete;

  // Flushes and closes RocksDB. Called by the destructor if not before; call
  // it explicitly before main returns. Idempotent.
  Status Close();

  // Writes all maps in one batch, durably (WAL) before returning, then
  // indexes them. Empty map ids are assigned ("m" + 12 digits, increasing per
  // collection) and written back into *maps; an existing id is replaced
  // (its old postings removed in the same batch). Collections are created on
  // first insert; ResourceExhausted if that would exceed max_collections, or
  // if the batch alone holds more than retain_maps maps of one collection.
  // The metadata of maps deleted to keep within retain_maps is appended to
  // *evicted (oldest first; may be null).
  // With `mark`, the batch must hold one collection only, and its
  // replication mark is set in the same write.
  // With `request`, too: if the collection keeps that request id, nothing is
  // written, *maps' metadata becomes what the first insert stored and
  // *replayed (optional) is set (FailedPrecondition if the fingerprint
  // differs); else the id is kept with the stored metadata in the same write.
  Status InsertMaps(std::vector<MapWrite>* maps, const InsertLimits& limits,
                    std::vector<v1::MapMetadata>* evicted = nullptr, const ReplicationMark* mark = nullptr,
                    const InsertRequestId* request = nullptr, bool* replayed = nullptr);

  // NotFound naming the collection or the map if absent.
  Result<v1::StoredMap> GetMap(const std::string& collection, const std::string& map_id) const;
  // The stored metadata of a map. NotFound if absent.
  Result<v1::MapMetadata> GetMetadata(const std::string& collection, const std::string& map_id) const;
  // The stored descriptor of a map. NotFound as GetMap.
  Result<Lmd> GetDescriptor(const std::string& collection, const std::string& map_id) const;

  // Deletes one map with its descriptor and postings. NotFound if absent.
  // With `mark`, the collection's replication mark is set in the same write.
  Status DeleteMap(const std::string& collection, const std::string& map_id, const ReplicationMark* mark = nullptr);
  // Deletes the collection whole (maps, descriptors, postings, kept request
  // ids, counters) in one write; NotFound if absent. A collection created
  // again under that name numbers its maps after the dropped ones, so that
  // caches keyed by index id (PreparedMaps) never mistake a new map for an
  // old one.
  Status DropCollection(const std::string& collection);

  // The collection's replication mark ({0, 0} if unknown or never replicated).
  ReplicationMark MarkOf(const std::string& collection) const;
  // Sets the mark, creating the collection (empty) if absent. With
  // `requests`, the collection's kept insert request ids become these, in
  // the same write (a whole copy from the primary).
  Status SetMark(const std::string& collection, const ReplicationMark& mark,
                 const std::vector<KeptRequest>* requests = nullptr);
  // Every map of the collection from one consistent snapshot, in id order,
  // `chunk` at a time to `emit` (which may stop the walk by returning
  // false), then its kept request ids (oldest first) to `emit_requests`,
  // `chunk` at a time too; *mark receives the mark that snapshot holds.
  // NotFound for an unknown collection.
  Status ForEachMap(const std::string& collection, size_t chunk,
                    const std::function<bool(std::vector<StoredEntry>&&)>& emit,
                    const std::function<bool(std::vector<KeptRequest>&&)>& emit_requests, ReplicationMark* mark) const;

  // Up to `limit` maps' metadata in id order, starting after `after` (empty:
  // from the first). *next is the last id returned when more may follow, else
  // empty. NotFound for an unknown collection.
  Status ListMaps(const std::string& collection, const std::string& after, uint32_t limit,
                  std::vector<v1::MapMetadata>* out, std::string* next) const;

  // The collection's best maps for `query` (see core/index/index.h).
  // NotFound for an unknown collection; InvalidArgument for bad options.
  // `stats` (optional) receives the index's work counters.
  Result<std::vector<StoreHit>> Retrieve(const std::string& collection, const Lmd& query,
                                         const RetrieveOptions& options, RetrieveStats* stats = nullptr) const;

  // The default method's first stage over the collection (PlaceIndex::Search
  // on index ids); maps whose id is in `excluded` are never returned.
  // NotFound for an unknown collection.
  Result<std::vector<PlaceHypothesis>> SearchPlaces(const std::string& collection, const PlaceFeatures& query,
                                                    const PlaceSearchOptions& options,
                                                    const std::unordered_set<std::string>& excluded,
                                                    PlaceSearchStats* stats = nullptr) const;
  // The map behind an index id; NotFound once it is no longer stored.
  Result<IndexedEntry> Indexed(const std::string& collection, uint64_t index_id) const;
  // Its place on its robot's route (metadata robot_id and sequence, when
  // both are set: a sequence of 0 counts as unset); false if unknown.
  bool RouteOf(const std::string& collection, uint64_t index_id, MapSource::Route* route) const;
  // Its anchor in the collection's frame (MapMetadata.anchor), if any.
  std::optional<Pose2> AnchorOf(const std::string& collection, uint64_t index_id) const;
  // Whether the collection has any anchored map (false if unknown).
  bool HasAnchors(const std::string& collection) const;
  // The collection's anchored maps near a disk and nearest a path
  // (AnchorIndex::Near and NearestByPath), those in `excluded` passed over.
  std::vector<MapSource::Anchored> AnchoredNear(const std::string& collection, const Point2& centre, double radius_m,
                                                size_t per_cell, const std::unordered_set<std::string>& excluded) const;
  std::vector<MapSource::Anchored> NearestAnchored(const std::string& collection, const std::vector<Point2>& path,
                                                   double max_gap_m, size_t count,
                                                   const std::unordered_set<std::string>& excluded) const;

  // Writes a consistent, openable copy of the whole store into `directory`
  // (RocksDB checkpoint: hard links where possible) and returns its size in
  // bytes. InvalidArgument if the directory exists, has no parent directory,
  // lies inside the store, or its path or a name in it is longer than the
  // system takes; FailedPrecondition if it cannot be created (read-only,
  // /proc, permissions) or its file system is full; IoError on other
  // failures. Messages quote the directory shortened.
  // Restore = stop lmdd and start it with --data-dir on the copy.
  Result<uint64_t> Backup(const std::string& directory) const;

  // Every collection with its counters, by name.
  std::vector<v1::CollectionInfo> ListCollections() const;
  bool HasCollection(const std::string& collection) const;

  const IndexingConfig& indexing() const { return indexing_; }

 private:
  MapStore();
  Status CheckMeta(const std::string& data_dir);
  Status LoadCollections();
  Status RebuildIndexes();
  // Place features of a descriptor record: decoded, or computed again from
  // the stored map when the record has none of this build's version (*stale
  // is then set, so that the caller writes them back).
  Result<PlaceFeatures> PlaceFeaturesOf(const std::string& key, const internal::IndexedMap& indexed, bool* stale) const;
  // The state of a collection, or nullptr. States are never destroyed while
  // the store is open (dropped ones move to dropped_), so the pointer stays valid. The caller holds
  // collections_mutex_ (shared) or write_mutex_.
  CollectionState* FindCollection(const std::string& collection) const;
  // FindCollection under collections_mutex_ (shared), for a reader that then
  // takes the state's index_mutex.
  const CollectionState* StateOf(const std::string& collection) const;
  // The counters of a collection about to be created. The caller holds write_mutex_.
  internal::CollectionRecord NewRecord(const std::string& collection) const;
  Result<internal::IndexedMap> ReadIndexed(const std::string& key) const;
  Result<v1::MapMetadata> ReadMetadata(const std::string& key) const;
  // The kept record of an insert request id, if any.
  Result<std::optional<internal::InsertRequestRecord>> ReadRequest(const std::string& collection,
                                                                   const std::string& request_id) const;

  rocksdb::DB* db_ = nullptr;
  rocksdb::ColumnFamilyHandle* maps_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* metadata_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* descriptors_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* postings_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* collections_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* meta_cf_ = nullptr;
  rocksdb::ColumnFamilyHandle* requests_cf_ = nullptr;
  bool sync_writes_ = false;
  std::string data_dir_;
  IndexingConfig indexing_;

  // Serialises writers (InsertMaps, DeleteMap).
  std::mutex write_mutex_;
  // Guards the map below and every CollectionState::record (not the states'
  // indexes, which have their own locks): shared to read; exclusive to
  // change, which only a writer holding write_mutex_ does, so a writer may
  // read them without it.
  mutable std::shared_mutex collections_mutex_;
  std::map<std::string, std::unique_ptr<CollectionState>> collections_;
  // Dropped collections' states, emptied, kept while the store is open so
  // that readers holding one stay valid (guarded by collections_mutex_), and
  // the next index id each name had (guarded by write_mutex_).
  std::vector<std::unique_ptr<CollectionState>> dropped_;
  std::map<std::string, uint64_t> dropped_next_index_id_;
};

}  // namespace lmd::server
