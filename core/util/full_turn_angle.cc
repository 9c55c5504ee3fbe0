#include "core/util/full_turn_angle.h"

#include <algorithm>
#include <cmath>

namespace lmd {

// Reduce to t = min / max in [0, 1]; atan(t) = atan(k / 8) + atan(u) with
// k = round(8 t) and u = (t - k / 8) / (1 + t k / 8), so |u| <= 1 / 16 and
// seven terms of atan's Taylor series leave an error below 1e-17.
double FullTurnAngle(double y, double x) {
  static const double kAtanOfEighths[9] = {std::atan(0.0),   std::atan(0.125), std::atan(0.25),
                                           std::atan(0.375), std::atan(0.5),   std::atan(0.625),
                                           std::atan(0.75),  std::atan(0.875), std::atan(1.0)};
  const double ax = std::fabs(x), ay = std::fabs(y);
  if (!(ax + ay > 0)) return 0.0;  // (0, 0) or NaN
  const double hi = std::max(ax, ay);
  const double t = std::min(ax, ay) / hi;
  const int k = static_cast<int>(t * 8.0 + 0.5);
  const double tk = k * 0.125;
  const double u = (t - tk) / (1.0 + t * tk);
  const double u2 = u * u;
  const double series =
      u * (1.0 + u2 * (-1.0 / 3 + u2 * (1.0 / 5 + u2 * (-1.0 / 7 + u2 * (1.0 / 9 + u2 * (-1.0 / 11 + u2 / 13))))));
  double a = kAtanOfEighths[k] + series;  // atan(min / max), in [0, pi / 4]
  if (ay > ax) a = M_PI / 2 - a;          // [0, pi / 2]
  if (x < 0) a = M_PI - a;                // [0, pi]
  return std::signbit(y) && a != 0 ? 2 * M_PI - a : a;
}

}  // namespace lmd
