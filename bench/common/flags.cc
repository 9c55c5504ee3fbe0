#include "bench/common/flags.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace lmd {

Flags::Flags(std::vector<std::string> valued, std::vector<std::string> booleans)
    : valued_(std::move(valued)), booleans_(std::move(booleans)) {}

bool Flags::Declared(const std::string& name, bool* valued) const {
  *valued = std::find(valued_.begin(), valued_.end(), name) != valued_.end();
  return *valued || std::find(booleans_.begin(), booleans_.end(), name) != booleans_.end();
}

bool Flags::Parse(int argc, char** argv, int first) {
  std::string current;  // the valued flag collecting values (--log a b c)
  for (int i = first; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--", 0) != 0) {
      if (current.empty()) {
        error_ = "unexpected argument '" + a + "'";
        return false;
      }
      values_[current].push_back(a);  // a further value of a repeatable flag
      continue;
    }
    std::string name = a.substr(2);
    const size_t eq = name.find('=');
    if (eq != std::string::npos) name = name.substr(0, eq);
    bool valued = false;
    if (!Declared(name, &valued)) {
      std::string known;
      for (const std::vector<std::string>* list : {&valued_, &booleans_}) {
        for (const std::string& k : *list) known += (known.empty() ? "--" : ", --") + k;
      }
      error_ = "unknown flag --" + name + (known.empty() ? " (it takes none)" : " (it takes " + known + ")");
      return false;
    }
    current.clear();
    if (!valued) {
      if (eq != std::string::npos) {
        error_ = "flag --" + name + " takes no value";
        return false;
      }
      values_[name].push_back("1");
    } else if (eq != std::string::npos) {
      values_[name].push_back(a.substr(2 + eq + 1));
    } else if (i + 1 >= argc || std::string(argv[i + 1]).rfind("--", 0) == 0) {
      error_ = "flag --" + name + " needs a value";
      return false;
    } else {
      values_[name].push_back(argv[++i]);
      current = name;
    }
  }
  return true;
}

std::string Flags::Get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() || it->second.empty() ? fallback : it->second.back();
}

std::vector<std::string> Flags::GetAll(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

bool Flags::Number(const std::string& name, double lo, double hi, double fallback, double* out) {
  *out = fallback;
  if (!Has(name)) return true;
  const std::string v = Get(name);
  char* end = nullptr;
  errno = 0;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || errno == ERANGE || !(x >= lo && x <= hi)) {
    char range[96];
    std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
    error_ = "--" + name + " must be a number in " + range + ", got '" + v + "'";
    return false;
  }
  *out = x;
  return true;
}

bool Flags::Count(const std::string& name, uint64_t lo, uint64_t hi, uint64_t fallback, uint64_t* out) {
  *out = fallback;
  if (!Has(name)) return true;
  const std::string v = Get(name);
  char* end = nullptr;
  errno = 0;
  const unsigned long long x = std::strtoull(v.c_str(), &end, 10);
  if (v.empty() || v[0] < '0' || v[0] > '9' || *end != '\0' || errno == ERANGE || x < lo || x > hi) {
    error_ = "--" + name + " must be a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) +
             ", got '" + v + "'";
    return false;
  }
  *out = x;
  return true;
}

}  // namespace lmd
