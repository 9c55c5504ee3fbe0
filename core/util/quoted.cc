#include "core/util/quoted.h"

#include <cstdio>

namespace lmd {

std::string Quoted(std::string_view value) {
  constexpr size_t kMaxShown = 80;
  std::string out = "'";
  for (size_t i = 0; i < value.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(value[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      out += static_cast<char>(c);
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", c);
      out += escaped;
    }
  }
  if (value.size() > kMaxShown) out += "...";
  return out + "'";
}

}  // namespace lmd
