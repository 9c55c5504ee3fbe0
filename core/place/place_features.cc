#include "core/place/place_features.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <Eigen/Core>

#include "core/util/byte_codec.h"
#include "core/util/gaussian_matrix.h"

namespace lmd {
namespace {

constexpr int kSectors = 8;     // 45 deg each: a quarter turn is a shift by 2
constexpr int kGroups = 32;     // projection groups of 4 quarter turns: 128 bits
constexpr double kTan22_5 = 0.41421356237309503;

// Sector of direction (dx, dy): 0 = +x axis, counting counter-clockwise,
// each centred on an axis or a diagonal (boundaries at 22.5 + 45 k deg).
int Sector(double dx, double dy) {
  const double ax = std::abs(dx), ay = std::abs(dy);
  if (ay <= kTan22_5 * ax) return dx >= 0 ? 0 : 4;
  if (ax <= kTan22_5 * ay) return dy >= 0 ? 2 : 6;
  if (dx >= 0) return dy >= 0 ? 1 : 7;
  return dy >= 0 ? 3 : 5;
}

// Rows of the projection, row (g, j) = 4 g + j: group g's random vector read
// with the sectors shifted by -2 j, so that bit (g, j) of a map turned by k
// quarter turns is bit (g, j - k) of the unturned map.
std::vector<float> Projection(uint64_t seed, int shells) {
  const int dims = shells * kSectors;
  const std::vector<double> w = GaussianValues(seed ^ (0x9e3779b97f4a7c15ULL * (kPlaceFeatureVersion * 64 + shells)),
                                               static_cast<size_t>(kGroups) * dims);
  std::vector<float> rows(static_cast<size_t>(kGroups) * 4 * dims);
  for (int g = 0; g < kGroups; ++g) {
    for (int j = 0; j < 4; ++j) {
      float* row = rows.data() + static_cast<size_t>(4 * g + j) * dims;
      for (int sh = 0; sh < shells; ++sh) {
        for (int s = 0; s < kSectors; ++s) {
          const int from = (s - 2 * j + 2 * kSectors) % kSectors;
          row[sh * kSectors + s] = static_cast<float>(w[static_cast<size_t>(g) * dims + sh * kSectors + from]);
        }
      }
    }
  }
  return rows;
}

const std::vector<float>& CachedProjection(uint64_t seed, int shells) {
  // Options are fixed per process in practice; one cached matrix per (seed, shells).
  static thread_local uint64_t cached_seed = 0;
  static thread_local int cached_shells = -1;
  static thread_local std::vector<float> rows;
  if (cached_shells != shells || cached_seed != seed) {
    rows = Projection(seed, shells);
    cached_seed = seed, cached_shells = shells;
  }
  return rows;
}

// Points bucketed on a square grid for radius queries.
class PointGrid2 {
 public:
  PointGrid2(const std::vector<Point2>& points, double cell) : cell_(cell) {
    for (const Point2& p : points) {
      lo_x_ = std::min(lo_x_, p.x), lo_y_ = std::min(lo_y_, p.y);
      hi_x_ = std::max(hi_x_, p.x), hi_y_ = std::max(hi_y_, p.y);
    }
    nx_ = static_cast<int>((hi_x_ - lo_x_) / cell_) + 1;
    ny_ = static_cast<int>((hi_y_ - lo_y_) / cell_) + 1;
    start_.assign(static_cast<size_t>(nx_) * ny_ + 1, 0);
    std::vector<uint32_t> bucket(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      bucket[i] = static_cast<uint32_t>(Y(points[i].y) * nx_ + X(points[i].x));
      ++start_[bucket[i] + 1];
    }
    for (size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
    std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
    sorted_.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) sorted_[fill[bucket[i]]++] = points[i];
  }

  template <typename F>
  void ForNeighbours(const Point2& c, double radius, const F& f) const {
    const int x0 = std::max(0, X(c.x - radius)), x1 = std::min(nx_ - 1, X(c.x + radius));
    const int y0 = std::max(0, Y(c.y - radius)), y1 = std::min(ny_ - 1, Y(c.y + radius));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const size_t b = static_cast<size_t>(y) * nx_ + x;
        for (uint32_t i = start_[b]; i < start_[b + 1]; ++i) f(sorted_[i]);
      }
    }
  }

