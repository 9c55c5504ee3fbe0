#include "core/util/gaussian_matrix.h"

#include <cmath>
#include <random>

namespace lmd {

std::vector<double> GaussianValues(uint64_t seed, size_t count) {
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); };
  std::vector<double> m(count);
  for (size_t i = 0; i < m.size(); i += 2) {
    const double r = std::sqrt(-2.0 * std::log(uniform())), t = 2 * M_PI * uniform();
    m[i] = r * std::cos(t);
    if (i + 1 < m.size()) m[i + 1] = r * std::sin(t);
  }
  return m;
}

}  // namespace lmd
