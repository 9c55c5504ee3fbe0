// Small SE(2) helpers shared by the local map builder, simulator and ground
// truth. Header-only, all inline.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/types.h"

namespace lmd {

// Wraps an angle to (-pi, pi].
inline double NormalizeAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a <= 0.0) a += 2.0 * M_PI;
  return a - M_PI;
}

// a * b: pose b (expressed in frame a) expressed in a's parent frame.
inline Pose2 Compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, NormalizeAngle(a.theta + b.theta)};
}

// a^-1.
inline Pose2 Inverse(const Pose2& a) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {-(c * a.x + s * a.y), -(-s * a.x + c * a.y), NormalizeAngle(-a.theta)};
}

// Points of frame a expressed in a's parent frame, the sine and cosine
// computed once for all of them.
class PointTransform {
 public:
  explicit PointTransform(const Pose2& a) : a_(a), c_(std::cos(a.theta)), s_(std::sin(a.theta)) {}
  Point2 operator()(const Point2& p) const { return {a_.x + c_ * p.x - s_ * p.y, a_.y + s_ * p.x + c_ * p.y}; }

 private:
  Pose2 a_;
  double c_, s_;
};

// Point p (in frame a) expressed in a's parent frame.
inline Point2 TransformPoint(const Pose2& a, const Point2& p) { return PointTransform(a)(p); }

// Median of each component of `poses` (the upper one for an even count);
// headings as given, so wrap them around a common reference first. Empty
// input: the identity.
inline Pose2 ComponentMedian(const std::vector<Pose2>& poses) {
  if (poses.empty()) return {};
  auto median = [&](double Pose2::*field) {
    std::vector<double> v;
    for (const Pose2& p : poses) v.push_back(p.*field);
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  return {median(&Pose2::x), median(&Pose2::y), median(&Pose2::theta)};
}

}  // namespace lmd
