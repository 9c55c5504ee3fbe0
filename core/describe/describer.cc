#include "core/describe/describer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/util/full_turn_angle.h"
#include "core/util/gaussian_matrix.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd {
namespace {

constexpr int kFineSectors = 12;  // 30 deg each, centred on 0, 30, ... deg
constexpr double kChangeRadiusM = 6.0;
constexpr int kChangeSectors = 6;

int ValidSectors(int a) {
  for (int v : {12, 6, 4, 3, 2, 1}) {
    if (a >= v) return v;
  }
  return 1;
}

// Points of the planned frame, rasterised and bucketed for radius queries.
class PointBuckets {
 public:
  PointBuckets(std::vector<std::pair<int64_t, int64_t>> keys, double raster_m, double bucket_m) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    if (keys.empty()) return;
    double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
    std::vector<float> xs(keys.size()), ys(keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
      xs[i] = static_cast<float>((static_cast<double>(keys[i].first) + 0.5) * raster_m);
      ys[i] = static_cast<float>((static_cast<double>(keys[i].second) + 0.5) * raster_m);
      lo_x = std::min<double>(lo_x, xs[i]), hi_x = std::max<double>(hi_x, xs[i]);
      lo_y = std::min<double>(lo_y, ys[i]), hi_y = std::max<double>(hi_y, ys[i]);
    }
    bucket_ = bucket_m;
    while (((hi_x - lo_x) / bucket_ + 1) * ((hi_y - lo_y) / bucket_ + 1) > 4e6) bucket_ *= 2;
    lo_x_ = lo_x, lo_y_ = lo_y;
    nx_ = static_cast<int>((hi_x - lo_x) / bucket_) + 1;
    ny_ = static_cast<int>((hi_y - lo_y) / bucket_) + 1;
    start_.assign(static_cast<size_t>(nx_) * ny_ + 1, 0);
    std::vector<uint32_t> bucket_of(keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
      bucket_of[i] = static_cast<uint32_t>(BucketY(ys[i]) * nx_ + BucketX(xs[i]));
      ++start_[bucket_of[i] + 1];
    }
    for (size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
    std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
    x_.resize(keys.size()), y_.resize(keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
      const uint32_t at = fill[bucket_of[i]]++;
      x_[at] = xs[i], y_[at] = ys[i];
    }
  }

  // Calls f(dx, dy, d2) for every point within radius of (cx, cy).
  template <typename F>
  void ForNeighbours(double cx, double cy, double radius, const F& f) const {
    if (x_.empty()) return;
    const int bx0 = std::max(0, BucketX(cx - radius)), bx1 = std::min(nx_ - 1, BucketX(cx + radius));
    const int by0 = std::max(0, BucketY(cy - radius)), by1 = std::min(ny_ - 1, BucketY(cy + radius));
    const float r2 = static_cast<float>(radius * radius);
    const float fx = static_cast<float>(cx), fy = static_cast<float>(cy);
    for (int by = by0; by <= by1; ++by) {
      for (int bx = bx0; bx <= bx1; ++bx) {
        const size_t b = static_cast<size_t>(by) * nx_ + bx;
        for (uint32_t i = start_[b]; i < start_[b + 1]; ++i) {
          const float dx = x_[i] - fx, dy = y_[i] - fy, d2 = dx * dx + dy * dy;
          if (d2 < r2) f(dx, dy, d2);
        }
      }
    }
  }

