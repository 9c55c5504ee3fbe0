// Conversions between the wire messages (lmd.v1) and core's value types.
// The wire carries points as float32 packed arrays; core works in double.
#pragma once

#include <Eigen/Core>

#include "core/types.h"
#include "lmd/v1/lmd.pb.h"

namespace lmd {

// Wire -> core. The map must have been validated (equal x/y lengths).
LocalMap FromProto(const v1::LocalMap& map);
Pose2 FromProto(const v1::Pose2& pose);
Eigen::Matrix3d FromProto(const v1::PoseCovariance& covariance);

// Core -> wire. Truth (evaluation only) and the id are not sent.
v1::LocalMap ToProto(const LocalMap& map);
v1::Pose2 ToProto(const Pose2& pose);
v1::PoseCovariance ToProto(const Eigen::Matrix3d& covariance);  // its upper triangle

}  // namespace lmd
