// Entropy compass (paper sec. "Approach"): the dominant orientation of a
// Manhattan-like point set is the rotation that makes the histograms of its x
// and y projections the most peaked (least entropy).
#pragma once

#include <vector>

#include "core/types.h"

namespace lmd {

struct OrientationOptions {
  double bin_m = 0.1;            // m, projection histogram bin (paper: 0.1)
  double coarse_step_deg = 1.0;  // deg, first sweep over [0, 90)
  double fine_step_deg = 0.1;    // deg, refinement around the best coarse angle
  // Every field (a new one must join): whether two compasses are one.
  bool operator==(const OrientationOptions& o) const {
    return bin_m == o.bin_m && coarse_step_deg == o.coarse_step_deg && fine_step_deg == o.fine_step_deg;
  }
};

// Angle theta in [0, pi/2) minimising H(x') + H(y') where (x', y') =
// R(-theta) p are the rotated points binned at bin_m and H is the Shannon
// entropy of the bin counts. Rotating the input by a adds a to the result
// modulo pi/2. Fewer than 2 points: 0.
double EstimateDominantOrientation(const std::vector<Point2>& points,
                                   const OrientationOptions& options = {});

}  // namespace lmd
