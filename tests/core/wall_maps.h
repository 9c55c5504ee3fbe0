// Point maps of plain walls for tests of scan matching and the verdict: a
// room pins a pose in every direction, a corridor only across it. A point
// every 5 cm. Header-only.
#pragma once

#include <cmath>

#include "core/types.h"

namespace lmd::testing {

// The walls of a w x h room centred on the origin, leaving out the points
// within gap_m / 2 of the middle of the north wall.
inline LocalMap RoomWalls(double w, double h, double gap_m = 0.0) {
  LocalMap room;
  for (double t = -w / 2; t <= w / 2 + 1e-9; t += 0.05) {
    room.points.push_back({t, -h / 2});
    if (std::abs(t) > gap_m / 2) room.points.push_back({t, h / 2});
  }
  for (double t = -h / 2 + 0.05; t < h / 2 - 1e-9; t += 0.05) {
    room.points.push_back({-w / 2, t});
    room.points.push_back({w / 2, t});
  }
  return room;
}

// Two parallel walls 2 m apart (y = -1 and 1), from x0 to x1.
inline LocalMap CorridorWalls(double x0, double x1) {
  LocalMap corridor;
  for (double x = x0; x <= x1 + 1e-9; x += 0.05) {
    corridor.points.push_back({x, -1.0});
    corridor.points.push_back({x, 1.0});
  }
  return corridor;
}

}  // namespace lmd::testing
