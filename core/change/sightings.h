// What a local map's own scans saw at a point: a laser returned there, or its
// beams passed through it. A static object returns every beam aimed at it
// while the robot builds the map; a person walking by, or foliage the beams
// pass through, returns some beams and lets others through. Change detection
// (geometric_changes.h) uses this to keep moving things out of its masks:
// they are not changes of the map.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.h"

namespace lmd {

struct SightingOptions {
  // m; a beam whose return lies within this of the point's range saw the
  // point; one that returned farther than range + margin passed through it.
  double margin_m = 0.3;
  // Beams with no return clear up to this many metres (or their max_range if
  // smaller), as in the occupancy grid.
  double no_return_clear_m = 30.0;
  // Work bound: when points x scans exceeds this, only every k-th scan is
  // read (k as small as keeps the product under the bound), which keeps the
  // shares of returns and pass-throughs while a map at lmdd's limits (200k
  // points, 2000 scans) costs about a second, not a minute.
  size_t max_point_scan_pairs = 20'000'000;
};

struct Sightings {
  uint32_t returns = 0;  // scans whose beam towards the point returned at it
  uint32_t through = 0;  // scans whose beams towards it passed beyond it
};

// For each point (map's own frame), what `scans` (own frame) saw there. A
// scan sees through a point only when the beam nearest its bearing and both
// neighbours of that beam pass beyond it, so that a beam grazing the edge of
// a static object does not count. Scans that do not cover the bearing, whose
// beam ended before the point (occluded) or that have a non-finite pose or
// range count neither way. Scans beyond the work bound are skipped evenly.
std::vector<Sightings> CountSightings(const std::vector<Point2>& points, const std::vector<Scan>& scans,
                                      const SightingOptions& options = {});

}  // namespace lmd
