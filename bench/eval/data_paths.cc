#include "bench/eval/data_paths.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

namespace lmd::eval {
namespace fs = std::filesystem;

std::string DefaultDataDir() {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("LMD_DATA_DIR"); env != nullptr && *env) candidates.emplace_back(env);
  // This file is bench/eval/data_paths.cc: the repository root is three levels up.
  const fs::path source = fs::path(__FILE__);
  if (source.is_absolute()) {
    candidates.push_back(source.parent_path().parent_path().parent_path() / ".." / "shared" / "data");
  }
  candidates.emplace_back(fs::path("..") / "shared" / "data");
  candidates.emplace_back(fs::path("..") / ".." / "shared" / "data");
  for (const fs::path& c : candidates) {
    std::error_code ec;
    if (fs::is_directory(c, ec)) return fs::weakly_canonical(c, ec).string();
  }
  return "";
}

std::vector<std::string> LogsIn(const std::string& dir) {
  std::vector<std::string> logs;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > 7 && name.compare(name.size() - 7, 7, ".log.gz") == 0) logs.push_back(entry.path().string());
  }
  std::sort(logs.begin(), logs.end());
  return logs;
}

std::vector<std::string> LogsToMeasure(std::vector<std::string> named, std::string* error) {
  if (!named.empty()) return named;
  const std::string dir = DefaultDataDir();
  if (dir.empty()) {
    *error = "no --log given and no ../shared/data folder found (set LMD_DATA_DIR)";
    return {};
  }
  std::vector<std::string> logs = LogsIn(dir);
  if (logs.empty()) *error = "no *.log.gz in " + dir;
  return logs;
}

bool IsBagPath(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".mcap" || ext == ".bag" || ext == ".db3" || fs::is_directory(path);
}

const std::vector<std::string>& DefaultTunedOn() {
  static const std::vector<std::string> logs = {"aces", "fr079", "intel", "orebro"};
  return logs;
}

std::string DatasetName(const std::string& path) {
  std::string name = fs::path(path).filename().string();
  for (const char* ext : {".gz", ".log", ".mcap", ".bag", ".db3"}) {
    const std::string e = ext;
    if (name.size() > e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0) {
      name.resize(name.size() - e.size());
    }
  }
  return name;
}

}  // namespace lmd::eval
