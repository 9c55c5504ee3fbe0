#include "core/util/split.h"

#include <sstream>

namespace lmd {

std::vector<std::string> SplitCommas(const std::string& list) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(list);
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace lmd
