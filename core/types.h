// Core value types shared by every stage of the method (DESIGN.md §1):
// LocalMap -> Frame (planned viewpoint) -> Lmd (local map descriptor).
// Plain structs, no behaviour; units are metres and radians throughout.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace lmd {

// A 2D point in metres.
struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

// A planar pose: position in metres, heading in radians (counter-clockwise
// from the +x axis of the frame it is expressed in).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

// One 2D laser scan. Beam i points at pose.theta + first_angle + i * angle_step.
struct Scan {
  Pose2 pose;                 // laser pose, in the frame of the map holding it
  float first_angle = 0.0f;   // rad, relative to pose.theta
  float angle_step = 0.0f;    // rad between consecutive beams
  float max_range = 0.0f;     // m; a range >= max_range means "no return"
  std::vector<float> ranges;  // m
};

// What a local map knows about the world only for evaluation. No method may
// read it: it exists so that ground truth can be computed.
struct EvalTruth {
  Pose2 global_frame;        // pose of the map's own frame in the log's frame
  double travel_start = 0.0; // m of travel along the route at the first pose
  double travel_end = 0.0;   // m of travel at the last pose
};

// A local map as a robot builds it: points and trajectory in the map's own
// frame (any frame; by convention its first pose), optional raw scans so that
// free space can be ray-cast.
struct LocalMap {
  std::string id;
  std::vector<Point2> points;    // own frame, m
  std::vector<Pose2> trajectory; // own frame
  std::vector<Scan> scans;       // own frame; may be empty
  // rad per m travelled, >= 0: how far the trajectory's heading may have
  // drifted from the truth while the robot drove (its odometry's bound); 0:
  // a rigid map, as a scan matcher or SLAM builds it. A bent map fits
  // another rigidly only with its frame turned by part of the bend.
  double heading_drift_rad_per_m = 0.0;
  EvalTruth truth;               // evaluation only
};

// A planned viewpoint: a frame placed in the map's own frame. A point p in the
// map's own frame has coordinates R(-heading) * (p - origin) in this frame.
struct Frame {
  Point2 origin;       // m, in the map's own frame
  double heading = 0;  // rad, dominant orientation, in [0, pi/2)
};

// No word (Feature::inner_word of a descriptor described without one).
inline constexpr uint32_t kNoWord = 0xFFFFFFFF;

// One feature of a local map descriptor.
struct Feature {
  uint32_t appearance_word = 0;  // B-bit visual word (B <= 32) of the radius-R context
  float x = 0.0f;                // pose word source: position in the planned
  float y = 0.0f;                //   frame, m (quantised when indexed)
  uint64_t change_word = 0;      // 60-bit change word
  uint32_t inner_word = kNoWord;  // B-bit visual word of the inner context, or kNoWord
};

// Local map descriptor (LMD): the planned frame and the feature list.
struct Lmd {
  Frame frame;                   // planned viewpoint, in the map's own frame
  std::vector<Feature> features;
};

}  // namespace lmd
