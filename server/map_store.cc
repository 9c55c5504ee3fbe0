#include "server/map_store.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <shared_mutex>
#include <unordered_map>

#include <rocksdb/db.h>
#include <rocksdb/memtablerep.h>
#include <rocksdb/utilities/checkpoint.h>
#include <rocksdb/write_batch.h>
#include <spdlog/spdlog.h>

#include "core/describe/lmd_codec.h"
#include "core/index/index.h"
#include "core/index/postings.h"
#include "core/localize/anchor_index.h"
#include "core/util/fnv1a.h"
#include "proto/convert.h"
#include "server/store_paths.h"
#include "server/validate.h"

namespace lmd::server {

// A collection's counters and in-memory index.
struct CollectionState {
  explicit CollectionState(const IndexOptions& options) : index(Index::Create(options).value()) {}

  internal::CollectionRecord record;  // guarded by MapStore::collections_mutex_

  mutable std::shared_mutex index_mutex;
  // Guarded by index_mutex (shared: queries; exclusive: applying a write).
  Index index;
  PlaceIndex places;
  std::unordered_map<uint64_t, MapSource::Route> routes;  // index id -> route, where known
  AnchorIndex anchors;  // the maps anchored in the collection's frame
  // Index id -> map id. Ids grow with each insert, so the oldest map comes
  // first. A writer (holding MapStore::write_mutex_, as every writer of it
  // does) may read it without index_mutex.
  std::map<uint64_t, std::string> map_ids;
  // Map id -> index id: a request's excluded maps turned into index ids once
  // per store call instead of a look-up in map_ids per stored feature read.
  std::unordered_map<std::string, uint64_t> index_ids;

  void Name(uint64_t id, const std::string& map_id) {
    map_ids[id] = map_id;
    index_ids[map_id] = id;
  }
  void Forget(uint64_t id) {
    const auto it = map_ids.find(id);
    if (it == map_ids.end()) return;
    index_ids.erase(it->second);
    map_ids.erase(it);
  }
};

namespace {

constexpr char kFormatKey[] = "format";
constexpr char kFormatVersion[] = "lmd-store-2";
constexpr char kIndexingKey[] = "indexing";

// Whether an index id is one of the maps a request excludes (by map id);
// empty when it excludes none that is stored. Call with state.index_mutex
// held: the indexes and the ids change together under it.
std::function<bool(uint64_t)> ExcludedFrom(const CollectionState& state, const std::unordered_set<std::string>& excluded) {
  std::unordered_set<uint64_t> ids;
  for (const std::string& map_id : excluded) {
    const auto it = state.index_ids.find(map_id);
    if (it != state.index_ids.end()) ids.insert(it->second);
  }
  if (ids.empty()) return {};
  return [ids = std::move(ids)](uint64_t id) { return ids.count(id) != 0; };
}

// Maps an insert may evict beyond its own count (InsertLimits::retain_maps).
constexpr size_t kMaxExtraEvictions = 256;

std::string MapKey(const std::string& collection, const std::string& map_id) {
  return collection + "/" + map_id;
}

// Keys of the requests column family (lmd.internal.InsertRequestRecord).
std::string RequestKey(const std::string& collection, const std::string& request_id) {
  return collection + "/=" + request_id;
}
std::string RequestOrderKey(const std::string& collection, uint64_t number) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%020llu", static_cast<unsigned long long>(number));
  return collection + "/#" + buffer;
}

// Kept request ids forgotten per insert beyond the limit: a lowered limit is
// reached over several inserts.
constexpr int kMaxRequestsForgotten = 4;

std::string AutoMapId(uint64_t number) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "m%012llu", static_cast<unsigned long long>(number));
  return buffer;
}

// `status` as lmd's (Corruption or IoError) with `message`.
Status FromRocksWithMessage(const rocksdb::Status& status, const std::string& message) {
  if (status.ok()) return Status::Ok();
  if (status.IsCorruption()) return Status::Corruption(message);
  return Status::IoError(message);
}

// ... saying `what` failed, and RocksDB's reason.
Status FromRocks(const rocksdb::Status& status, const std::string& what) {
  return FromRocksWithMessage(status, what + ": " + status.ToString());
}

v1::CollectionInfo ToInfo(const std::string& name, const internal::CollectionRecord& record) {
  v1::CollectionInfo info;
  info.set_name(name);
  info.set_maps(record.maps());
  info.set_points(record.points());
  info.set_postings(record.postings());
  return info;
}

// The route a map's metadata gives (MapStore::RouteOf); false if unset.
bool RouteFromMetadata(const v1::MapMetadata& meta, MapSource::Route* route) {
  if (meta.robot_id().empty() || meta.sequence() == 0) return false;
  *route = {Fnv1a64(meta.robot_id()), meta.sequence()};
  return true;
}

// Anchors map `id` in `anchors` from its metadata's anchor (if any), with
// its box and trajectory from the stored map.
void AnchorFromMetadata(uint64_t id, const v1::MapMetadata& meta, const v1::LocalMap& map, AnchorIndex* anchors) {
  if (!meta.has_anchor()) return;
  Point2 lo{1e300, 1e300}, hi{-1e300, -1e300};
  for (int i = 0; i < map.x_size(); ++i) {
    lo = {std::min<double>(lo.x, map.x(i)), std::min<double>(lo.y, map.y(i))};
    hi = {std::max<double>(hi.x, map.x(i)), std::max<double>(hi.y, map.y(i))};
  }
  std::vector<Pose2> trajectory;
  for (const v1::Pose2& p : map.trajectory()) trajectory.push_back(FromProto(p));
  anchors->Set(id, FromProto(meta.anchor().pose()), lo, hi, trajectory, meta.anchor().derived());
}

// Writes of place features recomputed at open go out in batches of this many.
constexpr size_t kMigrationBatch = 1000;

// What a write does to one collection's index once the batch is durable.
struct IndexChange {
  std::vector<uint64_t> removed;
  std::vector<std::pair<uint64_t, const MapWrite*>> added;
};

