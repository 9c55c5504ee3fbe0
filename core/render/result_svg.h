// The picture of one retrieval result, like the paper's Fig. 5: the db map
// (grey) and the query map (blue) overlaid in the db map's frame through the
// hit's pose, the detected change masks (red circles, numbered by rank) and,
// when known, the true change region (green box).
#pragma once

#include <string>
#include <vector>

#include "core/types.h"

namespace lmd {

struct ResultPicture {
  const LocalMap* query = nullptr;        // own frame
  const LocalMap* db = nullptr;           // own frame
  Pose2 query_in_db;                      // pose of the query's frame in the db's
  std::vector<std::vector<Point2>> masks; // ranked, query's own frame
  std::vector<Point2> true_change;        // region corners, query's own frame; may be empty
  std::string title;
};

// The SVG document.
std::string RenderResultSvg(const ResultPicture& picture);

}  // namespace lmd
