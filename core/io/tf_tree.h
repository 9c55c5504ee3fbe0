// The transforms of a bag's /tf and /tf_static, and lookups through them
// (what tf2's buffer does, for planar use): each child frame has one parent;
// a lookup composes the edges between two frames, each edge interpolated at
// the asked time (static edges hold at every time).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/io/ros_messages.h"
#include "core/status.h"
#include "core/types.h"

namespace lmd {

// A transform projected on the plane: (x, y, yaw) of the child frame in the
// parent frame, and whether the child is upside down (its z axis points
// down: a laser mounted upside down sees its beams in the mirrored order).
struct PlanarTransform {
  Pose2 pose;
  bool flipped = false;
};

// Planar projection of a 3D transform.
PlanarTransform ToPlanar(const Transform3& t);

class TfTree {
 public:
  // Adds `t` (child in parent). A child that already has another parent
  // keeps its first one (tf forbids two); returns false then.
  bool Add(const TransformStampedMessage& t, bool is_static);

  // The frames known, as "parent -> child" lines, for error messages.
  std::vector<std::string> Edges() const;
  bool HasFrame(const std::string& frame) const;
  // True if `a` and `b` are in one tree (a lookup between them can succeed).
  bool Connected(const std::string& a, const std::string& b) const;

  // Pose of `source` in `target` at `stamp_ns`: dynamic edges interpolated
  // between their two samples around the stamp, or the nearest sample when
  // it lies within tolerance_ns beyond the first / last one or across a gap
  // of at most 2 tolerance_ns. NotFound (saying which frame or time) otherwise.
  Result<Transform3> Lookup(const std::string& target, const std::string& source, int64_t stamp_ns,
                            int64_t tolerance_ns) const;

 private:
  struct Edge {
    std::string parent;
    bool is_static = false;
    std::vector<std::pair<int64_t, Transform3>> samples;  // sorted by stamp
  };
  Result<Transform3> EdgeAt(const std::string& child, const Edge& edge, int64_t stamp_ns, int64_t tolerance_ns) const;
  // Frames from `frame` up to its root, `frame` first.
  std::vector<std::string> Ancestry(const std::string& frame) const;

  std::map<std::string, Edge> edges_;  // by child frame
};

// Linear / slerp interpolation of two transforms, fraction f in [0, 1].
Transform3 Interpolate(const Transform3& a, const Transform3& b, double f);
// a * b (b expressed in a's child frame, result in a's parent frame).
Transform3 ComposeTransforms(const Transform3& a, const Transform3& b);
Transform3 InverseTransform(const Transform3& a);

}  // namespace lmd
