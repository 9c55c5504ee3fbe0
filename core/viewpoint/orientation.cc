#include "core/viewpoint/orientation.h"

#include <algorithm>
#include <cmath>

namespace lmd {
namespace {

// H(x') + H(y') of the points turned by -theta, with linear (two-bin) soft
// binning so that the score varies smoothly with theta. `xs`, `ys` are
// centred on the centroid; `hist` is scratch of 2 * bins doubles.
double ProjectionEntropy(const std::vector<double>& xs, const std::vector<double>& ys, double theta,
                         double bin_m, double half_extent, std::vector<double>& hist) {
  const size_t bins = hist.size() / 2;
  std::fill(hist.begin(), hist.end(), 0.0);
  const double c = std::cos(theta), s = std::sin(theta);
  const double inv = 1.0 / bin_m;
  double* hx = hist.data();
  double* hy = hist.data() + bins;
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
  }
  const double n = static_cast<double>(xs.size());
  double h = 0.0;
  for (size_t b = 0; b < 2 * bins; ++b) {
    const double p = hist[b] / n;
    if (p > 0) h -= p * std::log(p);
  }
  return h;
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

  const double deg = M_PI / 180.0;
  const double coarse = std::clamp(options.coarse_step_deg, 0.01, 45.0);
  const double fine = std::clamp(options.fine_step_deg, 0.001, coarse);
  double best = 0.0, best_h = 1e300;
  for (double a = 0.0; a < 90.0 - 1e-9; a += coarse) {
    const double h = ProjectionEntropy(xs, ys, a * deg, bin, half, hist);
    if (h < best_h) best_h = h, best = a;
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