 private:
  int X(double x) const { return std::clamp(static_cast<int>((x - lo_x_) / cell_), 0, nx_ - 1); }
  int Y(double y) const { return std::clamp(static_cast<int>((y - lo_y_) / cell_), 0, ny_ - 1); }
  double cell_;
  double lo_x_ = 1e300, lo_y_ = 1e300, hi_x_ = -1e300, hi_y_ = -1e300;
  int nx_ = 1, ny_ = 1;
  std::vector<uint32_t> start_;
  std::vector<Point2> sorted_;
};

// One interest point per occupied cell: the point nearest the cell centre
// (ties: the smaller x, then y), cells in (y, x) order.
std::vector<Point2> InterestPoints(const std::vector<Point2>& points, double cell) {
  struct Best {
    Point2 p;
    double d2;
  };
  std::unordered_map<uint64_t, Best> best;
  std::vector<std::pair<int64_t, int64_t>> order;
  for (const Point2& p : points) {
    const int64_t cx = static_cast<int64_t>(std::floor(p.x / cell)), cy = static_cast<int64_t>(std::floor(p.y / cell));
    const double ex = p.x - (cx + 0.5) * cell, ey = p.y - (cy + 0.5) * cell, d2 = ex * ex + ey * ey;
    const uint64_t key = (static_cast<uint64_t>(cx) << 32) ^ static_cast<uint64_t>(cy & 0xffffffff);
    auto [it, added] = best.try_emplace(key, Best{p, d2});
    if (added) {
      order.push_back({cy, cx});
    } else if (d2 < it->second.d2 || (d2 == it->second.d2 && (p.x < it->second.p.x ||
                                                             (p.x == it->second.p.x && p.y < it->second.p.y)))) {
      it->second = {p, d2};
    }
  }
  std::sort(order.begin(), order.end());
  std::vector<Point2> out;
  out.reserve(order.size());
  for (const auto& [cy, cx] : order) {
    out.push_back(best.at((static_cast<uint64_t>(cx) << 32) ^ static_cast<uint64_t>(cy & 0xffffffff)).p);
  }
  return out;
}

}  // namespace

Point2 TurnQuarters(const Point2& p, int k) {
  switch (((k % 4) + 4) % 4) {
    case 1: return {-p.y, p.x};
    case 2: return {-p.x, -p.y};
    case 3: return {p.y, -p.x};
    default: return p;
  }
}

PlaceCode RotateCode(const PlaceCode& code, int k) {
  k = ((k % 4) + 4) % 4;
  if (k == 0) return code;
  // Each nibble holds one group's 4 bits (bit j = quarter turn j): rotate
  // every nibble left by k, so that new bit j = old bit j - k.
  constexpr uint64_t kOnes = 0x1111111111111111ULL;
  const uint64_t high = kOnes * ((0xFu << k) & 0xFu);  // bits that stay in their nibble
  const uint64_t low = kOnes * ((1u << k) - 1);       // bits that wrap around
  PlaceCode out;
  for (int w = 0; w < 2; ++w) out[w] = ((code[w] << k) & high) | ((code[w] >> (4 - k)) & low);
  return out;
}

