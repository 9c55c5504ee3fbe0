#include "core/util/progress_bar.h"

#include <unistd.h>

#include <algorithm>

namespace lmd {

ProgressBar::ProgressBar(std::string label, size_t total, std::FILE* out, OffTerminal off_terminal)
    : label_(std::move(label)),
      total_(total),
      out_(out),
      terminal_(isatty(fileno(out)) != 0),
      silent_(!terminal_ && off_terminal == OffTerminal::kNothing) {}

ProgressBar::~ProgressBar() { Done(); }

void ProgressBar::Update(size_t done) {
  done_ = std::min(done, total_);
  if (silent_) return;
  const auto now = std::chrono::steady_clock::now();
  if (terminal_) {
    if (now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
    last_draw_ = now;
    Draw(false);
    return;
  }
  const int decile = total_ == 0 ? 10 : static_cast<int>(10 * done_ / total_);
  if (decile != last_decile_) {
    last_decile_ = decile;
    Draw(false);
  }
}

void ProgressBar::Done() {
  if (finished_) return;
  finished_ = true;
  if (silent_) return;
  // Off a terminal the final state may already be printed by Update.
  if (terminal_ || last_decile_ != 10 || done_ != total_) Draw(true);
}

void ProgressBar::Abandon() {
  if (finished_) return;
  finished_ = true;
  if (terminal_ && last_draw_ != std::chrono::steady_clock::time_point{}) {
    std::fputs("\r\x1b[2K", out_);  // carriage return, erase the line
    std::fflush(out_);
  }
}

void ProgressBar::Draw(bool final_draw) {
  constexpr int kWidth = 30;
  const double fraction = total_ == 0 ? 1.0 : static_cast<double>(done_) / static_cast<double>(total_);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const int filled = static_cast<int>(fraction * kWidth);
  std::string bar(static_cast<size_t>(filled), '=');
  bar.resize(kWidth, ' ');
  if (terminal_) {
    std::fprintf(out_, "\r%s [%s] %zu/%zu %.1fs", label_.c_str(), bar.c_str(), done_, total_, seconds);
    if (final_draw) std::fputc('\n', out_);
  } else {
    std::fprintf(out_, "%s [%s] %zu/%zu %.1fs\n", label_.c_str(), bar.c_str(), done_, total_, seconds);
  }
  std::fflush(out_);
}

}  // namespace lmd
