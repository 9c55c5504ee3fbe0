#include "core/io/tf_tree.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace lmd {
namespace {

Eigen::Quaterniond Q(const Transform3& t) {
  Eigen::Quaterniond q(t.qw, t.qx, t.qy, t.qz);
  const double n = q.norm();
  if (!(n > 1e-12) || !std::isfinite(n)) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(q.coeffs() / n);
}

Transform3 Make(const Eigen::Quaterniond& q, const Eigen::Vector3d& v) {
  Transform3 t;
  t.x = v.x(), t.y = v.y(), t.z = v.z();
  t.qx = q.x(), t.qy = q.y(), t.qz = q.z(), t.qw = q.w();
  return t;
}

std::string Seconds(int64_t ns) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3f s", static_cast<double>(ns) * 1e-9);
  return buf;
}

}  // namespace

PlanarTransform ToPlanar(const Transform3& t) {
  const Eigen::Matrix3d r = Q(t).toRotationMatrix();
  PlanarTransform p;
  p.pose = {t.x, t.y, std::atan2(r(1, 0), r(0, 0))};
  p.flipped = r(2, 2) < 0;
  return p;
}

Transform3 Interpolate(const Transform3& a, const Transform3& b, double f) {
  const Eigen::Vector3d va(a.x, a.y, a.z), vb(b.x, b.y, b.z);
  return Make(Q(a).slerp(f, Q(b)), va + f * (vb - va));
}

Transform3 ComposeTransforms(const Transform3& a, const Transform3& b) {
  const Eigen::Quaterniond qa = Q(a);
  return Make(qa * Q(b), Eigen::Vector3d(a.x, a.y, a.z) + qa * Eigen::Vector3d(b.x, b.y, b.z));
}

Transform3 InverseTransform(const Transform3& a) {
  const Eigen::Quaterniond qi = Q(a).conjugate();
  return Make(qi, -(qi * Eigen::Vector3d(a.x, a.y, a.z)));
}

bool TfTree::Add(const TransformStampedMessage& t, bool is_static) {
  if (t.child_frame_id.empty() || t.child_frame_id == t.frame_id) return false;
  auto [it, added] = edges_.try_emplace(t.child_frame_id);
  Edge& e = it->second;
  if (added) e.parent = t.frame_id;
  if (e.parent != t.frame_id) return false;
  if (is_static) {
    e.is_static = true;
    e.samples.assign(1, {t.stamp_ns, t.transform});  // the latest static transform wins, as in tf2
    return true;
  }
  if (e.is_static) return true;
  // Kept sorted by stamp (publishers interleave; appending is the usual case).
  const auto at = std::upper_bound(e.samples.begin(), e.samples.end(), t.stamp_ns,
                                   [](int64_t v, const auto& x) { return v < x.first; });
  e.samples.insert(at, {t.stamp_ns, t.transform});
  return true;
}

std::vector<std::string> TfTree::Edges() const {
  std::vector<std::string> out;
  for (const auto& [child, e] : edges_) out.push_back(e.parent + " -> " + child + (e.is_static ? " (static)" : ""));
  return out;
}

bool TfTree::HasFrame(const std::string& frame) const {
  if (edges_.count(frame)) return true;
  for (const auto& [child, e] : edges_) {
    if (e.parent == frame) return true;
  }
  return false;
}

std::vector<std::string> TfTree::Ancestry(const std::string& frame) const {
  std::vector<std::string> chain{frame};
  for (size_t guard = 0; guard < edges_.size(); ++guard) {
    const auto it = edges_.find(chain.back());
    if (it == edges_.end()) break;
    if (std::find(chain.begin(), chain.end(), it->second.parent) != chain.end()) break;  // a cycle: stop
    chain.push_back(it->second.parent);
  }
  return chain;
}

bool TfTree::Connected(const std::string& a, const std::string& b) const {
  if (!HasFrame(a) || !HasFrame(b)) return a == b;
  return Ancestry(a).back() == Ancestry(b).back();
}

Result<Transform3> TfTree::EdgeAt(const std::string& child, const Edge& edge, int64_t t, int64_t tol) const {
  const auto& s = edge.samples;
  if (edge.is_static || s.size() == 1) {
    if (edge.is_static || std::llabs(s[0].first - t) <= tol) return s[0].second;
  } else {
    const auto after = std::lower_bound(s.begin(), s.end(), t, [](const auto& x, int64_t v) { return x.first < v; });
    if (after != s.end() && after->first == t) return after->second;
    if (after == s.begin()) {
      if (s.front().first - t <= tol) return s.front().second;
    } else if (after == s.end()) {
      if (t - s.back().first <= tol) return s.back().second;
    } else {
      const auto before = after - 1;
      const int64_t gap = after->first - before->first;
      if (gap <= 2 * tol) {
        return Interpolate(before->second, after->second, static_cast<double>(t - before->first) / gap);
      }
    }
  }
  return Status::NotFound("tf " + edge.parent + " -> " + child + " has no transform near " + Seconds(t) + " (" +
                          std::to_string(s.size()) + " between " + Seconds(s.front().first) + " and " +
                          Seconds(s.back().first) + ")");
}

Result<Transform3> TfTree::Lookup(const std::string& target, const std::string& source, int64_t stamp_ns,
                                  int64_t tolerance_ns) const {
  if (target == source) return Transform3{};
  const std::vector<std::string> up_source = Ancestry(source), up_target = Ancestry(target);
  size_t common_s = up_source.size(), common_t = up_target.size();
  for (size_t i = 0; i < up_source.size() && common_s == up_source.size(); ++i) {
    for (size_t j = 0; j < up_target.size(); ++j) {
      if (up_source[i] == up_target[j]) {
        common_s = i, common_t = j;
        break;
      }
    }
  }
  if (common_s == up_source.size()) {
    return Status::NotFound("tf has no chain from '" + target + "' to '" + source + "'");
  }
  // source in the common ancestor, then target in it; result = inv(target_in_common) * source_in_common.
  Transform3 source_in_common, target_in_common;
  for (size_t i = 0; i < common_s; ++i) {
    Result<Transform3> e = EdgeAt(up_source[i], edges_.at(up_source[i]), stamp_ns, tolerance_ns);
    if (!e.ok()) return e.status();
    source_in_common = ComposeTransforms(*e, source_in_common);
  }
  for (size_t j = 0; j < common_t; ++j) {
    Result<Transform3> e = EdgeAt(up_target[j], edges_.at(up_target[j]), stamp_ns, tolerance_ns);
    if (!e.ok()) return e.status();
    target_in_common = ComposeTransforms(*e, target_in_common);
  }
  return ComposeTransforms(InverseTransform(target_in_common), source_in_common);
}

}  // namespace lmd
