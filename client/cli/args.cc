#include "client/cli/args.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
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

Result<double> GetNumber(const Args& args, const std::string& key, const std::string& unit, double fallback, double lo,
                         double hi) {
  if (!args.Has(key)) return fallback;
  char* end = nullptr;
  const std::string text = args.Get(key);
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(value >= lo && value <= hi)) {
    char range[64];
    std::snprintf(range, sizeof range, " from %g to %g", lo, hi);
    return Status::InvalidArgument("--" + key + " must be a number of " + unit + range + ", got '" + text + "'");
  }
  return value;
}

Result<double> GetMetres(const Args& args, const std::string& key, double fallback, double lo, double hi) {
  return GetNumber(args, key, "metres", fallback, lo, hi);
}

Result<long> GetPositive(const Args& args, const std::string& key, long fallback, long max) {
  if (!args.Has(key)) return fallback;
  const std::string value = args.Get(key);
  char* end = nullptr;
  errno = 0;
  const long parsed = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || errno == ERANGE || parsed <= 0 || parsed > max) {
    return Status::InvalidArgument("--" + key + " must be a whole number from 1 to " + std::to_string(max) +
                                   ", got '" + value + "'");
  }
  return parsed;
}

Result<std::vector<double>> ParseNumberList(const std::string& text) {
  std::vector<double> values;
  for (size_t begin = 0; begin <= text.size();) {
    const size_t end = std::min(text.find(',', begin), text.size());
    const std::string word = text.substr(begin, end - begin);
    char* stop = nullptr;
    const double v = std::strtod(word.c_str(), &stop);
    if (word.empty() || *stop != '\0' || !std::isfinite(v)) {
      return Status::InvalidArgument("'" + word + "' is not a finite number");
    }
    values.push_back(v);
    begin = end + 1;
  }
  return values;
}

Status CheckKnownOptions(const Args& args, const std::set<std::string>& known) {
  for (const auto& [name, value] : args.options) {
    if (known.count(name) == 0) return Status::InvalidArgument("unknown option --" + name + " (see lmdctl --help)");
  }
  return Status::Ok();
}

}  // namespace lmd::cli
