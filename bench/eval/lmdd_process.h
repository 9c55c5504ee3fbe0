// An lmdd started by lmd-eval for one run: its own data directory and a free
// loopback port, stopped (SIGTERM, then waited for) when the object goes,
// and its data directory deleted then (a run's collections are throwaway;
// kept, they piled up in the temp directory run after run). Its log goes too
// unless lmdd did not exit cleanly.
#pragma once

#include <string>
#include <sys/types.h>

#include "core/status.h"

namespace lmd::eval {

class LmddProcess {
 public:
  // Starts `binary` on 127.0.0.1:0 with `data_dir` (created by lmdd), its
  // output in data_dir + ".log", and waits until it says which port it
  // serves on. IoError with lmdd's output if it exits or does not say so
  // within 30 s.
  static Result<LmddProcess> Start(const std::string& binary, const std::string& data_dir);
  LmddProcess(LmddProcess&& other) noexcept;
  LmddProcess& operator=(LmddProcess&&) = delete;
  LmddProcess(const LmddProcess&) = delete;
  ~LmddProcess();

  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }

 private:
  LmddProcess() = default;
  pid_t pid_ = -1;
  int port_ = 0;
  std::string data_dir_;
};

// lmdd next to this binary in the build tree (<dir>/../server/lmdd), or "".
std::string LmddBesideThisBinary();

}  // namespace lmd::eval
