// A small command-line parser for lmdctl: "--key value" options, "--flag"
// switches, and positional words.
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/status.h"

namespace lmd::cli {

struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;  // without the leading "--"
  std::set<std::string> switches;              // without the leading "--"

  bool Has(const std::string& key) const { return options.count(key) > 0; }
  bool Switch(const std::string& name) const { return switches.count(name) > 0; }
  // The option's value, or `fallback` if absent.
  std::string Get(const std::string& key, const std::string& fallback = "") const;
};

// Parses argv[first..argc). Names in `switch_names` take no value; every other
// "--name" takes the next word. InvalidArgument if a value is missing.
Result<Args> ParseArgs(int argc, char** argv, int first, const std::set<std::string>& switch_names);

// The option as a whole number in [1, max], InvalidArgument naming it otherwise.
Result<long> GetPositive(const Args& args, const std::string& key, long fallback, long max = 1000000);

// The option as a number of `unit` in [lo, hi], InvalidArgument "--key must
// be a number of <unit> from lo to hi, got '...'" otherwise.
Result<double> GetNumber(const Args& args, const std::string& key, const std::string& unit, double fallback, double lo,
                         double hi);
// ... of metres.
Result<double> GetMetres(const Args& args, const std::string& key, double fallback, double lo, double hi);

// "A,B,C" as finite numbers; InvalidArgument (without naming the option:
// the caller says what it expects) for an empty or non-numeric word.
Result<std::vector<double>> ParseNumberList(const std::string& text);

// InvalidArgument naming the first option that is not in `known` (a typo
// such as --topk must not be ignored).
Status CheckKnownOptions(const Args& args, const std::set<std::string>& known);

}  // namespace lmd::cli
