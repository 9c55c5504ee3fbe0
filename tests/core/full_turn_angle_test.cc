#include "core/util/full_turn_angle.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace lmd {
namespace {

double Reference(double y, double x) {
  const double a = std::atan2(y, x);
  return a < 0 ? a + 2 * M_PI : a;
}

TEST(FullTurnAngleTest, MatchesTheLibraryAtan2WithinAFewUlps) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coord(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double y = std::ldexp(coord(rng), exponent(rng)), x = std::ldexp(coord(rng), exponent(rng));
    worst = std::max(worst, std::fabs(FullTurnAngle(y, x) - Reference(y, x)));
  }
  EXPECT_LE(worst, 8 * std::numeric_limits<double>::epsilon()) << worst;  // angles up to 2 pi: a few ulps
}

TEST(FullTurnAngleTest, AxesDiagonalsAndZeroAreExact) {
  for (double r : {1e-9, 0.01, 1.0, 7.5, 1e9}) {
    EXPECT_EQ(FullTurnAngle(0.0, r), 0.0);
    EXPECT_EQ(FullTurnAngle(r, 0.0), Reference(r, 0.0));
    EXPECT_EQ(FullTurnAngle(0.0, -r), Reference(0.0, -r));
    EXPECT_EQ(FullTurnAngle(-0.0, -r), Reference(-0.0, -r));
    EXPECT_EQ(FullTurnAngle(-r, 0.0), Reference(-r, 0.0));
    EXPECT_EQ(FullTurnAngle(r, r), Reference(r, r));
    EXPECT_EQ(FullTurnAngle(-r, -r), Reference(-r, -r));
  }
  EXPECT_EQ(FullTurnAngle(0.0, 0.0), 0.0);
  EXPECT_EQ(FullTurnAngle(std::nan(""), 1.0), 0.0);
}

}  // namespace
}  // namespace lmd