 private:
  int BucketX(double x) const { return static_cast<int>(std::floor((x - lo_x_) / bucket_)); }
  int BucketY(double y) const { return static_cast<int>(std::floor((y - lo_y_) / bucket_)); }
  double bucket_ = 1.0, lo_x_ = 0, lo_y_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<uint32_t> start_;
  std::vector<float> x_, y_;
};

// shells x 12 histogram (30 deg sectors centred on multiples of 30 deg from
// the frame heading) of the points within radius of (cx, cy), the point
// itself excluded. Soft binning: each point is split linearly between the two
// nearest shell centres and the two nearest sector centres, so that small
// noise moves the histogram a little instead of flipping whole counts.
void FineHistogram(const PointBuckets& pts, double cx, double cy, double radius, int shells, double self_m,
                   std::vector<double>& hist) {
  hist.assign(static_cast<size_t>(shells) * kFineSectors, 0.0);
  const float self2 = static_cast<float>(self_m * self_m);
  const double shell_scale = shells / radius;
  const double sector_scale = kFineSectors / (2 * M_PI);
  pts.ForNeighbours(cx, cy, radius, [&](float dx, float dy, float d2) {
    if (d2 < self2) return;
    const double u = std::sqrt(static_cast<double>(d2)) * shell_scale - 0.5;  // shell centres at integers
    int s0 = static_cast<int>(std::floor(u));
    double ws = u - s0;
    if (s0 < 0) s0 = 0, ws = 0;
    if (s0 >= shells - 1) s0 = shells - 1, ws = 0;
    const double v = FullTurnAngle(dy, dx) * sector_scale;  // sector centres at integers
    const int a0 = static_cast<int>(std::floor(v)) % kFineSectors, a1 = (a0 + 1) % kFineSectors;
    const double wa = v - std::floor(v);
    double* row0 = hist.data() + static_cast<size_t>(s0) * kFineSectors;
    row0[a0] += (1 - ws) * (1 - wa);
    row0[a1] += (1 - ws) * wa;
    if (ws > 0) {
      double* row1 = row0 + kFineSectors;
      row1[a0] += ws * (1 - wa);
      row1[a1] += ws * wa;
    }
  });
}

// Canonical quarter turn k (0..3): the axis direction (quadrant centred on
// heading + k * 90 deg) holding the most points, ties toward the next
// counter-clockwise axis via score Q_k + Q_{k-1} / 2.
int CanonicalQuarter(const std::vector<double>& fine, int shells) {
  double q[4] = {0, 0, 0, 0};
  for (int s = 0; s < shells; ++s) {
    for (int j = 0; j < kFineSectors; ++j) {
      // Fine sector j is centred on 30 j deg; quadrant k spans sectors 3k-1 .. 3k+1.
      const int k = ((j + 1) / 3) % 4;
      q[k] += fine[static_cast<size_t>(s) * kFineSectors + j];
    }
  }
  int best = 0;
  double best_score = -1;
  for (int k = 0; k < 4; ++k) {
    const double score = q[k] + 0.5 * q[(k + 3) % 4];
    if (score > best_score + 1e-9) best_score = score, best = k;
  }
  return best;
}

// Collapses the fine histogram to shells x sectors, measured from quarter turn k.
void Collapse(const std::vector<double>& fine, int shells, int sectors, int k, std::vector<double>& out) {
  out.assign(static_cast<size_t>(shells) * sectors, 0.0);
  const int per = kFineSectors / sectors;
  for (int s = 0; s < shells; ++s) {
    for (int j = 0; j < kFineSectors; ++j) {
      const int jr = ((j - 3 * k) % kFineSectors + kFineSectors) % kFineSectors;
      out[static_cast<size_t>(s) * sectors + jr / per] += fine[static_cast<size_t>(s) * kFineSectors + j];
    }
  }
}

// B x D Gaussian matrix, row-major, from the seed.
std::vector<double> ProjectionMatrix(uint64_t seed, int bits, int dims) {
  return GaussianValues(seed ^ (0x9e3779b97f4a7c15ULL * (static_cast<uint64_t>(dims) * 64 + bits + kProjectionVersion)),
                        static_cast<size_t>(bits) * dims);
}

// sign(W h): h is NOT centred, so that the common near-flat profiles (a
// straight wall through the interest point) land at a definite place in the
// projection rather than on every bit's boundary (centring made words of
// walls flip under millimetre noise). Scale-free, so h needs no normalising.
uint32_t AppearanceWord(const std::vector<double>& hist, const std::vector<double>& projection, int bits) {
  double total = 0;
  for (double v : hist) total += v;
  if (total <= 0) return 0;
  const size_t d = hist.size();
  uint32_t word = 0;
  for (int b = 0; b < bits; ++b) {
    const double* row = projection.data() + static_cast<size_t>(b) * d;
    double dot = 0;
    for (size_t i = 0; i < d; ++i) dot += row[i] * hist[i];
    if (dot > 0) word |= 1u << b;
  }
  return word;
}

uint64_t ChangeWord(const std::vector<double>& hist) {
  double mean = 0;
  for (double v : hist) mean += v;
  mean /= static_cast<double>(hist.size());
  uint64_t word = 0;
  for (size_t i = 0; i < hist.size() && i < 64; ++i) {
    if (hist[i] > mean) word |= uint64_t{1} << i;
  }
  return word;
}

}  // namespace

DescriptorSetting PaperDescriptorSetting(int number) {
  static const DescriptorSetting kSettings[8] = {{1, 1}, {6, 3}, {12, 6}, {1, 6}, {3, 6}, {6, 6}, {3, 1}, {6, 1}};
  return number >= 1 && number <= 8 ? kSettings[number - 1] : kSettings[0];
}

DescriberOptions ProductDescriberOptions() {
  DescriberOptions options;
  options.setting = PaperDescriptorSetting(6);
  options.word_bits = 13;
  return options;
}

DescriberOptions WithInnerWords(DescriberOptions options) {
  options.inner_radius_m = 3.0;
  options.max_features = 64;
  return options;
}

