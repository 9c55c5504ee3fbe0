// Local outlier factor (Breunig et al. 2000) of 2D points, used to drop
// isolated query features before change detection (DESIGN.md §1).
#pragma once

#include <vector>

#include "core/types.h"

namespace lmd {

// LOF of every point with k nearest neighbours (Euclidean; exactly k
// neighbours, ties broken by index). reach-dist(p, o) = max(k-distance(o),
// d(p, o)); lrd(p) = 1 / mean reach-dist(p, N_k(p)) (the mean is floored at
// 1e-6 m so duplicates stay finite); LOF(p) = mean lrd(N_k(p)) / lrd(p).
// ~1 inside a cluster, > 1 for points sparser than their neighbours. k is
// clamped to n - 1; with fewer than 2 points (or k < 1) every LOF is 1.
// Brute force O(n^2): meant for one map's features (tens to a few thousand).
std::vector<double> LocalOutlierFactors(const std::vector<Point2>& points, int k);

}  // namespace lmd
