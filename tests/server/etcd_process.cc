#include "tests/server/etcd_process.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <thread>

namespace lmd::testing {
namespace {

// A socket bound to a loopback port of the kernel's choice; -1 on failure.
int BindLoopback(int* port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof(addr);
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &length) != 0) {
    close(fd);
    return -1;
  }
  *port = ntohs(addr.sin_port);
  return fd;
}

// `n` distinct free loopback ports (held until all are picked).
Result<std::vector<int>> FreePorts(int n) {
  std::vector<int> ports(n), fds;
  for (int& port : ports) {
    const int fd = BindLoopback(&port);
    if (fd < 0) break;
    fds.push_back(fd);
  }
  for (const int fd : fds) close(fd);
  if (static_cast<int>(fds.size()) != n) return Status::IoError("cannot bind a loopback port");
  return ports;
}

// The body of an HTTP GET of `path` on 127.0.0.1:port ("" if it fails).
std::string HttpGet(int port, const std::string& path) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return "";
  timeval timeout{0, 500 * 1000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof(timeout));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::string reply;
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0) {
    const std::string request = "GET " + path + " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
    if (send(fd, request.data(), request.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(request.size())) {
      char buffer[4096];
      ssize_t got;
      while ((got = recv(fd, buffer, sizeof(buffer), 0)) > 0) reply.append(buffer, got);
    }
  }
  close(fd);
  const size_t body = reply.find("\r\n\r\n");
  return body == std::string::npos ? "" : reply.substr(body + 4);
}

std::string Url(int port) { return "http://127.0.0.1:" + std::to_string(port); }

}  // namespace

int UnusedLoopbackPort() {
  int port = 0;
  const int fd = BindLoopback(&port);
  if (fd >= 0) close(fd);
  return port;
}

Result<std::unique_ptr<EtcdCluster>> EtcdCluster::Start(int members) {
  if (access(kEtcdBinary, X_OK) != 0) {
    return Status::FailedPrecondition(std::string(kEtcdBinary) +
                                      " not found: run scripts/setup.sh (it installs Debian's etcd-server)");
  }
  if (members < 1) return Status::InvalidArgument("an etcd cluster needs at least one member");
  std::unique_ptr<EtcdCluster> cluster(new EtcdCluster());
  std::string dir = (std::filesystem::temp_directory_path() / "lmd-etcd-XXXXXX").string();
  if (mkdtemp(dir.data()) == nullptr) return Status::IoError("cannot make a temp dir for etcd");
  cluster->dir_ = dir;
  const Result<std::vector<int>> ports = FreePorts(2 * members);
  if (!ports.ok()) return ports.status();
  std::random_device random;
  cluster->token_ = "lmd-test-" + std::to_string(getpid()) + "-" + std::to_string(random());
  for (int i = 0; i < members; ++i) {
    Member member;
    member.name = "m" + std::to_string(i);
    member.client_port = (*ports)[2 * i];
    member.peer_port = (*ports)[2 * i + 1];
    member.endpoint = "127.0.0.1:" + std::to_string(member.client_port);
    if (i > 0) cluster->initial_cluster_ += ",";
    cluster->initial_cluster_ += member.name + "=" + Url(member.peer_port);
    cluster->members_.push_back(member);
  }
  for (int i = 0; i < members; ++i) {
    if (Status status = cluster->Launch(i); !status.ok()) return status;
  }
  for (int i = 0; i < members; ++i) {
    if (Status status = cluster->WaitHealthy(i, 15000); !status.ok()) return status;
  }
  return cluster;
}

EtcdCluster::~EtcdCluster() {
  for (size_t i = 0; i < members_.size(); ++i) Kill(static_cast<int>(i));
  std::error_code ignored;
  if (!dir_.empty()) std::filesystem::remove_all(dir_, ignored);
}