Lmd Describe(const LocalMap& map, const Frame& frame, const DescriberOptions& options) {
  Lmd lmd;
  lmd.frame = frame;
  const int shells = std::max(1, options.shells);
  const int sectors = ValidSectors(options.setting.sectors);
  const int bits = std::clamp(options.word_bits, 1, 16);
  const double radius = options.setting.radius_m > 0 ? options.setting.radius_m : 1.0;
  const double raster = options.raster_m > 0 ? options.raster_m : 0.01;
  const double icell = options.interest_cell_m > 0 ? options.interest_cell_m : 0.5;

  // Points in the planned frame, their 0.01 m raster cells, interest cells.
  std::vector<Point2> q;
  q.reserve(map.points.size());
  for (const Point2& p : map.points) {
    const Point2 f = ToFrame(frame, p);
    if (std::isfinite(f.x) && std::isfinite(f.y) && std::abs(f.x) < 1e6 && std::abs(f.y) < 1e6) q.push_back(f);
  }
  if (q.empty()) return lmd;
  std::vector<std::pair<int64_t, int64_t>> keys(q.size());
  for (size_t i = 0; i < q.size(); ++i) {
    keys[i] = {static_cast<int64_t>(std::floor(q[i].x / raster)), static_cast<int64_t>(std::floor(q[i].y / raster))};
  }
  const double inner_radius =
      bits <= 15 && options.inner_radius_m < radius ? std::max(options.inner_radius_m, 0.0) : 0.0;
  const double max_radius = options.change_words ? std::max(radius, kChangeRadiusM) : radius;
  const PointBuckets buckets(std::move(keys), raster, std::max(1.0, max_radius / 4));

  struct Interest {
    int64_t cx, cy;   // interest cell
    double d2;        // point's squared distance to the cell centre
    Point2 p;
  };
  std::vector<Interest> cand(q.size());
  for (size_t i = 0; i < q.size(); ++i) {
    const int64_t cx = static_cast<int64_t>(std::floor(q[i].x / icell));
    const int64_t cy = static_cast<int64_t>(std::floor(q[i].y / icell));
    const double ex = q[i].x - (cx + 0.5) * icell, ey = q[i].y - (cy + 0.5) * icell;
    cand[i] = {cx, cy, ex * ex + ey * ey, q[i]};
  }
  std::sort(cand.begin(), cand.end(), [](const Interest& a, const Interest& b) {
    if (a.cy != b.cy) return a.cy < b.cy;
    if (a.cx != b.cx) return a.cx < b.cx;
    if (a.d2 != b.d2) return a.d2 < b.d2;
    return a.p.x != b.p.x ? a.p.x < b.p.x : a.p.y < b.p.y;
  });
  std::vector<Interest> interest;
  for (size_t i = 0; i < cand.size(); ++i) {
    if (i == 0 || cand[i].cx != cand[i - 1].cx || cand[i].cy != cand[i - 1].cy) interest.push_back(cand[i]);
  }
  if (options.max_features > 0 && interest.size() > static_cast<size_t>(options.max_features)) {
    auto dist = [&](const Interest& a) {
      const double x = (a.cx + 0.5) * icell, y = (a.cy + 0.5) * icell;
      return x * x + y * y;
    };
    std::stable_sort(interest.begin(), interest.end(),
                     [&](const Interest& a, const Interest& b) { return dist(a) < dist(b); });
    interest.resize(static_cast<size_t>(options.max_features));
    std::sort(interest.begin(), interest.end(), [](const Interest& a, const Interest& b) {
      return a.cy != b.cy ? a.cy < b.cy : a.cx < b.cx;
    });
  }

  const std::vector<double> projection = ProjectionMatrix(options.projection_seed, bits, shells * sectors);
  const bool same_change = radius == kChangeRadiusM && shells == 10;
  std::vector<double> fine, hist, change_fine, change_hist, inner_fine, inner_hist;
  lmd.features.reserve(interest.size());
  for (const Interest& ip : interest) {
    Feature f;
    f.x = static_cast<float>(ip.p.x);
    f.y = static_cast<float>(ip.p.y);
    FineHistogram(buckets, ip.p.x, ip.p.y, radius, shells, raster * 0.5, fine);
    Collapse(fine, shells, sectors, CanonicalQuarter(fine, shells), hist);
    f.appearance_word = AppearanceWord(hist, projection, bits);
    if (inner_radius > 0) {
      FineHistogram(buckets, ip.p.x, ip.p.y, inner_radius, shells, raster * 0.5, inner_fine);
      Collapse(inner_fine, shells, sectors, CanonicalQuarter(inner_fine, shells), inner_hist);
      f.inner_word = AppearanceWord(inner_hist, projection, bits);
    }
    if (options.change_words) {
      if (!same_change) FineHistogram(buckets, ip.p.x, ip.p.y, kChangeRadiusM, 10, raster * 0.5, change_fine);
      const std::vector<double>& cf = same_change ? fine : change_fine;
      Collapse(cf, 10, kChangeSectors, CanonicalQuarter(cf, 10), change_hist);
      f.change_word = ChangeWord(change_hist);
    }
    lmd.features.push_back(f);
  }
  return lmd;
}

}  // namespace lmd
