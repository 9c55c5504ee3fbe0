// The metric pose a retrieval hit implies: where the query map's own frame
// lies in the db map's own frame, from the two planned viewpoints, the hit's
// orientation (multiples of 90 deg) and its alignment offset.
//
// The index aligns planned positions as db = R(o * 90 deg) q + offset; with
// q = R(-h_q) (p - o_q) and own_db = o_d + R(h_d) db, a point p of the query's
// own frame lands at own_db = t + R(theta) p with theta = h_d + o 90 deg - h_q
// and t = o_d + R(h_d) offset - R(theta) o_q.
#pragma once

#include "core/localmap/pose_ops.h"  // TransformPoint, Compose, Inverse
#include "core/types.h"

namespace lmd {

// Pose (x, y, theta) of the query's own frame in the db map's own frame;
// theta is wrapped to (-pi, pi].
Pose2 RelativePose(const Frame& query_frame, const Frame& db_frame, int orientation, const Point2& offset);

}  // namespace lmd