PlaceFeatures DescribePlace(const std::vector<Point2>& points, double heading, const PlaceFeatureOptions& options) {
  PlaceFeatures out;
  out.heading = heading;
  const double c = std::cos(-heading), s = std::sin(-heading);
  std::vector<Point2> compass;
  compass.reserve(points.size());
  for (const Point2& p : points) {
    if (std::isfinite(p.x) && std::isfinite(p.y)) compass.push_back({c * p.x - s * p.y, s * p.x + c * p.y});
  }
  if (compass.empty()) return out;
  const int shells = std::max(1, options.shells);
  const double radius = options.radius_m > 0 ? options.radius_m : 4.0;
  std::vector<Point2> interest = InterestPoints(compass, options.interest_cell_m > 0 ? options.interest_cell_m : 0.5);
  if (options.max_features > 0 && interest.size() > options.max_features) {
    std::vector<Point2> kept;
    kept.reserve(options.max_features);
    for (size_t i = 0; i < options.max_features; ++i) kept.push_back(interest[i * interest.size() / options.max_features]);
    interest = std::move(kept);
  }
  const PointGrid2 grid(compass, radius);
  const std::vector<float>& projection = CachedProjection(options.projection_seed, shells);
  const int dims = shells * kSectors;
  const double r2 = radius * radius, shell_scale = shells / radius;
  // One matrix-vector product per feature, vectorised by Eigen (a plain
  // loop's float sum cannot be reordered by the compiler): most of
  // describing a map at insert (perf, lmd-bench load --mode fleet).
  const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> rows(
      projection.data(), 4 * kGroups, dims);
  Eigen::VectorXf dots(4 * kGroups);
  std::vector<float> hist(dims);
  out.features.reserve(interest.size());
  for (const Point2& ip : interest) {
    std::fill(hist.begin(), hist.end(), 0.0f);
    grid.ForNeighbours(ip, radius, [&](const Point2& q) {
      const double dx = q.x - ip.x, dy = q.y - ip.y, d2 = dx * dx + dy * dy;
      if (d2 >= r2 || d2 < 1e-12) return;
      const int shell = std::min(shells - 1, static_cast<int>(std::sqrt(d2) * shell_scale));
      hist[shell * kSectors + Sector(dx, dy)] += 1.0f;
    });
    float mean = 0.0f;
    for (float& v : hist) mean += (v = std::sqrt(v));
    mean /= static_cast<float>(dims);
    for (float& v : hist) v -= mean;  // scale does not change signs: no normalising needed
    PlaceFeature f;
    f.x = static_cast<float>(ip.x);
    f.y = static_cast<float>(ip.y);
    f.code = {0, 0};
    dots.noalias() = rows * Eigen::Map<const Eigen::VectorXf>(hist.data(), dims);
    for (int b = 0; b < 4 * kGroups; ++b) {
      if (dots[b] > 0.0f) f.code[b / 64] |= uint64_t{1} << (b % 64);
    }
    out.features.push_back(f);
  }
  return out;
}

std::string EncodePlaceFeatures(const PlaceFeatures& features) {
  std::string out;
  out.reserve(16 + 24 * features.features.size());
  out.push_back(static_cast<char>(kPlaceFeatureVersion));
  PutVarint(out, features.features.size());
  PutF32(out, static_cast<float>(features.heading));
  for (const PlaceFeature& f : features.features) {
    PutF32(out, f.x);
    PutF32(out, f.y);
    PutU64(out, f.code[0]);
    PutU64(out, f.code[1]);
  }
  return out;
}

Result<PlaceFeatures> DecodePlaceFeatures(const std::string& bytes) {
  constexpr size_t kFeatureBytes = 24;
  ByteReader r(bytes);
  uint8_t version;
  if (!r.U8(&version)) return Status::Corruption("place features: empty record");
  if (version != kPlaceFeatureVersion) {
    return Status::Corruption("place features: version " + std::to_string(version) + ", this build reads " +
                              std::to_string(kPlaceFeatureVersion));
  }
  uint64_t n;
  float heading;
  if (!r.Varint(&n) || !r.F32(&heading)) return Status::Corruption("place features: truncated header");
  if (!std::isfinite(heading)) return Status::Corruption("place features: non-finite heading");
  if (n > r.left() / kFeatureBytes || n * kFeatureBytes != r.left()) {
    return Status::Corruption("place features: " + std::to_string(n) + " features need " +
                              std::to_string(n * kFeatureBytes) + " bytes, record has " + std::to_string(r.left()));
  }
  PlaceFeatures out;
  out.heading = heading;
  out.features.resize(static_cast<size_t>(n));
  for (PlaceFeature& f : out.features) {
    r.F32(&f.x), r.F32(&f.y), r.U64(&f.code[0]), r.U64(&f.code[1]);
    if (!std::isfinite(f.x) || !std::isfinite(f.y)) return Status::Corruption("place features: non-finite position");
  }
  return out;
}

}  // namespace lmd
