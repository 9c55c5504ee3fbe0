// EtcdCluster: real etcd processes (/usr/bin/etcd, Debian's etcd-server) for
// tests: one member, or several forming one cluster, on free loopback ports,
// with their data in a fresh temp dir. Members can be killed, paused and
// restarted on their data. Destruction kills every member and removes the
// dir. Elections are fast (heartbeat 10 ms and election timeout 100 ms for a
// lone member, 50 ms and 500 ms in a cluster), which also lets etcd grant
// leases of 1 s.
#pragma once

#include <sys/types.h>

#include <memory>
#include <string>
#include <vector>

#include "core/status.h"

namespace lmd::testing {

inline constexpr char kEtcdBinary[] = "/usr/bin/etcd";

// A loopback port that nothing listens on (the kernel's pick, released).
int UnusedLoopbackPort();

class EtcdCluster {
 public:
  // Starts `members` members as one cluster and waits (at most 15 s) until
  // each reports itself healthy. FailedPrecondition, saying to run
  // scripts/setup.sh, when etcd is not installed; else why it did not start
  // (with the end of the member's log).
  static Result<std::unique_ptr<EtcdCluster>> Start(int members = 1);
  ~EtcdCluster();
  EtcdCluster(const EtcdCluster&) = delete;
  EtcdCluster& operator=(const EtcdCluster&) = delete;

  // Client address ("127.0.0.1:port") of every member, in member order.
  std::vector<std::string> endpoints() const;
  const std::string& endpoint(int member) const { return members_[member].endpoint; }

  // The member that is the raft leader now, as etcd's /metrics says
  // (etcd_server_is_leader); NotFound while there is none.
  Result<int> Leader() const;

  // SIGKILL, and waits for the process to end.
  void Kill(int member);
  // SIGSTOP: the member keeps its connections but answers nothing.
  void Pause(int member);
  // SIGCONT after Pause.
  void Resume(int member);
  // Starts a killed member again, on the same data dir and ports, and waits
  // until it is healthy.
  Status Restart(int member);

 private:
  struct Member {
    std::string name;
    std::string endpoint;
    int client_port = 0;
    int peer_port = 0;
    pid_t pid = -1;
  };

  EtcdCluster() = default;
  // Starts member `i`'s process (it logs to <dir>/<name>.log).
  Status Launch(int i);
  // Waits until member `i` answers GET /health with "true".
  Status WaitHealthy(int i, int timeout_ms);
  std::string LogTail(int i) const;

  std::string dir_;
  std::string initial_cluster_;  // "m0=http://127.0.0.1:P0,..."
  std::string token_;
  std::vector<Member> members_;
};

}  // namespace lmd::testing
