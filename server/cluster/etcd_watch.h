// PrefixWatcher: follows every change under a key prefix in etcd from a given
// revision on, and hands the changes to a callback in batches, in revision
// order, each change once. Its own thread holds one Watch stream; when the
// stream fails (the member died, restarted or lost its leader) it opens a new
// one, at the next endpoint, from the revision after the last one delivered,
// so nothing is lost or repeated. When etcd has compacted away history the
// watcher still needs, the changes in between are gone: the watcher then
// reads the whole prefix and delivers it as a reset batch, and follows on
// from there.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/status.h"

namespace grpc {
class ClientContext;
}

namespace lmd::server::cluster {

class EtcdEndpoints;

struct WatchEvent {
  enum class Type { kPut, kDelete };
  Type type = Type::kPut;
  std::string key;
  std::string value;         // empty for kDelete
  int64_t mod_revision = 0;  // the revision of this change
};

struct WatchBatch {
  // false: `events` are the changes that follow those of the previous batch.
  // true: history was compacted, so changes were missed; `events` are a kPut
  // of every key under the prefix as of `revision`: the receiver replaces
  // what it holds with them (a key it holds that is not among them is gone).
  bool reset = false;
  std::vector<WatchEvent> events;
  // The store revision the receiver is at once it has applied the batch.
  int64_t revision = 0;
};

class PrefixWatcher {
 public:
  using BatchCallback = std::function<void(const WatchBatch& batch)>;

  // Made by EtcdClient::WatchPrefix; starts the thread, which calls
  // `on_batch` (never concurrently with itself). `start_revision` <= 0: from
  // the revision current when the first stream opens.
  PrefixWatcher(std::shared_ptr<EtcdEndpoints> endpoints, std::string prefix, int64_t start_revision,
                BatchCallback on_batch);
  // Cancels the stream and joins the thread, promptly, even while etcd is
  // unreachable; on_batch is not running after it returns. Must not be called
  // from on_batch.
  ~PrefixWatcher();
  PrefixWatcher(const PrefixWatcher&) = delete;
  PrefixWatcher& operator=(const PrefixWatcher&) = delete;

  // The first revision not yet delivered: where a new stream starts (0 until
  // the first stream opens, when started "from now").
  int64_t next_revision() const;

 private:
  // How one stream ended.
  struct StreamEnd {
    Status status;           // why it failed (OK when the watcher is stopping)
    bool created = false;    // etcd had accepted the watch (the stream was healthy)
    bool compacted = false;  // the history from next_revision() is gone
  };

  void Run();
  // Follows the prefix over one Watch stream at endpoint `i` until it ends.
  StreamEnd Follow(size_t i);
  // Reads the whole prefix at endpoint `i` (one attempt) and delivers it as
  // a reset batch.
  Status Reload(size_t i);
  bool stopping() const;

  const std::shared_ptr<EtcdEndpoints> endpoints_;
  const std::string prefix_;
  const BatchCallback on_batch_;

  mutable std::mutex mu_;
  // State below is guarded by mu_.
  bool stopping_ = false;
  int64_t next_revision_;
  grpc::ClientContext* stream_ = nullptr;  // the stream's context, for TryCancel

  std::thread thread_;  // last: starts once the rest is built
};

}  // namespace lmd::server::cluster
