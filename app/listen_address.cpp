#include "app/listen_address.hpp"

#include <boost/asio/ip/address.hpp>

#include "app/cli_error.hpp"

namespace corridor::app {

ListenAddress parse_listen_address(const std::string& text, const std::string& option, int min_port) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos) throw UsageError(option + " expects HOST:PORT, got '" + text + "'");
  ListenAddress a;
  a.host = text.substr(0, colon);
  a.port = -1;
  const std::string port = text.substr(colon + 1);
  if (!port.empty() && port.size() <= 5 && port.find_first_not_of("0123456789") == std::string::npos) a.port = std::stoi(port);
  if (a.port < min_port || a.port > 65535) {
    throw UsageError(option + " port must be " + std::to_string(min_port) + "..65535, got '" + port + "'");
  }
  boost::system::error_code ec;
  (void)boost::asio::ip::make_address(a.host, ec);
  if (ec) throw UsageError(option + " host must be an IP address (for example 127.0.0.1 or ::1), got '" + a.host + "'");
  return a;
}

}  // namespace corridor::app
