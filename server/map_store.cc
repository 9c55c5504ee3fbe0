#include "server/map_store.h"

#include <cstdio>
#include <filesystem>

#include <rocksdb/db.h>
#include <rocksdb/utilities/checkpoint.h>
#include <rocksdb/write_batch.h>

namespace lmd::server {
namespace {

constexpr char kFormatKey[] = "format";
constexpr char kFormatVersion[] = "lmd-store-1";

std::string MapKey(const std::string& collection, const std::string& map_id) {
  return collection + "/" + map_id;
}

std::string AutoMapId(uint64_t number) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "m%012llu", static_cast<unsigned long long>(number));
  return buffer;
}

Status FromRocks(const rocksdb::Status& status, const std::string& what) {
  if (status.ok()) return Status::Ok();
  if (status.IsCorruption()) return Status::Corruption(what + ": " + status.ToString());
  return Status::IoError(what + ": " + status.ToString());
}

v1::CollectionInfo ToInfo(const std::string& name, const internal::CollectionRecord& record) {
  v1::CollectionInfo info;
  info.set_name(name);
  info.set_maps(record.maps());
  info.set_points(record.points());
  info.set_postings(record.postings());
  return info;
}

}  // namespace

Result<std::unique_ptr<MapStore>> MapStore::Open(const MapStoreOptions& options) {
  rocksdb::DBOptions db_options;
  db_options.create_if_missing = true;
  db_options.create_missing_column_families = true;
  const std::vector<rocksdb::ColumnFamilyDescriptor> families = {
      {rocksdb::kDefaultColumnFamilyName, {}}, {"maps", {}}, {"metadata", {}}, {"collections", {}}, {"meta", {}}};
  std::vector<rocksdb::ColumnFamilyHandle*> handles;
  rocksdb::DB* db = nullptr;
  const rocksdb::Status opened = rocksdb::DB::Open(db_options, options.data_dir, families, &handles, &db);
  if (!opened.ok()) {
    return FromRocks(opened, "cannot open the store in " + options.data_dir);
  }
  std::unique_ptr<MapStore> store(new MapStore());
  store->db_ = db;
  store->maps_cf_ = handles[1];
  store->metadata_cf_ = handles[2];
  store->collections_cf_ = handles[3];
  store->meta_cf_ = handles[4];
  store->sync_writes_ = options.sync_writes;
  db->DestroyColumnFamilyHandle(handles[0]);

  std::string format;
  const rocksdb::Status read = db->Get({}, store->meta_cf_, kFormatKey, &format);
  if (read.IsNotFound()) {
    rocksdb::WriteOptions write_options;
    write_options.sync = true;
    Status status = FromRocks(db->Put(write_options, store->meta_cf_, kFormatKey, kFormatVersion),
                              "cannot initialise the store");
    if (!status.ok()) return status;
  } else if (!read.ok()) {
    return FromRocks(read, "cannot read the store format");
  } else if (format != kFormatVersion) {
    return Status::Corruption("store in " + options.data_dir + " has format '" + format + "', this lmdd reads '" +
                              kFormatVersion + "'");
  }
  Status loaded = store->LoadCollections();
  if (!loaded.ok()) return loaded;
  return store;
}

MapStore::~MapStore() { Close(); }

Status MapStore::Close() {
  if (db_ == nullptr) return Status::Ok();
  for (auto* handle : {maps_cf_, metadata_cf_, collections_cf_, meta_cf_}) db_->DestroyColumnFamilyHandle(handle);
  const rocksdb::Status closed = db_->Close();
  delete db_;
  db_ = nullptr;
  return FromRocks(closed, "closing the store");
}

Status MapStore::LoadCollections() {
  std::unique_ptr<rocksdb::Iterator> it(db_->NewIterator({}, collections_cf_));
  for (it->SeekToFirst(); it->Valid(); it->Next()) {
    internal::CollectionRecord record;
    if (!record.ParseFromArray(it->value().data(), static_cast<int>(it->value().size()))) {
      return Status::Corruption("collection record '" + it->key().ToString() + "' does not parse");
    }
    collections_[it->key().ToString()] = record;
  }
  return FromRocks(it->status(), "reading collections");
}

