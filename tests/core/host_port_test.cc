#include "core/util/host_port.h"

#include <gtest/gtest.h>

namespace lmd {
namespace {

TEST(HostPortTest, SplitsHostAndPort) {
  Result<HostPort> parsed = ParseHostPort("127.0.0.1:50051", 1, "server address");
  ASSERT_TRUE(parsed.ok()) << parsed.status().ToString();
  EXPECT_EQ(parsed->host, "127.0.0.1");
  EXPECT_EQ(parsed->port, 50051);
  parsed = ParseHostPort("[::1]:0", 0, "listen address");
  ASSERT_TRUE(parsed.ok()) << parsed.status().ToString();
  EXPECT_EQ(parsed->host, "::1");
  EXPECT_EQ(parsed->port, 0);
  EXPECT_EQ(ParseHostPort("node-2:65535", 1, "server address")->port, 65535);
}

// gRPC takes these modulo 65536 (":99999" is port 34463) instead of refusing them.
TEST(HostPortTest, PortsOutsideTheRangeAreRefused) {
  EXPECT_EQ(ParseHostPort("127.0.0.1:99999", 0, "listen address").status().message(),
            "listen address '127.0.0.1:99999': port 99999 is not from 0 to 65535");
  EXPECT_EQ(ParseHostPort("127.0.0.1:65536", 0, "listen address").status().message(),
            "listen address '127.0.0.1:65536': port 65536 is not from 0 to 65535");
  EXPECT_EQ(ParseHostPort("127.0.0.1:0", 1, "server address").status().message(),
            "server address '127.0.0.1:0': port 0 is not from 1 to 65535");
  EXPECT_FALSE(ParseHostPort("127.0.0.1:99999999999999999999999", 0, "listen address").ok());
}

TEST(HostPortTest, WhatIsNotHostPortIsRefused) {
  for (const char* address : {"garbage", ":50051", "host:", "host:-1", "host:5x", "host: 50"}) {
    Result<HostPort> parsed = ParseHostPort(address, 0, "listen address");
    ASSERT_FALSE(parsed.ok()) << address;
    EXPECT_EQ(parsed.status().message(), "listen address '" + std::string(address) + "' is not HOST:PORT");
  }
}

}  // namespace
}  // namespace lmd
