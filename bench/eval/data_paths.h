// Where lmd-eval finds the real laser logs when none are named.
#pragma once

#include <string>
#include <vector>

namespace lmd::eval {

// The shared data folder: $LMD_DATA_DIR if set; else ../shared/data relative
// to the repository root this binary was built from (known at compile time);
// else ../shared/data, ../../shared/data relative to the working directory.
// Empty if none exists.
std::string DefaultDataDir();

// Every *.log.gz in `dir`, sorted by name.
std::vector<std::string> LogsIn(const std::string& dir);

// What a command measures: the logs it was given (--log) or, with none,
// every log of DefaultDataDir(). Empty, with `error` saying why, if there
// are none.
std::vector<std::string> LogsToMeasure(std::vector<std::string> named, std::string* error);

// The logs the served configuration was tuned on (docs/results.md); the
// others are held out.
const std::vector<std::string>& DefaultTunedOn();

// "aces" for ".../aces.log.gz" (directory and .gz/.log extensions stripped).
std::string DatasetName(const std::string& path);

// True for a bag: an .mcap, .bag or .db3 file, or a directory (rosbag2).
bool IsBagPath(const std::string& path);

}  // namespace lmd::eval