Status MapStore::InsertMaps(std::vector<v1::StoredMap>* maps, uint32_t max_collections) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Counters are updated on a copy and published only after the write succeeds.
  std::map<std::string, internal::CollectionRecord> changed;
  std::map<std::string, const v1::StoredMap*> written;  // key -> map in this batch
  rocksdb::WriteBatch batch;
  size_t new_collections = 0;
  for (v1::StoredMap& map : *maps) {
    v1::MapMetadata* meta = map.mutable_metadata();
    const std::string& collection = meta->collection();
    auto record_it = changed.find(collection);
    if (record_it == changed.end()) {
      const auto stored = collections_.find(collection);
      if (stored == collections_.end()) ++new_collections;
      record_it = changed.emplace(collection, stored == collections_.end() ? internal::CollectionRecord()
                                                                            : stored->second).first;
    }
    internal::CollectionRecord& record = record_it->second;
    if (meta->map_id().empty()) meta->set_map_id(AutoMapId(record.next_auto_id()));
    record.set_next_auto_id(record.next_auto_id() + 1);
    meta->set_point_count(static_cast<uint32_t>(map.map().x_size()));

    const std::string key = MapKey(collection, meta->map_id());
    // A replaced map stops counting: either earlier in this batch or stored.
    if (auto previous = written.find(key); previous != written.end()) {
      record.set_maps(record.maps() - 1);
      record.set_points(record.points() - previous->second->metadata().point_count());
    } else {
      Result<v1::MapMetadata> old = ReadMetadata(key);
      if (old.ok()) {
        record.set_maps(record.maps() - 1);
        record.set_points(record.points() - old->point_count());
      } else if (old.status().code() != Status::Code::kNotFound) {
        return old.status();
      }
    }
    record.set_maps(record.maps() + 1);
    record.set_points(record.points() + meta->point_count());
    written[key] = &map;
    batch.Put(maps_cf_, key, map.SerializeAsString());
    batch.Put(metadata_cf_, key, meta->SerializeAsString());
  }
  if (collections_.size() + new_collections > max_collections) {
    return Status::ResourceExhausted("max_collections (" + std::to_string(max_collections) +
                                     ") reached: cannot create another collection");
  }
  for (const auto& [name, record] : changed) batch.Put(collections_cf_, name, record.SerializeAsString());
  rocksdb::WriteOptions write_options;
  write_options.sync = sync_writes_;
  Status status = FromRocks(db_->Write(write_options, &batch), "writing maps");
  if (!status.ok()) return status;
  for (auto& [name, record] : changed) collections_[name] = record;
  return Status::Ok();
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

Result<v1::StoredMap> MapStore::GetMap(const std::string& collection, const std::string& map_id) const {
  if (!HasCollection(collection)) return Status::NotFound("unknown collection '" + collection + "'");
  std::string value;
  const rocksdb::Status read = db_->Get({}, maps_cf_, MapKey(collection, map_id), &value);
  if (read.IsNotFound()) {
    return Status::NotFound("no map '" + map_id + "' in collection '" + collection + "'");
  }
  if (!read.ok()) return FromRocks(read, "reading map " + map_id);
  v1::StoredMap map;
  if (!map.ParseFromString(value)) return Status::Corruption("stored map '" + map_id + "' does not parse");
  return map;
}

Status MapStore::DeleteMap(const std::string& collection, const std::string& map_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto record_it = collections_.find(collection);
  if (record_it == collections_.end()) return Status::NotFound("unknown collection '" + collection + "'");
  const std::string key = MapKey(collection, map_id);
  Result<v1::MapMetadata> old = ReadMetadata(key);
  if (!old.ok()) {
    if (old.status().code() != Status::Code::kNotFound) return old.status();
    return Status::NotFound("no map '" + map_id + "' in collection '" + collection + "'");
  }
  internal::CollectionRecord record = record_it->second;
  record.set_maps(record.maps() - 1);
  record.set_points(record.points() - old->point_count());
  rocksdb::WriteBatch batch;
  batch.Delete(maps_cf_, key);
  batch.Delete(metadata_cf_, key);
  batch.Put(collections_cf_, collection, record.SerializeAsString());
  rocksdb::WriteOptions write_options;
  write_options.sync = sync_writes_;
  Status status = FromRocks(db_->Write(write_options, &batch), "deleting map " + map_id);
  if (status.ok()) record_it->second = record;
  return status;
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

Result<uint64_t> MapStore::Backup(const std::string& directory) const {
  std::error_code error;
  if (std::filesystem::exists(directory, error)) {
    return Status::InvalidArgument("backup directory " + directory + " already exists");
  }
  rocksdb::Checkpoint* checkpoint = nullptr;
  Status status = FromRocks(rocksdb::Checkpoint::Create(db_, &checkpoint), "preparing a backup");
  if (!status.ok()) return status;
  std::unique_ptr<rocksdb::Checkpoint> owned(checkpoint);
  status = FromRocks(owned->CreateCheckpoint(directory), "writing the backup to " + directory);
  if (!status.ok()) return status;
  uint64_t bytes = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(directory, error)) {
    if (entry.is_regular_file(error)) bytes += entry.file_size(error);
  }
  return bytes;
}

std::vector<v1::CollectionInfo> MapStore::ListCollections() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<v1::CollectionInfo> infos;
  for (const auto& [name, record] : collections_) infos.push_back(ToInfo(name, record));
  return infos;
}

bool MapStore::HasCollection(const std::string& collection) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return collections_.count(collection) > 0;
}

}  // namespace lmd::server
