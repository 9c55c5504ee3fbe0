#include "core/change/lof.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace lmd {

std::vector<double> LocalOutlierFactors(const std::vector<Point2>& points, int k_requested) {
  const size_t n = points.size();
  std::vector<double> lof(n, 1.0);
  if (n < 2 || k_requested < 1) return lof;
  const size_t k = std::min<size_t>(static_cast<size_t>(k_requested), n - 1);
  std::vector<uint32_t> neighbours(n * k);
  std::vector<double> neighbour_dist(n * k);
  std::vector<double> k_distance(n);
  std::vector<std::pair<double, uint32_t>> row(n - 1);
  for (size_t i = 0; i < n; ++i) {
    // Ranked by squared distance; only the k kept need a square root.
    size_t m = 0;
    for (size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const double dx = points[i].x - points[j].x, dy = points[i].y - points[j].y;
      row[m++] = {dx * dx + dy * dy, static_cast<uint32_t>(j)};
    }
    std::nth_element(row.begin(), row.begin() + (k - 1), row.end());
    std::sort(row.begin(), row.begin() + k);
    for (size_t r = 0; r < k; ++r) {
      neighbours[i * k + r] = row[r].second;
      neighbour_dist[i * k + r] = std::sqrt(row[r].first);
    }
    k_distance[i] = neighbour_dist[i * k + k - 1];
  }
  std::vector<double> lrd(n);
  for (size_t i = 0; i < n; ++i) {
    double sum = 0.0;
    for (size_t r = 0; r < k; ++r)
      sum += std::max(k_distance[neighbours[i * k + r]], neighbour_dist[i * k + r]);
    lrd[i] = 1.0 / std::max(sum / static_cast<double>(k), 1e-6);
  }
  for (size_t i = 0; i < n; ++i) {
    double sum = 0.0;
    for (size_t r = 0; r < k; ++r) sum += lrd[neighbours[i * k + r]];
    lof[i] = sum / (static_cast<double>(k) * lrd[i]);
  }
  return lof;
}

}  // namespace lmd
