// HOST:PORT addresses, as lmdd listens on them and its clients dial them:
// "127.0.0.1:50051", "localhost:50051", "[::1]:50051". One parser for lmdd
// and the clients: gRPC itself takes a port above 65535 modulo 65536
// (":99999" serves or dials 34463) instead of refusing it.
#pragma once

#include <string>

#include "core/status.h"

namespace lmd {

struct HostPort {
  std::string host;  // an IPv6 address without its brackets
  int port = 0;
};

// `address` split at its last colon. InvalidArgument, starting with `what`
// and the address ("listen address '127.0.0.1:99999': port 99999 is not from
// 0 to 65535"), if it is not HOST:PORT or its port is below `min_port` (0 for
// a listening address: any free port; 1 for one to dial) or above 65535.
Result<HostPort> ParseHostPort(const std::string& address, int min_port, const std::string& what);

}  // namespace lmd
