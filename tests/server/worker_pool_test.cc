// WorkerPool: the threads that run lmdd's calls.
#include "server/worker_pool.h"

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>

namespace lmd::server {
namespace {

// Bytes of address space this process maps now (/proc/self/statm).
rlim_t MappedBytes() {
  std::ifstream statm("/proc/self/statm");
  rlim_t pages = 0;
  statm >> pages;
  return pages * static_cast<rlim_t>(sysconf(_SC_PAGESIZE));
}

TEST(WorkerPoolTest, RunsWhatItIsGiven) {
  std::atomic<int> ran{0};
  {
    Result<std::unique_ptr<WorkerPool>> pool = WorkerPool::Start(2, 8);
    ASSERT_TRUE(pool.ok()) << pool.status().ToString();
    for (int i = 0; i < 8; ++i) EXPECT_TRUE((*pool)->TrySubmit([&ran] { ++ran; }));
  }  // the destructor runs what is queued
  EXPECT_EQ(ran.load(), 8);
}

// A thread the system refuses (here for want of address space for its
// stack, as a pids limit would) is an error lmdd reports, not an abort.
TEST(WorkerPoolDeathTest, AThreadTheSystemRefusesIsAnErrorNotAnAbort) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        rlimit limit{};
        getrlimit(RLIMIT_AS, &limit);
        limit.rlim_cur = MappedBytes() + (64 << 20);  // room for a few 8 MiB stacks, not 4096
        setrlimit(RLIMIT_AS, &limit);
        Result<std::unique_ptr<WorkerPool>> pool = WorkerPool::Start(4096, 1);
        std::fprintf(stderr, "%s\n", pool.ok() ? "started" : pool.status().message().c_str());
        std::exit(pool.ok() ? 1 : 0);
      },
      ::testing::ExitedWithCode(0), "cannot start worker thread [0-9]+ of 4096: .*; lower worker_threads");
}

}  // namespace
}  // namespace lmd::server
