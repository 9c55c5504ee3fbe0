// Change detection (paper sec. "Change Detection", DESIGN.md §1): which parts
// of a query map do the retrieved db maps not explain?
//
// 1. LOF (lof.h) over the query features' positions removes outliers
//    (LOF > lof_threshold): isolated features are noise, not changes.
// 2. NN-d (Tax & Duin, 1-NN) per remaining query feature p: its position is
//    predicted in the db map's planned frame through the hit's orientation
//    and offset (db = R(o 90 deg) q + offset); the training set T = the db
//    features inside [-window, window]^2 around that position. Dissimilarity
//    d(a, b) = Hamming distance of the change words + spatial_weight * the
//    Euclidean distance (m) of the (predicted) positions. NN(p) = nearest in
//    T; r(p) = d(p, NN(p)) / max(d(NN(p), NN_T(NN(p))), min_denominator)
//    (NN_T(NN(p)) = nearest other member of T; unrelated_distance when T has
//    one member); p is a change when r(p) > threshold. Empty T: a change with
//    r = empty_window_score (nothing was seen there before).
// 3. Change features of one db map closer than merge_radius (query frame)
//    form one change mask (single linkage): one mask = one detected change.
//    Mask score = its largest r; positions are given in the QUERY MAP'S OWN
//    frame (own = frame.origin + R(frame.heading) * planned).
// Masks are ranked by the db map's score K (then its rank), then by score.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/index/retrieve_options.h"
#include "core/status.h"
#include "core/types.h"

namespace lmd {

struct ChangeDetectorOptions {
  int lof_k = 10;                     // LOF neighbours (>= 1)
  double lof_threshold = 1.6;         // LOF above this drops a query feature (paper: 1.6); inf = keep all
  double window_half_m = 3.0;         // m, training window half-width (paper: 3, i.e. [-3, 3] m)
  double threshold = 1.5;             // T: r above this is a change (paper: 1.5)
  double spatial_weight = 2.0;        // bits per m added to the Hamming distance (paper: 0)
  double min_denominator = 1.0;       // bits, floor of d(NN, NN(NN)) (guards divide by zero)
  double unrelated_distance = 30.0;   // bits, d(NN, NN(NN)) when T has one feature (~60 / 2)
  double empty_window_score = 100.0;  // r of a feature with no db feature in its window
  double merge_radius_m = 1.0;        // m, change features closer than this share a mask; 0 = one per feature
  size_t max_masks = 0;               // masks returned, best first; 0 = all
};

// A db map retrieved for the query, with its descriptor (not owned; must
// outlive the call).
struct ChangeCandidate {
  MapHit hit;
  const Lmd* db = nullptr;
};

// One detected change.
struct ChangeMask {
  uint64_t db_map_id = 0;       // map it was found against
  double map_score = 0.0;       // that map's K
  size_t map_rank = 0;          // that map's rank
  std::vector<Point2> points;   // change features, query map's own frame, m
  std::vector<double> scores;   // r of each point
  Point2 centre;                // mean of points, own frame
  double score = 0.0;           // max r (geometric masks: evidence, geometric_changes.h)
  size_t rank = 0;              // 0 = first
};

// Ranked change masks of `query` against every candidate. InvalidArgument for
// bad options or a null db pointer.
Result<std::vector<ChangeMask>> DetectChanges(const Lmd& query, const std::vector<ChangeCandidate>& candidates,
                                              const ChangeDetectorOptions& options = {});

// r per query feature against one db map (NaN for features LOF removed).
// Exposed for evaluation and tests; DetectChanges uses it.
Result<std::vector<double>> NoveltyScores(const Lmd& query, const MapHit& hit, const Lmd& db,
                                          const ChangeDetectorOptions& options = {});

Status ValidateChangeDetectorOptions(const ChangeDetectorOptions& options);

}  // namespace lmd
