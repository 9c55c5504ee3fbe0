// A 2D laser log in memory: the scans of one robot run, in line order.
#pragma once

#include <vector>

#include "core/types.h"

namespace lmd {

// Scans in recording order; Scan::pose is the laser pose in the log's global
// frame (for the CARMEN logs in ../shared/data: the scan-matched pose).
struct LaserLog {
  std::vector<Scan> scans;
};

}  // namespace lmd
