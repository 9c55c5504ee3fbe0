// The picture of a site map: the anchored stored maps (grey) in the
// collection's frame, a robot's route through it (blue), each fix lmdd gave
// (green: right, red: wrong, orange: not sure; an arrow for its heading, a
// number for its order) and the changes found (red circles) next to the true
// ones (green boxes). Labels are placed where they overlap neither another
// label nor a marker, with a leader line when they had to move away; a label
// that finds no free place is left out rather than drawn over another.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"

namespace lmd {

struct SiteMap {
  const LocalMap* map = nullptr;  // own frame
  Pose2 anchor;                   // its own frame in the site's
};

enum class FixOutcome { kRight, kWrong, kUnsure };

struct SiteFix {
  Pose2 pose;  // the query's own frame in the site's, as lmdd answered
  FixOutcome outcome = FixOutcome::kRight;
  std::string label;
};

struct SitePicture {
  std::vector<SiteMap> maps;
  std::vector<Point2> route;  // site frame
  std::vector<SiteFix> fixes;
  std::vector<Point2> changes;                   // centres of the changes found, site frame
  std::vector<std::vector<Point2>> true_changes; // true change regions (corners), site frame
  std::string title;
};

// The SVG document; *labels_left_out (if not null) counts labels that found
// no free place.
std::string RenderSiteSvg(const SitePicture& picture, int* labels_left_out = nullptr);

}  // namespace lmd
