#include "core/types.h"

#include <gtest/gtest.h>

TEST(TypesTest, FrameDefaultsToIdentity) {
  lmd::Frame frame;
  EXPECT_EQ(frame.origin.x, 0.0);
  EXPECT_EQ(frame.heading, 0.0);
}
