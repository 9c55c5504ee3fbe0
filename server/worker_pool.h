// WorkerPool: a fixed number of threads running queued tasks, with a bounded
// queue. The gRPC callback handlers hand their work to it so that gRPC's own
// threads never block on retrieval or RocksDB, the number of calls working at
// once is bounded by the thread count, and memory is bounded by the queue:
// a call that finds the queue full is refused at once (RESOURCE_EXHAUSTED).
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "core/status.h"

namespace lmd::server {

class WorkerPool {
 public:
  // Starts `threads` workers (at least 1); at most `max_queued` tasks wait.
  // ResourceExhausted, the workers already started joined, if the system
  // refuses a thread (std::thread would throw, and lmdd abort).
  static Result<std::unique_ptr<WorkerPool>> Start(size_t threads, size_t max_queued);
  // Runs the tasks already queued, then joins the workers.
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Queues `task`; false (and the task is dropped) if the queue is full or
  // the pool is stopping.
  bool TrySubmit(std::function<void()> task);

  // Tasks waiting (not yet running).
  size_t queued() const;

 private:
  explicit WorkerPool(size_t max_queued);
  void Work();

  const size_t max_queued_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  // State below is protected by mutex_.
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;

  std::vector<std::thread> threads_;
};

}  // namespace lmd::server
