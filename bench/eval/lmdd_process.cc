#include "bench/eval/lmdd_process.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace lmd::eval {

Result<LmddProcess> LmddProcess::Start(const std::string& binary, const std::string& data_dir) {
  // Its output goes to a file beside the data directory (a pipe would kill
  // lmdd with SIGPIPE once lmd-eval stopped reading it).
  const std::string log_path = data_dir + ".log";
  const int log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (log < 0) return Status::IoError("cannot create " + log_path);
  const pid_t pid = fork();
  if (pid < 0) {
    close(log);
    return Status::IoError("cannot fork lmdd");
  }
  if (pid == 0) {
    dup2(log, STDOUT_FILENO);
    dup2(log, STDERR_FILENO);
    execl(binary.c_str(), binary.c_str(), "--listen", "127.0.0.1:0", "--data-dir", data_dir.c_str(), "--log-level",
          "warn", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(log);
  LmddProcess process;
  process.pid_ = pid;
  process.data_dir_ = data_dir;
  std::string text;
  const std::regex listening("lmdd listening on port ([0-9]+)");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(log_path);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    std::smatch m;
    if (std::regex_search(text, m, listening)) {
      process.port_ = std::stoi(m[1]);
      return process;
    }
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      process.pid_ = -1;
      return Status::IoError("lmdd (" + binary + ") exited: " + text);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return Status::IoError("lmdd (" + binary + ") did not start within 30 s: " + text);
}

LmddProcess::LmddProcess(LmddProcess&& other) noexcept
    : pid_(other.pid_), port_(other.port_), data_dir_(std::move(other.data_dir_)) {
  other.pid_ = -1;
  other.data_dir_.clear();
}

LmddProcess::~LmddProcess() {
  bool clean = true;
  if (pid_ > 0) {
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  }
  if (data_dir_.empty()) return;
  std::error_code error;
  std::filesystem::remove_all(data_dir_, error);
  if (clean) {
    std::filesystem::remove(data_dir_ + ".log", error);
  } else {
    std::fprintf(stderr, "lmdd did not exit cleanly: its log is %s.log\n", data_dir_.c_str());
  }
}

std::string LmddBesideThisBinary() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return "";
  const std::filesystem::path lmdd = self.parent_path().parent_path() / "server" / "lmdd";
  return std::filesystem::exists(lmdd, error) ? lmdd.string() : "";
}

}  // namespace lmd::eval
