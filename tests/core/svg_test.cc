#include "core/render/svg_writer.h"

#include <gtest/gtest.h>

#include "core/describe/describer.h"
#include "core/render/local_map_svg.h"
#include "core/render/site_svg.h"
#include "core/viewpoint/viewpoint.h"
#include "tests/core/toy_world.h"

namespace lmd {
namespace {

TEST(SvgWriterTest, MapsWorldToPixelsWithYUp) {
  SvgWriter svg(0, 0, 10, 5, 200);
  EXPECT_DOUBLE_EQ(svg.height_px(), 100.0);
  EXPECT_DOUBLE_EQ(svg.PxX(0), 0.0);
  EXPECT_DOUBLE_EQ(svg.PxX(10), 200.0);
  EXPECT_DOUBLE_EQ(svg.PxY(5), 0.0);    // top
  EXPECT_DOUBLE_EQ(svg.PxY(0), 100.0);  // bottom
}

TEST(SvgWriterTest, DocumentIsWellFormedAndEscapesText) {
  SvgWriter svg(0, 0, 1, 1);
  svg.Line({0, 0}, {1, 1}, {});
  svg.Text({0.5, 0.5}, "a < b & \"c\"");
  const std::string doc = svg.ToString();
  EXPECT_EQ(doc.rfind("<svg", 0), 0u);
  EXPECT_NE(doc.find("</svg>"), std::string::npos);
  EXPECT_NE(doc.find("a &lt; b &amp; &quot;c&quot;"), std::string::npos);
  EXPECT_NE(doc.find("<line"), std::string::npos);
}

TEST(LocalMapSvgTest, PictureShowsBothViewpointsAndTheFeatures) {
  const LocalMap map = testing::ScanWorld(testing::RoomAndCorridor(), testing::RoomVisit());
  const ViewpointPlan plan = PlanViewpointDetailed(map, {});
  const Lmd lmd = Describe(map, plan.frame);
  const std::string doc = RenderLocalMapSvg(map, plan, &lmd, {});
  EXPECT_NE(doc.find("CoG"), std::string::npos);
  EXPECT_NE(doc.find("CoR"), std::string::npos);
  EXPECT_NE(doc.find("#9467bd"), std::string::npos);  // features
  EXPECT_NE(doc.find("<polyline"), std::string::npos);  // trajectory
  EXPECT_NE(doc.find("</svg>"), std::string::npos);
}

// The site picture's legend names what it shows: a site map alone (lmdctl
// site) has no route, fixes or changes to explain.
TEST(SiteSvgTest, TheLegendNamesOnlyWhatThePictureShows) {
  LocalMap room;
  room.points = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  SitePicture site;
  site.maps.push_back({&room, Pose2{10, 5, 0.5}});
  const std::string alone = RenderSiteSvg(site);
  EXPECT_NE(alone.find("grey: stored maps in the site frame"), std::string::npos);
  EXPECT_EQ(alone.find("true route"), std::string::npos);
  EXPECT_EQ(alone.find("fixes (arrow"), std::string::npos);

  site.route = {{10, 5}, {12, 6}};
  site.fixes.push_back({Pose2{11, 5, 0}, FixOutcome::kRight, "1"});
  const std::string tracked = RenderSiteSvg(site);
  EXPECT_NE(tracked.find("; blue: the robot's true route"), std::string::npos);
  EXPECT_NE(tracked.find("fixes (arrow"), std::string::npos);
  EXPECT_EQ(tracked.find("changes found"), std::string::npos);
}

}  // namespace
}  // namespace lmd
