// Command-line flags of the lmd-eval and lmd-bench commands: "--name value"
// (or "--name=value") pairs, repeatable names ("--log a b c" as the shell
// expands a glob), and "--name" booleans. A command declares every flag it
// takes, so that a mistyped one is refused before an hour-long run starts
// without it, and numbers are read whole: "12abc", "-5" for a count, "nan"
// or a value out of range are refused, never read as something else.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lmd {

class Flags {
 public:
  // `valued`: the flags that take values; `booleans`: those that take none.
  Flags(std::vector<std::string> valued, std::vector<std::string> booleans = {});

  // Parses argv[first..argc). False (error() says why) on a flag not
  // declared, a valued flag without a value, or a stray argument.
  bool Parse(int argc, char** argv, int first = 0);

  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  // Last value of --name, or `fallback`.
  std::string Get(const std::string& name, const std::string& fallback = "") const;
  // All values of --name in order.
  std::vector<std::string> GetAll(const std::string& name) const;
  // The last value of --name as a number in [lo, hi] (`fallback` when the
  // flag is absent). False, with error() naming the flag and the value, when
  // it is not one.
  bool Number(const std::string& name, double lo, double hi, double fallback, double* out);
  // ... as a whole number.
  bool Count(const std::string& name, uint64_t lo, uint64_t hi, uint64_t fallback, uint64_t* out);
  const std::string& error() const { return error_; }

 private:
  bool Declared(const std::string& name, bool* valued) const;

  std::vector<std::string> valued_, booleans_;
  std::map<std::string, std::vector<std::string>> values_;
  std::string error_;
};

}  // namespace lmd
