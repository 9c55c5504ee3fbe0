// Comma-separated lists from flags and settings ("a:1,b:2"): the items in
// order, empty ones dropped.
#pragma once

#include <string>
#include <vector>

namespace lmd {

std::vector<std::string> SplitCommas(const std::string& list);

}  // namespace lmd
