// Place features: what the localisation pipeline's first stage (place_index.h)
// matches between a query map and the stored maps.
//
// A map is expressed in its compass frame: its own frame turned by minus the
// entropy-compass heading (core/viewpoint/orientation.h), no translation. The
// heading is defined modulo 90 deg, so two maps of one place have compass
// frames related by a quarter turn k (0..3) and a translation.
//
// Interest points: one per interest_cell_m cell of the compass frame (the
// map point nearest the cell centre), every occupied cell, not only those
// near a planned viewpoint: two maps of a place then share features wherever
// they overlap, whatever part of it each saw.
//
// Descriptor: the map's points within radius_m of the interest point counted
// in `shells` equal rings x 8 sectors of 45 deg (centred on the compass axes
// and diagonals), square-rooted, centred (own mean removed) and normalised.
// Turning a map by a quarter turn shifts the sectors by 2, so the descriptor
// of one place under any of the 4 hypotheses is a permutation of the other.
//
// Code: 128 signs of random projections of the descriptor (SimHash: Hamming
// distance estimates the angle between descriptors). The 128 projections are
// 32 groups of 4, the 4 of a group being one random vector turned by 0, 1, 2
// and 3 quarter turns; a quarter turn of the map then rotates each group's 4
// bits (RotateCode), so a query needs one projection for all 4 hypotheses.
//
// Why not the LMD's 13-bit appearance words: on real logs (aces, fr079, intel,
// orebro, true correspondences within 0.15 m under the true pose) two maps of
// one place gave a feature the same 13-bit word 5-11 % of the time; with this
// descriptor the true correspondence is among the 10 nearest of all
// candidate maps' features (15k-60k) for over half of them (docs/results.md).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"

namespace lmd {

// Bumped whenever the descriptor or its projections change: codes of
// different versions are not comparable (stores keep the version).
inline constexpr uint32_t kPlaceFeatureVersion = 1;

struct PlaceFeatureOptions {
  // m; descriptor radius. 4 m: the true place among the first stage's top 10
  // for 0.94 of the queries of aces, fr079, intel and orebro (mean over the
  // logs) against 0.89 with 6 m, 0.94 with 3 m and 0.90 with 2 m (30 queries
  // per log, docs/results.md).
  double radius_m = 4.0;
  int shells = 10;                 // rings of radius_m / shells
  double interest_cell_m = 0.5;    // m; one interest point per occupied cell
  // Cap on features per map; beyond it the interest cells are thinned
  // evenly (every n-th in cell order). 0 = no cap.
  size_t max_features = 400;
  uint64_t projection_seed = 0x706c616365ULL;  // "place"
};

using PlaceCode = std::array<uint64_t, 2>;  // 128 bits

struct PlaceFeature {
  float x = 0.0f;  // m, compass frame
  float y = 0.0f;
  PlaceCode code;  // of the unturned descriptor
};

struct PlaceFeatures {
  double heading = 0.0;  // rad in [0, pi/2): compass frame = own frame turned by -heading
  std::vector<PlaceFeature> features;
};

// Features of `points` (own frame, finite) in the compass frame of
// `heading`. Deterministic; no points: no features.
PlaceFeatures DescribePlace(const std::vector<Point2>& points, double heading,
                            const PlaceFeatureOptions& options = {});

// The code of a feature's descriptor after turning the map by k quarter
// turns counter-clockwise (k mod 4).
PlaceCode RotateCode(const PlaceCode& code, int k);

inline int HammingDistance(const PlaceCode& a, const PlaceCode& b) {
  return __builtin_popcountll(a[0] ^ b[0]) + __builtin_popcountll(a[1] ^ b[1]);
}

// Point p of the compass frame turned by k quarter turns counter-clockwise.
Point2 TurnQuarters(const Point2& p, int k);

// Compact binary form (stored per map): version byte, varint count, float32
// heading, then per feature float32 x, y and the 16 code bytes (24 bytes).
std::string EncodePlaceFeatures(const PlaceFeatures& features);
// Corruption on a wrong version, truncation, trailing bytes or a heading that
// is not finite; never allocates more than the input warrants.
Result<PlaceFeatures> DecodePlaceFeatures(const std::string& bytes);

}  // namespace lmd
