#include "core/viewpoint/orientation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lmd {
namespace {

// H(x') + H(y') of the points turned by -theta, with linear (two-bin) soft
// binning so that the score varies smoothly with theta. `xs`, `ys` are
// centred on the centroid; `hist` is scratch of 2 * bins doubles, all zero
// on entry and on return.
double ProjectionEntropy(const std::vector<double>& xs, const std::vector<double>& ys, double theta,
                         double bin_m, double half_extent, std::vector<double>& hist) {
  const size_t bins = hist.size() / 2;
  const double c = std::cos(theta), s = std::sin(theta);
  const double inv = 1.0 / bin_m;
  double* hx = hist.data();
  double* hy = hist.data() + bins;
  // The points fill only part of each axis's bins: track the range touched,
  // so that only it is read (and zeroed for the next angle).
  size_t lo_u = bins, hi_u = 0, lo_v = bins, hi_v = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    const double u = (c * xs[i] + s * ys[i] + half_extent) * inv;
    const double v = (-s * xs[i] + c * ys[i] + half_extent) * inv;
    const double fu = std::floor(u), fv = std::floor(v);
    const size_t iu = static_cast<size_t>(fu), iv = static_cast<size_t>(fv);
    const double wu = u - fu, wv = v - fv;
    hx[iu] += 1.0 - wu;
    hx[iu + 1] += wu;
    hy[iv] += 1.0 - wv;
    hy[iv + 1] += wv;
    lo_u = std::min(lo_u, iu), hi_u = std::max(hi_u, iu + 1);
    lo_v = std::min(lo_v, iv), hi_v = std::max(hi_v, iv + 1);
  }
  const double n = static_cast<double>(xs.size());
  double h = 0.0;
  auto add_and_clear = [&](double* axis, size_t lo, size_t hi) {
    for (size_t b = lo; b <= hi; ++b) {
      const double p = axis[b] / n;
      if (p > 0) h -= p * std::log(p);
      axis[b] = 0.0;
    }
  };
  if (!xs.empty()) {
    add_and_clear(hx, lo_u, hi_u);
    add_and_clear(hy, lo_v, hi_v);
  }
  return h;
}

// Local maxima of the coarse sweep compared on the soft entropy.
constexpr size_t kCoarsePeaks = 3;

// The coarse sweep's score: sum over the bins of both axes of c ln c, c =
// the count of points in the bin (hard binning). For n points the entropy
// H(x') + H(y') = 2 ln n - score / n, so the highest score is the lowest
// entropy; integer counts let `c_log_c` (c ln c for c = 0..n) replace the
// logarithms, and one bin per point per axis halves the histogram work.
double CountScore(const std::vector<double>& xs, const std::vector<double>& ys, double theta, double bin_m,
                  double half_extent, const std::vector<double>& c_log_c, std::vector<uint32_t>& counts) {
  const size_t bins = counts.size() / 2;
  const double c = std::cos(theta), s = std::sin(theta);
  const double inv = 1.0 / bin_m;
  uint32_t* hx = counts.data();
  uint32_t* hy = counts.data() + bins;
  size_t lo_u = bins, hi_u = 0, lo_v = bins, hi_v = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    const size_t iu = static_cast<size_t>((c * xs[i] + s * ys[i] + half_extent) * inv);
    const size_t iv = static_cast<size_t>((-s * xs[i] + c * ys[i] + half_extent) * inv);
    ++hx[iu], ++hy[iv];
    lo_u = std::min(lo_u, iu), hi_u = std::max(hi_u, iu);
    lo_v = std::min(lo_v, iv), hi_v = std::max(hi_v, iv);
  }
  double score = 0.0;
  auto add_and_clear = [&](uint32_t* axis, size_t lo, size_t hi) {
    for (size_t b = lo; b <= hi; ++b) {
      score += c_log_c[axis[b]];
      axis[b] = 0;
    }
  };
  if (!xs.empty()) {
    add_and_clear(hx, lo_u, hi_u);
    add_and_clear(hy, lo_v, hi_v);
  }
  return score;
}

}  // namespace

double EstimateDominantOrientation(const std::vector<Point2>& points, const OrientationOptions& options) {
  std::vector<double> xs, ys;
  xs.reserve(points.size()), ys.reserve(points.size());
  double mx = 0, my = 0;
  for (const Point2& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    xs.push_back(p.x), ys.push_back(p.y);
    mx += p.x, my += p.y;
  }
  if (xs.size() < 2) return 0.0;
  mx /= static_cast<double>(xs.size()), my /= static_cast<double>(xs.size());
  double r2 = 0;
  for (size_t i = 0; i < xs.size(); ++i) {
    xs[i] -= mx, ys[i] -= my;
    r2 = std::max(r2, xs[i] * xs[i] + ys[i] * ys[i]);
  }
  const double bin = options.bin_m > 0 ? options.bin_m : 0.1;
  const double half = std::sqrt(r2) + 2 * bin;
  std::vector<double> hist(2 * (static_cast<size_t>(2 * half / bin) + 3));
  std::vector<uint32_t> counts(hist.size());
  std::vector<double> c_log_c(xs.size() + 1, 0.0);
  for (size_t k = 2; k < c_log_c.size(); ++k) c_log_c[k] = static_cast<double>(k) * std::log(static_cast<double>(k));

  const double deg = M_PI / 180.0;
  const double coarse = std::clamp(options.coarse_step_deg, 0.01, 45.0);
  const double fine = std::clamp(options.fine_step_deg, 0.001, coarse);
  // Coarse sweep on counts; its best local maxima (the sweep wraps at 90
  // deg) and their coarse neighbours are compared on the smooth soft-binned
  // entropy, and the best is refined on it. Against a soft coarse sweep, on
  // the 5678 local maps of the nine real logs: 12 headings differ by more
  // than 1 deg (132 when the best count peak alone is refined), 45 by more
  // than 0.05 deg; 0.56x the compass's instructions in lmdd (callgrind).
  std::vector<double> angles, scores;
  for (double a = 0.0; a < 90.0 - 1e-9; a += coarse) {
    angles.push_back(a);
    scores.push_back(CountScore(xs, ys, a * deg, bin, half, c_log_c, counts));
  }
  std::vector<size_t> peaks;
  for (size_t i = 0; i < scores.size(); ++i) {
    const double before = scores[(i + scores.size() - 1) % scores.size()], after = scores[(i + 1) % scores.size()];
    if (scores[i] >= before && scores[i] >= after) peaks.push_back(i);
  }
  const size_t kept = std::min<size_t>(peaks.size(), kCoarsePeaks);
  std::partial_sort(peaks.begin(), peaks.begin() + kept, peaks.end(),
                    [&](size_t a, size_t b) { return scores[a] != scores[b] ? scores[a] > scores[b] : a < b; });
  double best = 0.0, best_h = 1e300;
  for (size_t k = 0; k < kept; ++k) {
    for (int step = -1; step <= 1; ++step) {
      const double a = angles[peaks[k]] + step * coarse;
      const double h = ProjectionEntropy(xs, ys, a * deg, bin, half, hist);
      if (h < best_h) best_h = h, best = a;
    }
  }
  const double centre = best;
  for (double a = centre - coarse; a <= centre + coarse + 1e-9; a += fine) {
    const double h = ProjectionEntropy(xs, ys, a * deg, bin, half, hist);
    if (h < best_h) best_h = h, best = a;
  }
  double result = std::fmod(best, 90.0);
  if (result < 0) result += 90.0;
  if (result >= 90.0 - 1e-9) result = 0.0;
  return result * deg;
}

}  // namespace lmd
