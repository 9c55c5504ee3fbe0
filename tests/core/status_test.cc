#include "core/status.h"

#include <gtest/gtest.h>

TEST(StatusTest, ResultHoldsValueOrError) {
  lmd::Result<int> good(3);
  ASSERT_TRUE(good.ok());
  EXPECT_EQ(*good, 3);
  lmd::Result<int> bad(lmd::Status::InvalidArgument("x is NaN"));
  EXPECT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), lmd::Status::Code::kInvalidArgument);
  EXPECT_EQ(bad.status().message(), "x is NaN");
}

TEST(StatusTest, ToStringNamesTheCode) {
  EXPECT_EQ(lmd::Status::Ok().ToString(), "OK");
  EXPECT_EQ(lmd::Status::NotFound("map m1").ToString(), "NOT_FOUND: map m1");
}
