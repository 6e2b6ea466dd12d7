// HOST:PORT on the command line (--listen), checked: an IP address and a port in range.
#pragma once

#include <string>

namespace corridor::app {

struct ListenAddress {
  std::string host;
  int port = 0;
};

// Throws UsageError naming `option` for anything that is not IP:PORT with the port in
// [min_port, 65535].
ListenAddress parse_listen_address(const std::string& text, const std::string& option, int min_port = 0);

}  // namespace corridor::app
