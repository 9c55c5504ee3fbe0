// atan2 mapped to a full turn, fast: the describer's angular bins call it
// once per neighbour of every interest point.
#pragma once

namespace lmd {

// atan2(y, x) + (2 pi if atan2 is negative), in [0, 2 pi), within a few ulps
// of the C library's atan2. glibc's atan2 is correctly rounded and slow: it
// was about 4 % of lmdd's CPU. (0, 0) and NaN give 0.
double FullTurnAngle(double y, double x);

}  // namespace lmd
