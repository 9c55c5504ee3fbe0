// Odometry that drifts, for simulated robots that track their pose: the
// relative pose between two of a robot's maps as its wheels would report
// it, how far a pose carried by it can be off, and a local map built on it.
#pragma once

#include <random>

#include "core/types.h"

namespace lmd {

struct OdometryDrift {
  double scale = 0.02;                               // length off by up to this share
  double heading_rad_per_m = 0.5 * 3.14159265358979 / 180;  // heading off by up to this per metre
};

// `from`'s own frame in `to`'s own frame (the truth, from their frames in a
// common one), its length and heading drifted over `travel_m`; the heading
// error builds up along the way, so on average half of it turns the path.
Pose2 DriftedOdometry(const Pose2& from_frame, const Pose2& to_frame, double travel_m, const OdometryDrift& drift,
                      std::mt19937_64& rng);

// `map` as a robot would have built it on odometry that drifts: every step
// of its scans' path lengthened by one share (up to drift.scale) and turned
// by one heading rate (up to drift.heading_rad_per_m per metre of the step),
// both drawn once for the map, as wheels of a slightly wrong size or track
// turn a straight corridor into an arc. The scans are re-posed on that path,
// the trajectory is their poses and the points are taken from them again
// (one per dedup_cell_m, as BuildLocalMaps does); the map states the bound
// (heading_drift_rad_per_m), as a robot that knows its odometry would. The
// first pose, the map's own frame, stays exact; so does `truth`. A map
// without scans has nothing to re-pose and is returned as it is.
LocalMap WithDriftedOdometry(LocalMap map, const OdometryDrift& drift, double dedup_cell_m, std::mt19937_64& rng);

// Position uncertainty (m) of a pose carried `travel_m` by such odometry
// from an exact fix: a floor of 0.3 m, the length error, and the heading
// error's sweep.
double DriftRadius(double travel_m, const OdometryDrift& drift);

}  // namespace lmd