// A checkpoint's failure: FailedPrecondition when the backup's file system
// is full (the client's to free), else an IoError or Corruption.
Status CheckpointFailure(const rocksdb::Status& status, const std::string& directory) {
  if (status.ok()) return Status::Ok();
  const std::string message =
      "writing the backup to " + Quoted(directory) + ": " + ShortenPath(status.ToString(), directory);
  return status.IsNoSpace() ? Status::FailedPrecondition(message) : FromRocksWithMessage(status, message);
}

}  // namespace

MapStore::MapStore() = default;

Result<std::unique_ptr<MapStore>> MapStore::Open(const MapStoreOptions& options) {
  const Status usable = CheckDataDirectory(options.data_dir);
  if (!usable.ok()) return usable;
  rocksdb::DBOptions db_options;
  db_options.create_if_missing = true;
  db_options.create_missing_column_families = true;
  // The postings are only written here (start-up rebuilds the index from the
  // descriptors), so their memtable is an unsorted vector, sorted once at
  // flush: a skip list paid a search per key for each of a map's ~80 keys
  // (3 % of lmdd's CPU under lmd-bench load). A vector memtable takes no
  // concurrent writes; the store's writes are serialised anyway.
  db_options.allow_concurrent_memtable_write = false;
  rocksdb::ColumnFamilyOptions postings_options;
  postings_options.memtable_factory = std::make_shared<rocksdb::VectorRepFactory>();
  const std::vector<rocksdb::ColumnFamilyDescriptor> families = {
      {rocksdb::kDefaultColumnFamilyName, {}}, {"maps", {}},        {"metadata", {}}, {"descriptors", {}},
      {"postings", postings_options},          {"collections", {}}, {"meta", {}},
      {"requests", {}}};
  std::vector<rocksdb::ColumnFamilyHandle*> handles;
  rocksdb::DB* db = nullptr;
  const rocksdb::Status opened = rocksdb::DB::Open(db_options, options.data_dir, families, &handles, &db);
  if (!opened.ok()) return FromRocks(opened, "cannot open the store in " + options.data_dir);

  std::unique_ptr<MapStore> store(new MapStore());
  store->db_ = db;
  db->DestroyColumnFamilyHandle(handles[0]);
  store->maps_cf_ = handles[1];
  store->metadata_cf_ = handles[2];
  store->descriptors_cf_ = handles[3];
  store->postings_cf_ = handles[4];
  store->collections_cf_ = handles[5];
  store->meta_cf_ = handles[6];
  store->requests_cf_ = handles[7];
  store->sync_writes_ = options.sync_writes;
  store->data_dir_ = options.data_dir;
  store->indexing_ = options.indexing;

  Status status = store->CheckMeta(options.data_dir);
  if (status.ok()) status = store->LoadCollections();
  if (status.ok()) status = store->RebuildIndexes();
  if (!status.ok()) return status;
  return store;
}

MapStore::~MapStore() { Close(); }

Status MapStore::Close() {
  if (db_ == nullptr) return Status::Ok();
  for (auto* handle :
       {maps_cf_, metadata_cf_, descriptors_cf_, postings_cf_, collections_cf_, meta_cf_, requests_cf_}) {
    db_->DestroyColumnFamilyHandle(handle);
  }
  const rocksdb::Status closed = db_->Close();
  delete db_;
  db_ = nullptr;
  return FromRocks(closed, "closing the store");
}

Status MapStore::CheckMeta(const std::string& data_dir) {
  const std::string fingerprint = Fingerprint(indexing_);
  std::string format;
  const rocksdb::Status read = db_->Get({}, meta_cf_, kFormatKey, &format);
  if (read.IsNotFound()) {  // a new store
    rocksdb::WriteBatch batch;
    batch.Put(meta_cf_, kFormatKey, kFormatVersion);
    batch.Put(meta_cf_, kIndexingKey, fingerprint);
    rocksdb::WriteOptions write_options;
    write_options.sync = true;
    return FromRocks(db_->Write(write_options, &batch), "cannot initialise the store");
  }
  if (!read.ok()) return FromRocks(read, "cannot read the store format");
  if (format != kFormatVersion) {
    return Status::Corruption("store in " + data_dir + " has format '" + format + "', this lmdd reads '" +
                              kFormatVersion + "'");
  }
  std::string stored;
  Status status = FromRocks(db_->Get({}, meta_cf_, kIndexingKey, &stored), "cannot read the indexing settings");
  if (!status.ok()) return status;
  if (stored != fingerprint) {
    return Status::Corruption("store in " + data_dir + " was indexed with other settings (" + stored +
                              "); this lmdd uses (" + fingerprint + "); re-ingest into a new data directory");
  }
  return Status::Ok();
}

Status MapStore::LoadCollections() {
  std::unique_ptr<rocksdb::Iterator> it(db_->NewIterator({}, collections_cf_));
  for (it->SeekToFirst(); it->Valid(); it->Next()) {
    auto state = std::make_unique<CollectionState>(indexing_.index);
    if (!state->record.ParseFromArray(it->value().data(), static_cast<int>(it->value().size()))) {
      return Status::Corruption("collection record '" + it->key().ToString() + "' does not parse");
    }
    collections_[it->key().ToString()] = std::move(state);
  }
  return FromRocks(it->status(), "reading collections");
}

