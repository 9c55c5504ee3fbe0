#include "bench/eval/args.h"

#include <algorithm>

namespace lmd::eval {

bool Args::Parse(int argc, char** argv, int first, const std::vector<std::string>& booleans) {
  std::string current;  // flag collecting values (--log a b c)
  for (int i = first; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--", 0) == 0) {
      std::string name = a.substr(2), value;
      const size_t eq = name.find('=');
      if (eq != std::string::npos) {
        value = name.substr(eq + 1), name = name.substr(0, eq);
        values_[name].push_back(value);
        current.clear();
        continue;
      }
      if (std::find(booleans.begin(), booleans.end(), name) != booleans.end()) {
        values_[name].push_back("1");
        current.clear();
        continue;
      }
      if (i + 1 >= argc || std::string(argv[i + 1]).rfind("--", 0) == 0) {
        error_ = "flag --" + name + " needs a value";
        return false;
      }
      values_[name].push_back(argv[++i]);
      current = name;
    } else if (!current.empty()) {
      values_[current].push_back(a);  // further values of a repeatable flag
    } else {
      error_ = "unexpected argument '" + a + "'";
      return false;
    }
  }
  return true;
}

std::string Args::Get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() || it->second.empty() ? fallback : it->second.back();
}

std::vector<std::string> Args::GetAll(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

}  // namespace lmd::eval
