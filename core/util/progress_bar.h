// ProgressBar: shows how far a long job is (ingesting a log, building an
// index, running an evaluation) on a stream the program chooses, normally
// stderr. On a terminal it redraws one line; elsewhere (CI logs, pipes) it
// prints a line at every 10 % so logs stay short, or nothing at all if the
// program asks (a command-line tool whose stderr carries only its errors).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>

namespace lmd {

class ProgressBar {
 public:
  // What the bar draws when `out` is not a terminal.
  enum class OffTerminal { kTenths, kNothing };

  // `total` steps of `what` (e.g. "maps"), drawn on `out`.
  ProgressBar(std::string label, size_t total, std::FILE* out = stderr,
              OffTerminal off_terminal = OffTerminal::kTenths);
  ~ProgressBar();  // finishes the line if Done was not called

  // Sets the number of steps done (clamped to total) and redraws if needed.
  void Update(size_t done);
  void Add(size_t steps = 1) { Update(done_ + steps); }
  // Draws the final state and ends the line. Idempotent.
  void Done();
  // The job failed: erases the bar's line on a terminal and draws nothing
  // more, so that the error printed next is the last line.
  void Abandon();

 private:
  void Draw(bool final_draw);

  const std::string label_;
  const size_t total_;
  std::FILE* const out_;
  const bool terminal_;
  const bool silent_;  // off a terminal, asked to draw nothing
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_draw_{};
  size_t done_ = 0;
  int last_decile_ = -1;
  bool finished_ = false;
};

}  // namespace lmd