Status MapStore::RebuildIndexes() {
  const auto start = std::chrono::steady_clock::now();
  size_t maps = 0, stale_maps = 0;
  rocksdb::WriteBatch migrated;  // recomputed place features, written back
  std::unique_ptr<rocksdb::Iterator> it(db_->NewIterator({}, descriptors_cf_));
  for (it->SeekToFirst(); it->Valid(); it->Next()) {
    const std::string key = it->key().ToString();
    const auto slash = key.find('/');
    CollectionState* state = slash == std::string::npos ? nullptr : FindCollection(key.substr(0, slash));
    internal::IndexedMap indexed;
    if (state == nullptr || !indexed.ParseFromArray(it->value().data(), static_cast<int>(it->value().size()))) {
      return Status::Corruption("descriptor record '" + key + "' has no collection or does not parse");
    }
    Result<Lmd> lmd = DecodeLmd(indexed.lmd());
    if (!lmd.ok()) return Status::Corruption("descriptor of " + key + ": " + lmd.status().message());
    Status added = state->index.Add(indexed.index_id(), *lmd);
    if (!added.ok()) return Status::Corruption("indexing " + key + ": " + added.message());
    bool stale = false;
    Result<PlaceFeatures> place = PlaceFeaturesOf(key, indexed, &stale);
    if (!place.ok()) return place.status();
    if (stale) {
      indexed.set_place_features(EncodePlaceFeatures(*place));
      migrated.Put(descriptors_cf_, key, indexed.SerializeAsString());
      if (++stale_maps % kMigrationBatch == 0) {
        Status written = FromRocks(db_->Write({}, &migrated), "writing recomputed place features");
        if (!written.ok()) return written;
        migrated.Clear();
        spdlog::info("place features recomputed for {} maps", stale_maps);
      }
    }
    added = state->places.Add(indexed.index_id(), std::move(place).value());
    if (!added.ok()) return Status::Corruption("indexing the place features of " + key + ": " + added.message());
    Result<v1::MapMetadata> meta = ReadMetadata(key);  // absent: the counts below report it
    MapSource::Route route;
    if (meta.ok() && RouteFromMetadata(*meta, &route)) state->routes[indexed.index_id()] = route;
    if (meta.ok() && meta->has_anchor()) {
      std::string value;
      v1::StoredMap stored;
      Status read = FromRocks(db_->Get({}, maps_cf_, key, &value), "reading map " + key);
      if (!read.ok()) return read;
      if (!stored.ParseFromString(value)) return Status::Corruption("stored map " + key + " does not parse");
      AnchorFromMetadata(indexed.index_id(), *meta, stored.map(), &state->anchors);
    }
    state->Name(indexed.index_id(), key.substr(slash + 1));
    if (++maps % 100000 == 0) spdlog::info("rebuilding indexes: {} maps", maps);
  }
  Status status = FromRocks(it->status(), "reading descriptors");
  if (!status.ok()) return status;
  if (migrated.Count() > 0) status = FromRocks(db_->Write({}, &migrated), "writing recomputed place features");
  if (!status.ok()) return status;
  if (stale_maps > 0) spdlog::info("place features (version {}) recomputed for {} maps", kPlaceFeatureVersion, stale_maps);
  // The stored maps themselves, counted by their metadata records.
  std::map<std::string, uint64_t> stored;
  std::unique_ptr<rocksdb::Iterator> meta(db_->NewIterator({}, metadata_cf_));
  for (meta->SeekToFirst(); meta->Valid(); meta->Next()) {
    const std::string key = meta->key().ToString();
    ++stored[key.substr(0, key.find('/'))];
  }
  status = FromRocks(meta->status(), "reading map metadata");
  if (!status.ok()) return status;
  for (const auto& [name, state] : collections_) {
    if (stored[name] != state->record.maps()) {
      return Status::Corruption("collection '" + name + "' is inconsistent: " + std::to_string(stored[name]) +
                                " maps stored, " + std::to_string(state->record.maps()) + " counted");
    }
    if (state->index.size() != state->record.maps() || state->index.PostingCount() != state->record.postings() ||
        state->places.size() != state->record.maps()) {
      return Status::Corruption("collection '" + name + "' is inconsistent: " + std::to_string(state->record.maps()) +
                                " maps and " + std::to_string(state->record.postings()) + " postings counted, " +
                                std::to_string(state->index.size()) + " maps and " +
                                std::to_string(state->index.PostingCount()) + " postings indexed");
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("indexes rebuilt: {} maps in {} collections in {:.2f} s", maps, collections_.size(), seconds);
  return Status::Ok();
}

Result<PlaceFeatures> MapStore::PlaceFeaturesOf(const std::string& key, const internal::IndexedMap& indexed,
                                                bool* stale) const {
  if (!indexed.place_features().empty()) {
    Result<PlaceFeatures> decoded = DecodePlaceFeatures(indexed.place_features());
    if (decoded.ok()) return decoded;
    if (static_cast<uint8_t>(indexed.place_features()[0]) == kPlaceFeatureVersion) {
      return Status::Corruption("place features of " + key + ": " + decoded.status().message());
    }
  }
  std::string value;
  Status read = FromRocks(db_->Get({}, maps_cf_, key, &value), "reading map " + key);
  if (!read.ok()) return read;
  v1::StoredMap stored;
  if (!stored.ParseFromString(value)) return Status::Corruption("stored map " + key + " does not parse");
  *stale = true;
  return PreparePlace(MethodView(FromProto(stored.map())), indexing_.localize).features;
}

CollectionState* MapStore::FindCollection(const std::string& collection) const {
  const auto it = collections_.find(collection);
  return it == collections_.end() ? nullptr : it->second.get();
}

internal::CollectionRecord MapStore::NewRecord(const std::string& collection) const {
  internal::CollectionRecord record;
  const auto dropped = dropped_next_index_id_.find(collection);
  if (dropped != dropped_next_index_id_.end()) record.set_next_index_id(dropped->second);
  return record;
}

Result<internal::IndexedMap> MapStore::ReadIndexed(const std::string& key) const {
  std::string value;
  const rocksdb::Status read = db_->Get({}, descriptors_cf_, key, &value);
  if (read.IsNotFound()) return Status::NotFound("no descriptor for " + key);
  if (!read.ok()) return FromRocks(read, "reading descriptor of " + key);
  internal::IndexedMap indexed;
  if (!indexed.ParseFromString(value)) return Status::Corruption("descriptor of " + key + " does not parse");
  return indexed;
}

Result<v1::MapMetadata> MapStore::ReadMetadata(const std::string& key) const {
  std::string value;
  const rocksdb::Status read = db_->Get({}, metadata_cf_, key, &value);
  if (read.IsNotFound()) return Status::NotFound("no map " + key);
  if (!read.ok()) return FromRocks(read, "reading metadata of " + key);
  v1::MapMetadata meta;
  if (!meta.ParseFromString(value)) return Status::Corruption("metadata of " + key + " does not parse");
  return meta;
}

Result<std::optional<internal::InsertRequestRecord>> MapStore::ReadRequest(const std::string& collection,
                                                                           const std::string& request_id) const {
  std::string value;
  const rocksdb::Status read = db_->Get({}, requests_cf_, RequestKey(collection, request_id), &value);
  if (read.IsNotFound()) return std::optional<internal::InsertRequestRecord>();
  if (!read.ok()) return FromRocks(read, "reading request " + request_id);
  internal::InsertRequestRecord record;
  if (!record.ParseFromString(value)) return Status::Corruption("record of request " + request_id + " does not parse");
  return std::optional<internal::InsertRequestRecord>(std::move(record));
}

Status MapStore::InsertMaps(std::vector<MapWrite>* maps, const InsertLimits& limits,
                            std::vector<v1::MapMetadata>* evicted, const ReplicationMark* mark,
                            const InsertRequestId* request, bool* replayed) {
  std::lock_guard<std::mutex> lock(write_mutex_);
  if (replayed != nullptr) *replayed = false;
  if (request != nullptr) {
    if (maps->empty()) return Status::InvalidArgument("an insert with a request id holds no maps");
    const std::string& collection = maps->front().map.metadata().collection();
    for (const MapWrite& write : *maps) {
      if (write.map.metadata().collection() != collection) {
        return Status::InvalidArgument("an insert with a request id holds maps of one collection only");
      }
    }
    Result<std::optional<internal::InsertRequestRecord>> kept = ReadRequest(collection, request->id);
    if (!kept.ok()) return kept.status();
    if (*kept) {  // a retry: answered as the first time, nothing written
      if ((*kept)->fingerprint() != request->fingerprint || (*kept)->maps_size() != static_cast<int>(maps->size())) {
        return Status::FailedPrecondition("request_id '" + request->id +
                                          "' was used by an earlier insert of other maps into collection '" +
                                          collection + "'");
      }
      for (size_t i = 0; i < maps->size(); ++i) {
        *(*maps)[i].map.mutable_metadata() = (*kept)->maps(static_cast<int>(i));
      }
      if (replayed != nullptr) *replayed = true;
      return Status::Ok();
    }
  }
  // Counters change on copies, published only once the batch is written.
  std::map<std::string, internal::CollectionRecord> records;
  std::map<std::string, IndexChange> changes;
  std::map<std::string, std::pair<uint64_t, const MapWrite*>> written;  // key -> (index id, map) in this batch
  rocksdb::WriteBatch batch;
  size_t new_collections = 0;
  // Keys the batch names itself: an assigned id never takes one of them, nor
  // a stored map's, so that it cannot replace a map its client named.
  std::set<std::string> named;
  for (const MapWrite& write : *maps) {
    const v1::MapMetadata& meta = write.map.metadata();
    if (!meta.map_id().empty()) named.insert(MapKey(meta.collection(), meta.map_id()));
  }
  auto free_auto_id = [&](const std::string& collection, internal::CollectionRecord* record) -> Result<std::string> {
    for (;;) {
      const std::string id = AutoMapId(record->next_auto_id());
      record->set_next_auto_id(record->next_auto_id() + 1);
      const std::string key = MapKey(collection, id);
      if (named.count(key) != 0 || written.count(key) != 0) continue;
      Result<v1::MapMetadata> stored = ReadMetadata(key);
      if (stored.ok()) continue;
      if (stored.status().code() != Status::Code::kNotFound) return stored.status();
      return id;
    }
  };

  // Deletes a stored or earlier-in-batch map's postings and uncounts it.
  auto remove_old = [&](const std::string& collection, const std::string& key,
                        internal::CollectionRecord* record) -> Status {
    uint64_t old_id = 0;
    Lmd old_lmd;
    uint32_t old_points = 0;
    if (auto earlier = written.find(key); earlier != written.end()) {
      old_id = earlier->second.first;
      old_lmd = earlier->second.second->lmd;
      old_points = earlier->second.second->map.metadata().point_count();
      auto& added = changes[collection].added;
      added.erase(std::remove_if(added.begin(), added.end(), [&](const auto& a) { return a.first == old_id; }),
                  added.end());
    } else {
      Result<internal::IndexedMap> indexed = ReadIndexed(key);
      if (!indexed.ok()) return indexed.status().code() == Status::Code::kNotFound ? Status::Ok() : indexed.status();
      Result<Lmd> decoded = DecodeLmd(indexed->lmd());
      Result<v1::MapMetadata> meta = ReadMetadata(key);
      if (!decoded.ok() || !meta.ok()) return Status::Corruption("stored map " + key + " is damaged");
      old_id = indexed->index_id();
      old_lmd = std::move(decoded).value();
      old_points = meta->point_count();
      changes[collection].removed.push_back(old_id);
    }
    Result<std::vector<PostingRecord>> old_postings = PostingsOf(old_id, old_lmd, indexing_.index);
    if (!old_postings.ok()) return old_postings.status();
    for (const auto& posting : *old_postings) batch.Delete(postings_cf_, collection + "/" + posting.key);
    record->set_maps(record->maps() - 1);
    record->set_points(record->points() - old_points);
    record->set_postings(record->postings() - PoseFeatureCount(old_lmd));
    return Status::Ok();
  };

  for (MapWrite& write : *maps) {
    v1::MapMetadata* meta = write.map.mutable_metadata();
    const std::string collection = meta->collection();
    auto record_it = records.find(collection);
    if (record_it == records.end()) {
      const CollectionState* state = FindCollection(collection);
      if (state == nullptr) ++new_collections;
      record_it = records.emplace(collection, state ? state->record : NewRecord(collection)).first;
    }
    internal::CollectionRecord& record = record_it->second;
    if (meta->map_id().empty()) {
      Result<std::string> id = free_auto_id(collection, &record);
      if (!id.ok()) return id.status();
      meta->set_map_id(*id);
    } else {
      record.set_next_auto_id(record.next_auto_id() + 1);
    }
    meta->set_point_count(static_cast<uint32_t>(write.map.map().x_size()));
    const std::string key = MapKey(collection, meta->map_id());

    Status removed = remove_old(collection, key, &record);
    if (!removed.ok()) return removed;

    const uint64_t index_id = record.next_index_id();
    record.set_next_index_id(index_id + 1);
    Result<std::vector<PostingRecord>> postings = PostingsOf(index_id, write.lmd, indexing_.index);
    if (!postings.ok()) return Status::Internal("indexing map " + key + ": " + postings.status().message());
    internal::IndexedMap indexed;
    indexed.set_index_id(index_id);
    indexed.set_lmd(EncodeLmd(write.lmd));
    indexed.set_postings(static_cast<uint32_t>(PoseFeatureCount(write.lmd)));
    indexed.set_place_features(EncodePlaceFeatures(write.place));
    write.index_id = index_id;
    batch.Put(maps_cf_, key, write.map.SerializeAsString());
    batch.Put(metadata_cf_, key, meta->SerializeAsString());
    batch.Put(descriptors_cf_, key, indexed.SerializeAsString());
    for (const auto& posting : *postings) batch.Put(postings_cf_, collection + "/" + posting.key, posting.value);
    record.set_maps(record.maps() + 1);
    record.set_points(record.points() + meta->point_count());
    record.set_postings(record.postings() + PoseFeatureCount(write.lmd));
    written[key] = {index_id, &write};
    changes[collection].added.push_back({index_id, &write});
  }
  if (collections_.size() + new_collections > limits.max_collections) {
    return Status::ResourceExhausted("max_collections (" + std::to_string(limits.max_collections) +
                                     ") reached: cannot create another collection");
  }
  // Over the cap, the collection's oldest maps go in this write: at most the
  // batch's own maps plus kMaxExtraEvictions, so that a lowered cap is reached
  // over several inserts, not in one huge write (nor one huge response).
  std::vector<v1::MapMetadata> oldest;
  if (limits.retain_maps > 0) {
    for (auto& [name, record] : records) {
      const size_t batch_maps = changes[name].added.size();
      if (batch_maps > limits.retain_maps) {
        return Status::ResourceExhausted("the batch holds " + std::to_string(batch_maps) + " maps of collection '" +
                                         name + "', more than retain_maps_per_collection (" +
                                         std::to_string(limits.retain_maps) + ")");
      }
      const CollectionState* state = FindCollection(name);
      if (state == nullptr) continue;
      const std::set<uint64_t> replaced(changes[name].removed.begin(), changes[name].removed.end());
      size_t budget = batch_maps + kMaxExtraEvictions;
      for (auto it = state->map_ids.begin(); it != state->map_ids.end() && budget > 0; ++it) {
        if (record.maps() <= limits.retain_maps) break;
        if (replaced.count(it->first) != 0) continue;  // rewritten by this batch: now the newest
        const std::string key = MapKey(name, it->second);
        Result<v1::MapMetadata> meta = ReadMetadata(key);
        if (!meta.ok()) return meta.status();
        Status removed = remove_old(name, key, &record);
        if (!removed.ok()) return removed;
        batch.Delete(maps_cf_, key);
        batch.Delete(metadata_cf_, key);
        batch.Delete(descriptors_cf_, key);
        oldest.push_back(std::move(meta).value());
        --budget;
      }
    }
  }
  // Checked before the write, so that publishing below cannot fail.
  for (const auto& [name, record] : records) {
    constexpr uint64_t kMaxMaps = std::min<uint64_t>(Index::kMaxMaps, PlaceIndex::kMaxMaps);
    if (record.maps() > kMaxMaps) {
      return Status::ResourceExhausted("collection '" + name + "' would hold " + std::to_string(record.maps()) +
                                       " maps; one collection's index holds at most " + std::to_string(kMaxMaps));
    }
  }
  if (mark != nullptr) {
    if (records.size() != 1) return Status::InvalidArgument("a replicated write holds maps of one collection only");
    records.begin()->second.set_replication_epoch(mark->epoch);
    records.begin()->second.set_replication_seq(mark->seq);
  }
  if (request != nullptr) {
    const std::string& collection = maps->front().map.metadata().collection();
    internal::CollectionRecord& record = records.at(collection);
    internal::InsertRequestRecord kept;
    kept.set_number(record.next_request());
    kept.set_fingerprint(request->fingerprint);
    for (const MapWrite& write : *maps) *kept.add_maps() = write.map.metadata();
    batch.Put(requests_cf_, RequestKey(collection, request->id), kept.SerializeAsString());
    batch.Put(requests_cf_, RequestOrderKey(collection, kept.number()), request->id);
    record.set_next_request(kept.number() + 1);
    for (int i = 0; i < kMaxRequestsForgotten && record.next_request() - record.first_request() > limits.request_ids_kept;
         ++i) {
      const std::string order = RequestOrderKey(collection, record.first_request());
      std::string oldest;
      const rocksdb::Status read = db_->Get({}, requests_cf_, order, &oldest);
      if (!read.ok() && !read.IsNotFound()) return FromRocks(read, "reading the oldest kept request");
      if (read.ok()) batch.Delete(requests_cf_, RequestKey(collection, oldest));
      batch.Delete(requests_cf_, order);
      record.set_first_request(record.first_request() + 1);
    }
  }
  for (const auto& [name, record] : records) batch.Put(collections_cf_, name, record.SerializeAsString());
  rocksdb::WriteOptions write_options;
  write_options.sync = sync_writes_;
  Status status = FromRocks(db_->Write(write_options, &batch), "writing maps");
  if (!status.ok()) return status;
  if (evicted != nullptr) evicted->insert(evicted->end(), oldest.begin(), oldest.end());

  // Durable: now publish counters and index changes.
  for (auto& [name, record] : records) {
    CollectionState* state = nullptr;
    {
      std::unique_lock<std::shared_mutex> collections_lock(collections_mutex_);
      auto& owned = collections_[name];
      if (!owned) owned = std::make_unique<CollectionState>(indexing_.index);
      owned->record = record;
      state = owned.get();
    }
    const IndexChange& change = changes[name];
    std::unique_lock<std::shared_mutex> index_lock(state->index_mutex);
    for (uint64_t id : change.removed) {
      state->index.Remove(id);
      state->places.Remove(id);
      state->routes.erase(id);
      state->anchors.Remove(id);
      state->Forget(id);
    }
    for (const auto& [id, write] : change.added) {
      Status added = state->index.Add(id, write->lmd);
      if (added.ok()) added = state->places.Add(id, write->place);
      if (!added.ok()) return Status::Internal("index out of step with the store: " + added.message());
      MapSource::Route route;
      if (RouteFromMetadata(write->map.metadata(), &route)) state->routes[id] = route;
      AnchorFromMetadata(id, write->map.metadata(), write->map.map(), &state->anchors);
      state->Name(id, write->map.metadata().map_id());
    }
  }
  return Status::Ok();
}

Result<v1::StoredMap> MapStore::GetMap(const std::string& collection, const std::string& map_id) const {
  if (!HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");
  std::string value;
  const rocksdb::Status read = db_->Get({}, maps_cf_, MapKey(collection, map_id), &value);
  if (read.IsNotFound()) return Status::NotFound("no map '" + map_id + "' in collection '" + collection + "'");
  if (!read.ok()) return FromRocks(read, "reading map " + map_id);
  v1::StoredMap map;
  if (!map.ParseFromString(value)) return Status::Corruption("stored map '" + map_id + "' does not parse");
  return map;
}

Result<v1::MapMetadata> MapStore::GetMetadata(const std::string& collection, const std::string& map_id) const {
  Result<v1::MapMetadata> meta = ReadMetadata(MapKey(collection, map_id));
  if (!meta.ok() && meta.status().code() == Status::Code::kNotFound) {
    return Status::NotFound("no map '" + map_id + "' in collection '" + collection + "'");
  }
  return meta;
}

Result<Lmd> MapStore::GetDescriptor(const std::string& collection, const std::string& map_id) const {
  if (!HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");
  Result<internal::IndexedMap> indexed = ReadIndexed(MapKey(collection, map_id));
  if (!indexed.ok()) {
    if (indexed.status().code() != Status::Code::kNotFound) return indexed.status();
    return Status::NotFound("no map '" + map_id + "' in collection '" + collection + "'");
  }
  return DecodeLmd(indexed->lmd());
}

Status MapStore::DeleteMap(const std::string& collection, const std::string& map_id, const ReplicationMark* mark) {
  std::lock_guard<std::mutex> lock(write_mutex_);
  CollectionState* state = FindCollection(collection);
  if (state == nullptr) return Status::NotFound("unknown collection '" + collection + "'");
  const std::string key = MapKey(collection, map_id);
  Result<v1::MapMetadata> meta = ReadMetadata(key);
  if (!meta.ok()) {
    if (meta.status().code() != Status::Code::kNotFound) return meta.status();
    return Status::NotFound("no map '" + map_id + "' in collection '" + collection + "'");
  }
  Result<internal::IndexedMap> indexed = ReadIndexed(key);
  if (!indexed.ok()) return indexed.status();
  Result<Lmd> lmd = DecodeLmd(indexed->lmd());
  if (!lmd.ok()) return Status::Corruption("descriptor of " + key + ": " + lmd.status().message());
  Result<std::vector<PostingRecord>> postings = PostingsOf(indexed->index_id(), *lmd, indexing_.index);
  if (!postings.ok()) return postings.status();

  internal::CollectionRecord record = state->record;
  record.set_maps(record.maps() - 1);
  record.set_points(record.points() - meta->point_count());
  record.set_postings(record.postings() - PoseFeatureCount(*lmd));
  if (mark != nullptr) {
    record.set_replication_epoch(mark->epoch);
    record.set_replication_seq(mark->seq);
  }
  rocksdb::WriteBatch batch;
  batch.Delete(maps_cf_, key);
  batch.Delete(metadata_cf_, key);
  batch.Delete(descriptors_cf_, key);
  for (const auto& posting : *postings) batch.Delete(postings_cf_, collection + "/" + posting.key);
  batch.Put(collections_cf_, collection, record.SerializeAsString());
  rocksdb::WriteOptions write_options;
  write_options.sync = sync_writes_;
  Status status = FromRocks(db_->Write(write_options, &batch), "deleting map " + map_id);
  if (!status.ok()) return status;
  {
    std::unique_lock<std::shared_mutex> collections_lock(collections_mutex_);
    state->record = record;
  }
  std::unique_lock<std::shared_mutex> index_lock(state->index_mutex);
  state->index.Remove(indexed->index_id());
  state->places.Remove(indexed->index_id());
  state->routes.erase(indexed->index_id());
  state->anchors.Remove(indexed->index_id());
  state->Forget(indexed->index_id());
  return Status::Ok();
}

Status MapStore::DropCollection(const std::string& collection) {
  std::lock_guard<std::mutex> lock(write_mutex_);
  CollectionState* state = FindCollection(collection);
  if (state == nullptr) return Status::NotFound("unknown collection '" + collection + "'");
  rocksdb::WriteBatch batch;
  // "<collection>/" up to "<collection>0": every key of the collection ('0'
  // follows '/'; names hold no '/').
  for (auto* cf : {maps_cf_, metadata_cf_, descriptors_cf_, postings_cf_, requests_cf_}) {
    batch.DeleteRange(cf, collection + "/", collection + "0");
  }
  batch.Delete(collections_cf_, collection);
  rocksdb::WriteOptions write_options;
  write_options.sync = sync_writes_;
  Status status = FromRocks(db_->Write(write_options, &batch), "dropping collection " + collection);
  if (!status.ok()) return status;
  dropped_next_index_id_[collection] = state->record.next_index_id();
  {
    std::unique_lock<std::shared_mutex> collections_lock(collections_mutex_);
    auto it = collections_.find(collection);
    dropped_.push_back(std::move(it->second));
    collections_.erase(it);
  }
  std::unique_lock<std::shared_mutex> index_lock(state->index_mutex);
  for (const auto& [id, map_id] : state->map_ids) {
    state->index.Remove(id);
    state->places.Remove(id);
    state->anchors.Remove(id);
  }
  state->routes.clear();
  state->map_ids.clear();
  state->index_ids.clear();
  return Status::Ok();
}

ReplicationMark MapStore::MarkOf(const std::string& collection) const {
  std::shared_lock<std::shared_mutex> lock(collections_mutex_);
  const CollectionState* state = FindCollection(collection);
  if (state == nullptr) return {};
  return {state->record.replication_epoch(), state->record.replication_seq()};
}

Status MapStore::SetMark(const std::string& collection, const ReplicationMark& mark,
                         const std::vector<KeptRequest>* requests) {
  std::lock_guard<std::mutex> lock(write_mutex_);
  CollectionState* state = FindCollection(collection);
  internal::CollectionRecord record = state ? state->record : NewRecord(collection);
  record.set_replication_epoch(mark.epoch);
  record.set_replication_seq(mark.seq);
  rocksdb::WriteBatch batch;
  if (requests != nullptr) {
    // "<collection>/" up to "<collection>0": every key of the collection ('0' follows '/').
    batch.DeleteRange(requests_cf_, collection + "/", collection + "0");
    record.set_first_request(requests->empty() ? 0 : requests->front().record.number());
    record.set_next_request(requests->empty() ? 0 : requests->back().record.number() + 1);
    for (const KeptRequest& kept : *requests) {
      batch.Put(requests_cf_, RequestKey(collection, kept.id), kept.record.SerializeAsString());
      batch.Put(requests_cf_, RequestOrderKey(collection, kept.record.number()), kept.id);
    }
  }
  batch.Put(collections_cf_, collection, record.SerializeAsString());
  rocksdb::WriteOptions write_options;
  write_options.sync = sync_writes_;
  Status status = FromRocks(db_->Write(write_options, &batch), "writing the replication mark of " + collection);
  if (!status.ok()) return status;
  std::unique_lock<std::shared_mutex> collections_lock(collections_mutex_);
  auto& owned = collections_[collection];
  if (!owned) owned = std::make_unique<CollectionState>(indexing_.index);
  owned->record = record;
  return Status::Ok();
}

Status MapStore::ForEachMap(const std::string& collection, size_t chunk,
                            const std::function<bool(std::vector<StoredEntry>&&)>& emit,
                            const std::function<bool(std::vector<KeptRequest>&&)>& emit_requests,
                            ReplicationMark* mark) const {
  if (!HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");
  const rocksdb::Snapshot* snapshot = db_->GetSnapshot();
  rocksdb::ReadOptions read;
  read.snapshot = snapshot;
  auto finish = [&](Status status) {
    db_->ReleaseSnapshot(snapshot);
    return status;
  };
  std::string value;
  rocksdb::Status got = db_->Get(read, collections_cf_, collection, &value);
  internal::CollectionRecord record;
  if (!got.ok() || !record.ParseFromString(value)) return finish(Status::Corruption("record of " + collection));
  *mark = {record.replication_epoch(), record.replication_seq()};
  const std::string prefix = collection + "/";
  std::unique_ptr<rocksdb::Iterator> it(db_->NewIterator(read, maps_cf_));
  std::vector<StoredEntry> entries;
  for (it->Seek(prefix); it->Valid() && it->key().starts_with(prefix); it->Next()) {
    StoredEntry entry;
    if (!entry.map.ParseFromArray(it->value().data(), static_cast<int>(it->value().size()))) {
      return finish(Status::Corruption("stored map " + it->key().ToString() + " does not parse"));
    }
    got = db_->Get(read, descriptors_cf_, it->key(), &value);
    if (!got.ok() || !entry.indexed.ParseFromString(value)) {
      return finish(Status::Corruption("descriptor of " + it->key().ToString()));
    }
    entries.push_back(std::move(entry));
    if (entries.size() == chunk) {
      if (!emit(std::move(entries))) return finish(Status::Cancelled("copy of " + collection + " stopped"));
      entries.clear();
    }
  }
  if (!it->status().ok()) return finish(FromRocks(it->status(), "reading " + collection));
  if (!entries.empty() && !emit(std::move(entries))) return finish(Status::Cancelled("copy of " + collection + " stopped"));
  // The kept request ids, oldest first: their order keys "<collection>/#<number>".
  const std::string order_prefix = collection + "/#";
  std::unique_ptr<rocksdb::Iterator> order(db_->NewIterator(read, requests_cf_));
  std::vector<KeptRequest> kept;
  for (order->Seek(order_prefix); order->Valid() && order->key().starts_with(order_prefix); order->Next()) {
    KeptRequest request;
    request.id = order->value().ToString();
    got = db_->Get(read, requests_cf_, RequestKey(collection, request.id), &value);
    if (!got.ok() || !request.record.ParseFromString(value)) {
      return finish(Status::Corruption("kept request " + request.id + " of " + collection));
    }
    kept.push_back(std::move(request));
    if (kept.size() == chunk) {
      if (!emit_requests(std::move(kept))) return finish(Status::Cancelled("copy of " + collection + " stopped"));
      kept.clear();
    }
  }
  if (!order->status().ok()) return finish(FromRocks(order->status(), "reading the requests of " + collection));
  if (!kept.empty() && !emit_requests(std::move(kept))) {
    return finish(Status::Cancelled("copy of " + collection + " stopped"));
  }
  return finish(Status::Ok());
}

Status MapStore::ListMaps(const std::string& collection, const std::string& after, uint32_t limit,
                          std::vector<v1::MapMetadata>* out, std::string* next) const {
  if (!HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");
  out->clear();
  next->clear();
  const std::string prefix = collection + "/";
  std::unique_ptr<rocksdb::Iterator> it(db_->NewIterator({}, metadata_cf_));
  it->Seek(after.empty() ? prefix : MapKey(collection, after));
  if (!after.empty() && it->Valid() && it->key().ToString() == MapKey(collection, after)) it->Next();
  for (; it->Valid() && it->key().starts_with(prefix); it->Next()) {
    if (out->size() == limit) {
      *next = out->back().map_id();
      break;
    }
    v1::MapMetadata meta;
    if (!meta.ParseFromArray(it->value().data(), static_cast<int>(it->value().size()))) {
      return Status::Corruption("metadata of '" + it->key().ToString() + "' does not parse");
    }
    out->push_back(std::move(meta));
  }
  return FromRocks(it->status(), "listing maps");
}

Result<std::vector<StoreHit>> MapStore::Retrieve(const std::string& collection, const Lmd& query,
                                                 const RetrieveOptions& options, RetrieveStats* stats) const {
  const CollectionState* state = nullptr;
  {
    std::shared_lock<std::shared_mutex> lock(collections_mutex_);
    state = FindCollection(collection);
  }
  if (state == nullptr) return Status::NotFound("unknown collection '" + collection + "'");
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  Result<std::vector<MapHit>> hits = state->index.Retrieve(query, options, stats);
  if (!hits.ok()) return hits.status();
  std::vector<StoreHit> out;
  out.reserve(hits->size());
  for (const MapHit& hit : *hits) out.push_back({state->map_ids.at(hit.map_id), hit});
  return out;
}

Result<std::vector<PlaceHypothesis>> MapStore::SearchPlaces(const std::string& collection, const PlaceFeatures& query,
                                                            const PlaceSearchOptions& options,
                                                            const std::unordered_set<std::string>& excluded,
                                                            PlaceSearchStats* stats) const {
  const CollectionState* state = nullptr;
  {
    std::shared_lock<std::shared_mutex> lock(collections_mutex_);
    state = FindCollection(collection);
  }
  if (state == nullptr) return Status::NotFound("unknown collection '" + collection + "'");
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  const std::function<bool(uint64_t)> by_request = ExcludedFrom(*state, excluded);
  std::function<bool(uint64_t)> is_excluded = by_request;
  if (options.anchored_only) {
    is_excluded = [&](uint64_t id) { return (by_request && by_request(id)) || !state->anchors.Anchor(id); };
  }
  return state->places.Search(query, options, is_excluded, stats);
}

Result<IndexedEntry> MapStore::Indexed(const std::string& collection, uint64_t index_id) const {
  const CollectionState* state = nullptr;
  {
    std::shared_lock<std::shared_mutex> lock(collections_mutex_);
    state = FindCollection(collection);
  }
  if (state == nullptr) return Status::NotFound("unknown collection '" + collection + "'");
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  const auto it = state->map_ids.find(index_id);
  const std::optional<double> heading = state->places.Heading(index_id);
  if (it == state->map_ids.end() || !heading) {
    return Status::NotFound("map " + std::to_string(index_id) + " of collection '" + collection + "' is gone");
  }
  return IndexedEntry{it->second, *heading};
}

bool MapStore::RouteOf(const std::string& collection, uint64_t index_id, MapSource::Route* route) const {
  const CollectionState* state = nullptr;
  {
    std::shared_lock<std::shared_mutex> lock(collections_mutex_);
    state = FindCollection(collection);
  }
  if (state == nullptr) return false;
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  const auto it = state->routes.find(index_id);
  if (it == state->routes.end()) return false;
  *route = it->second;
  return true;
}

std::optional<Pose2> MapStore::AnchorOf(const std::string& collection, uint64_t index_id) const {
  const CollectionState* state = nullptr;
  {
    std::shared_lock<std::shared_mutex> lock(collections_mutex_);
    state = FindCollection(collection);
  }
  if (state == nullptr) return std::nullopt;
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  return state->anchors.Anchor(index_id);
}

bool MapStore::HasAnchors(const std::string& collection) const {
  const CollectionState* state = nullptr;
  {
    std::shared_lock<std::shared_mutex> lock(collections_mutex_);
    state = FindCollection(collection);
  }
  if (state == nullptr) return false;
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  return state->anchors.size() > 0;
}

std::vector<MapSource::Anchored> MapStore::AnchoredNear(const std::string& collection, const Point2& centre,
                                                        double radius_m, size_t per_cell,
                                                        const std::unordered_set<std::string>& excluded) const {
  const CollectionState* state = StateOf(collection);
  if (state == nullptr) return {};
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  return state->anchors.Near(centre, radius_m, per_cell, ExcludedFrom(*state, excluded));
}

std::vector<MapSource::Anchored> MapStore::NearestAnchored(const std::string& collection,
                                                           const std::vector<Point2>& path, double max_gap_m,
                                                           size_t count,
                                                           const std::unordered_set<std::string>& excluded) const {
  const CollectionState* state = StateOf(collection);
  if (state == nullptr) return {};
  std::shared_lock<std::shared_mutex> index_lock(state->index_mutex);
  return state->anchors.NearestByPath(path, max_gap_m, count, ExcludedFrom(*state, excluded));
}

const CollectionState* MapStore::StateOf(const std::string& collection) const {
  std::shared_lock<std::shared_mutex> lock(collections_mutex_);
  return FindCollection(collection);
}

Result<uint64_t> MapStore::Backup(const std::string& directory) const {
  Status status = CheckBackupDirectory(directory, data_dir_);
  if (!status.ok()) return status;
  rocksdb::Checkpoint* checkpoint = nullptr;
  status = FromRocks(rocksdb::Checkpoint::Create(db_, &checkpoint), "preparing a backup");
  if (!status.ok()) return status;
  std::unique_ptr<rocksdb::Checkpoint> owned(checkpoint);
  status = CheckpointFailure(owned->CreateCheckpoint(directory), directory);
  if (!status.ok()) return status;
  std::error_code error;
  uint64_t bytes = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(directory, error)) {
    if (entry.is_regular_file(error)) bytes += entry.file_size(error);
  }
  return bytes;
}

std::vector<v1::CollectionInfo> MapStore::ListCollections() const {
  std::shared_lock<std::shared_mutex> lock(collections_mutex_);
  std::vector<v1::CollectionInfo> infos;
  for (const auto& [name, state] : collections_) infos.push_back(ToInfo(name, state->record));
  return infos;
}

bool MapStore::HasCollection(const std::string& collection) const {
  std::shared_lock<std::shared_mutex> lock(collections_mutex_);
  return FindCollection(collection) != nullptr;
}

}  // namespace lmd::server
