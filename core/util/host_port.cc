#include "core/util/host_port.h"

#include <cerrno>
#include <cstdlib>

namespace lmd {

Result<HostPort> ParseHostPort(const std::string& address, int min_port, const std::string& what) {
  const std::string shown = what + " '" + address + "'";
  const size_t colon = address.rfind(':');
  const std::string port = colon == std::string::npos ? "" : address.substr(colon + 1);
  if (colon == 0 || port.empty() || port.find_first_not_of("0123456789") != std::string::npos) {
    return Status::InvalidArgument(shown + " is not HOST:PORT");
  }
  errno = 0;
  const unsigned long number = std::strtoul(port.c_str(), nullptr, 10);
  if (errno == ERANGE || number < static_cast<unsigned long>(min_port) || number > 65535) {
    return Status::InvalidArgument(shown + ": port " + port + " is not from " + std::to_string(min_port) +
                                   " to 65535");
  }
  HostPort parsed;
  parsed.host = address.substr(0, colon);
  if (parsed.host.size() > 2 && parsed.host.front() == '[' && parsed.host.back() == ']') {
    parsed.host = parsed.host.substr(1, parsed.host.size() - 2);
  }
  parsed.port = static_cast<int>(number);
  return parsed;
}

}  // namespace lmd
