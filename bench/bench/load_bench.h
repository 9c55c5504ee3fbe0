// lmd-bench load: a fleet of simulated robots against a running lmdd.
//
//   lmd-bench load --server HOST:PORT --collection C --robots R --hz H --seconds S [--json]
//                  [--token T] [--no-seed] [--log CARMEN_LOG] [--mode global|fleet] [--answers FILE]
//
// The collection is first seeded with robot 0's run through the demo world
// (unless --no-seed). Then R robots, each on its own route through that world,
// H times a second insert their newest local map and ask DetectChanges for
// it (excluding that map itself), for S seconds; loopback only, bounded in
// time. Reports calls/s and p50/p95/p99 latency over all calls, errors, and
// how often the top hit of a DetectChanges showed the robot's place (half of
// its points within 0.3 m of the hit's, in the world frame; computed after
// the run, for a collection holding the seed and this run's maps only).
// --log: the world is a real log's local maps instead, the even ones seeded
// and the odd ones driven by the robots, each from its own start. The seeded
// maps are anchored by their true poses (a site map). --mode fleet: each
// robot asks first and stores after, lost (global, then sequence queries)
// until lmdd is sure, then tracking with priors from its last fix and
// odometry off by 2 % and 0.5 deg/m; it reports the share of right fixes
// (pose within 0.2 m / 1 deg of the truth in the site frame); with --json the last line is {"robots": R, "rps": x, "p50_ms": a,
// "p95_ms": b, "p99_ms": c, "errors": n, "place_at_1": p}. --answers FILE
// writes each DetectChanges as answered, one tab-separated line with a header
// (how it was asked, the prior's radius, busy depth, latency, sure, the top
// hit and whether it shows the place, the pose, its error and the truth).
#pragma once

namespace lmd::bench {

int RunLoadBench(int argc, char** argv);

}  // namespace lmd::bench