std::vector<std::string> EtcdCluster::endpoints() const {
  std::vector<std::string> endpoints;
  for (const Member& member : members_) endpoints.push_back(member.endpoint);
  return endpoints;
}

Status EtcdCluster::Launch(int i) {
  const Member& member = members_[i];
  // A lone member has no peers to hear from: it can elect itself at once.
  const bool single = members_.size() == 1;
  std::vector<std::string> args = {
      kEtcdBinary,
      "--name", member.name,
      "--data-dir", dir_ + "/" + member.name,
      "--listen-client-urls", Url(member.client_port),
      "--advertise-client-urls", Url(member.client_port),
      "--listen-peer-urls", Url(member.peer_port),
      "--initial-advertise-peer-urls", Url(member.peer_port),
      "--initial-cluster", initial_cluster_,
      "--initial-cluster-state", "new",
      "--initial-cluster-token", token_,
      "--heartbeat-interval", single ? "10" : "50",
      "--election-timeout", single ? "100" : "500",
      "--unsafe-no-fsync",  // a killed process's writes are in the page cache still
      "--logger", "zap",
      "--log-outputs", "stderr",
      "--log-level", "warn",
  };
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  const std::string log = dir_ + "/" + member.name + ".log";
  const int log_fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  const int null_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (log_fd < 0 || null_fd < 0) return Status::IoError("cannot open " + log);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {  // the child: async-signal-safe calls only
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // etcd dies with the test
    if (getppid() != parent) _exit(1);
    dup2(null_fd, 0);
    dup2(log_fd, 1);
    dup2(log_fd, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(log_fd);
  close(null_fd);
  if (pid < 0) return Status::IoError("cannot fork etcd");
  members_[i].pid = pid;
  return Status::Ok();
}

Status EtcdCluster::WaitHealthy(int i, int timeout_ms) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  const Member& member = members_[i];
  while (true) {
    int wait_status = 0;
    if (waitpid(member.pid, &wait_status, WNOHANG) == member.pid) {
      members_[i].pid = -1;
      return Status::Internal("etcd " + member.name + " exited at start (status " + std::to_string(wait_status) +
                              "): " + LogTail(i));
    }
    if (HttpGet(member.client_port, "/health").find("\"health\":\"true\"") != std::string::npos) {
      return Status::Ok();
    }
    if (std::chrono::steady_clock::now() >= give_up) {
      return Status::DeadlineExceeded("etcd " + member.name + " not healthy after " + std::to_string(timeout_ms) +
                                      " ms: " + LogTail(i));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::string EtcdCluster::LogTail(int i) const {
  std::ifstream in(dir_ + "/" + members_[i].name + ".log");
  const std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return log.size() > 2000 ? log.substr(log.size() - 2000) : log;
}

Result<int> EtcdCluster::Leader() const {
  for (size_t i = 0; i < members_.size(); ++i) {
    if (members_[i].pid < 0) continue;
    if (HttpGet(members_[i].client_port, "/metrics").find("\netcd_server_is_leader 1") != std::string::npos) {
      return static_cast<int>(i);
    }
  }
  return Status::NotFound("no etcd member is leader");
}

void EtcdCluster::Kill(int member) {
  Member& m = members_[member];
  if (m.pid < 0) return;
  kill(m.pid, SIGKILL);
  waitpid(m.pid, nullptr, 0);
  m.pid = -1;
}

void EtcdCluster::Pause(int member) {
  if (members_[member].pid > 0) kill(members_[member].pid, SIGSTOP);
}

void EtcdCluster::Resume(int member) {
  if (members_[member].pid > 0) kill(members_[member].pid, SIGCONT);
}

Status EtcdCluster::Restart(int member) {
  if (members_[member].pid > 0) return Status::FailedPrecondition("etcd " + members_[member].name + " is running");
  if (Status status = Launch(member); !status.ok()) return status;
  return WaitHealthy(member, 15000);
}

}  // namespace lmd::testing
