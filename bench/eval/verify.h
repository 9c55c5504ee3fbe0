// Geometric verification for lmd-eval's "best" pipeline: aligns a query
// map's points to a candidate db map's with the scan matcher of core/align
// (correlative search + ICP) and reports the metric pose and the overlap.
// Kept behind this header (pimpl) so that the align headers never meet the
// index headers in one translation unit.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "core/types.h"

namespace lmd::eval {

struct VerifyConfig {
  double window_m = 2.0;          // m, translation window around each guess (per axis)
  double window_deg = 10.0;       // deg, rotation window around each guess
  bool quarter_turns = true;      // also try each guess turned by 90, 180, 270 deg
  bool global_fallback = true;    // guess-free search when the guided match is poor
  double global_below = 0.5;      // overlap under which the guess-free search runs
  double inlier_radius_m = 0.3;   // m, overlap radius
};

struct Alignment {
  Pose2 pose;             // query own frame in db own frame
  double overlap = 0.0;   // fraction of query points within inlier_radius_m after alignment
  double mean_dist_m = 0.5;  // mean of min(distance to nearest db point, 0.5 m) after alignment
  double conflict = 0.0;  // fraction of query points landing in the db map's free space
};

class Verifier {
 public:
  // `maps` (the dataset's db maps) must outlive the verifier.
  Verifier(const std::vector<LocalMap>* maps, const VerifyConfig& config);
  ~Verifier();
  Verifier(const Verifier&) = delete;
  Verifier& operator=(const Verifier&) = delete;

  // A prepared query (opaque).
  class Query;
  std::shared_ptr<const Query> Prepare(const LocalMap& query) const;

  // Aligns the query to db map `db` near `guesses`; thread-safe (db maps are
  // prepared once, on first use).
  Alignment Align(const Query& query, size_t db, const std::vector<Pose2>& guesses) const;

  // Frees the prepared db maps.
  void Clear();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lmd::eval
