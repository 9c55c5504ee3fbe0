#include "client/cli/args.h"

#include <cstdlib>

namespace lmd::cli {

std::string Args::Get(const std::string& key, const std::string& fallback) const {
  const auto it = options.find(key);
  return it == options.end() ? fallback : it->second;
}

Result<Args> ParseArgs(int argc, char** argv, int first, const std::set<std::string>& switch_names) {
  Args args;
  for (int i = first; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.rfind("--", 0) != 0 || word.size() == 2) {
      args.positional.push_back(word);
      continue;
    }
    const std::string name = word.substr(2);
    if (switch_names.count(name)) {
      args.switches.insert(name);
    } else if (i + 1 < argc) {
      args.options[name] = argv[++i];
    } else {
      return Status::InvalidArgument(word + " needs a value");
    }
  }
  return args;
}

Result<long> GetPositive(const Args& args, const std::string& key, long fallback) {
  if (!args.Has(key)) return fallback;
  const std::string value = args.Get(key);
  char* end = nullptr;
  const long parsed = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || parsed <= 0) {
    return Status::InvalidArgument("--" + key + " must be a positive whole number, got '" + value + "'");
  }
  return parsed;
}

}  // namespace lmd::cli
