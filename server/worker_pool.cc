#include "server/worker_pool.h"

#include <algorithm>
#include <string>
#include <system_error>

namespace lmd::server {

WorkerPool::WorkerPool(size_t max_queued) : max_queued_(max_queued) {}

Result<std::unique_ptr<WorkerPool>> WorkerPool::Start(size_t threads, size_t max_queued) {
  std::unique_ptr<WorkerPool> pool(new WorkerPool(max_queued));
  threads = std::max<size_t>(threads, 1);
  pool->threads_.reserve(threads);
  try {
    for (size_t i = 0; i < threads; ++i) pool->threads_.emplace_back([worker = pool.get()] { worker->Work(); });
  } catch (const std::system_error& error) {
    return Status::ResourceExhausted("cannot start worker thread " + std::to_string(pool->threads_.size() + 1) +
                                     " of " + std::to_string(threads) + ": " + error.what() +
                                     "; lower worker_threads");
  }
  return pool;
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  ready_.notify_all();
  for (auto& thread : threads_) thread.join();
}

bool WorkerPool::TrySubmit(std::function<void()> task) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || tasks_.size() >= max_queued_) return false;
    tasks_.push_back(std::move(task));
  }
  ready_.notify_one();
  return true;
}

size_t WorkerPool::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return tasks_.size();
}

void WorkerPool::Work() {
  for (;;) {
    std::function<void()> task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ready_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
      if (tasks_.empty()) return;  // stopping and drained
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    task();
  }
}

}  // namespace lmd::server
