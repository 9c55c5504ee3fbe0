// LineSplitter: cuts text that arrives in pieces of any size (a file read in
// blocks, a gzip stream) into lines for a callback, holding at most one line,
// so that a reader never holds the whole file. A "line" longer than its bound
// (binary data, /dev/zero: no newline for ever) is refused as soon as the
// bound is passed, without reading on.
#pragma once

#include <cstddef>
#include <functional>
#include <istream>
#include <string>
#include <string_view>

#include "core/status.h"

namespace lmd {

class LineSplitter {
 public:
  // `on_line(number, text)` gets each line without its '\n', numbered from 1;
  // a non-OK status stops the text there and is returned by Feed / Finish.
  using OnLine = std::function<Status(size_t number, std::string_view text)>;

  // Errors name `name` ("<name>:<line>: line longer than 4 MiB (<why>)");
  // `why` says what a line should be ("a CARMEN record is a few KB").
  LineSplitter(std::string name, size_t max_line_bytes, std::string why, OnLine on_line);

  // The next piece of the text.
  Status Feed(std::string_view bytes);
  // All that `in` holds, in blocks; IoError naming `name` if reading fails.
  Status FeedAll(std::istream& in);
  // The end of the text: passes on its last line if it has no '\n'.
  Status Finish();
  // Lines passed on so far.
  size_t lines() const { return lines_; }

 private:
  Status EndLine(std::string_view tail);
  Status TooLong() const;

  const std::string name_;
  const size_t max_line_bytes_;
  const std::string why_;
  const OnLine on_line_;
  std::string partial_;  // the current line's bytes so far
  size_t lines_ = 0;
};

}  // namespace lmd
