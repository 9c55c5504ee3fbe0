#include "core/util/line_splitter.h"

#include <utility>
#include <vector>

namespace lmd {
namespace {

// "4 MiB", "64 KiB" or "100 bytes".
std::string SizeText(size_t bytes) {
  if (bytes % (1 << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  if (bytes % (1 << 10) == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}

}  // namespace

LineSplitter::LineSplitter(std::string name, size_t max_line_bytes, std::string why, OnLine on_line)
    : name_(std::move(name)), max_line_bytes_(max_line_bytes), why_(std::move(why)), on_line_(std::move(on_line)) {}

Status LineSplitter::Feed(std::string_view bytes) {
  for (size_t newline; (newline = bytes.find('\n')) != std::string_view::npos;) {
    Status s = EndLine(bytes.substr(0, newline));
    if (!s.ok()) return s;
    bytes.remove_prefix(newline + 1);
  }
  if (bytes.size() > max_line_bytes_ - partial_.size()) return TooLong();
  partial_.append(bytes);
  return Status::Ok();
}

Status LineSplitter::FeedAll(std::istream& in) {
  std::vector<char> block(1 << 16);
  while (in.read(block.data(), static_cast<std::streamsize>(block.size())) || in.gcount() > 0) {
    Status s = Feed(std::string_view(block.data(), static_cast<size_t>(in.gcount())));
    if (!s.ok()) return s;
  }
  return in.bad() ? Status::IoError(name_ + ": read error") : Status::Ok();
}

Status LineSplitter::Finish() { return partial_.empty() ? Status::Ok() : EndLine({}); }

Status LineSplitter::EndLine(std::string_view tail) {
  if (tail.size() > max_line_bytes_ - partial_.size()) return TooLong();
  ++lines_;
  if (partial_.empty()) return on_line_(lines_, tail);  // the whole line is in this piece: no copy
  partial_.append(tail);
  Status s = on_line_(lines_, partial_);
  partial_.clear();
  return s;
}

Status LineSplitter::TooLong() const {
  return Status::InvalidArgument(name_ + ":" + std::to_string(lines_ + 1) + ": line longer than " +
                                 SizeText(max_line_bytes_) + " (" + why_ + ")");
}

}  // namespace lmd
