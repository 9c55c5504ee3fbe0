// Synthetic local map descriptors for index and change-detector tests:
// random features, and copies of them rotated by k * 90 deg, shifted, with
// pose noise and dropped features, as two planned frames of one place are.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "core/types.h"

namespace lmd::testing {

// n features uniform in [-half, half]^2 with random B-bit words and change words.
inline Lmd RandomLmd(std::mt19937_64& rng, int n, double half = 15.0, int word_bits = 10) {
  std::uniform_real_distribution<double> pos(-half, half);
  Lmd lmd;
  for (int i = 0; i < n; ++i) {
    Feature f;
    f.appearance_word = static_cast<uint32_t>(rng() & ((1u << word_bits) - 1));
    f.x = static_cast<float>(pos(rng));
    f.y = static_cast<float>(pos(rng));
    f.change_word = rng() & ((uint64_t{1} << 60) - 1);
    lmd.features.push_back(f);
  }
  return lmd;
}

// A view of `db` from another planned frame: query positions q with
// db = R(k * 90 deg) q + (tx, ty) (+ noise), each feature kept with
// probability keep.
inline Lmd TransformedCopy(const Lmd& db, int k, double tx, double ty, std::mt19937_64& rng,
                           double noise_m = 0.0, double keep = 1.0) {
  std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Lmd out;
  out.frame = db.frame;
  for (const Feature& f : db.features) {
    if (keep < 1.0 && u(rng) >= keep) continue;
    double x = f.x - tx, y = f.y - ty;
    for (int r = 0; r < k; ++r) {  // rotate by -90 deg, k times
      const double nx = y, ny = -x;
      x = nx;
      y = ny;
    }
    if (noise_m > 0) {
      x += noise(rng);
      y += noise(rng);
    }
    Feature g = f;
    g.x = static_cast<float>(x);
    g.y = static_cast<float>(y);
    out.features.push_back(g);
  }
  return out;
}

}  // namespace lmd::testing
