// Minimal command-line flags for lmd-eval commands: "--name value" pairs,
// repeatable names, and "--flag" booleans.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace lmd::eval {

class Args {
 public:
  // Parses argv[first..argc). Returns false (and sets error()) on a value-less
  // flag that is not in `booleans` or a stray positional argument.
  bool Parse(int argc, char** argv, int first, const std::vector<std::string>& booleans = {});

  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  // Last value of --name, or `fallback`.
  std::string Get(const std::string& name, const std::string& fallback = "") const;
  // All values of --name in order (a value may also hold several
  // space-separated entries when the shell passes a glob: --log a b c).
  std::vector<std::string> GetAll(const std::string& name) const;
  const std::string& error() const { return error_; }

 private:
  std::map<std::string, std::vector<std::string>> values_;
  std::string error_;
};

}  // namespace lmd::eval
