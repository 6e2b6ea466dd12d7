#include "sim/corridor_client.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "sim/errors.hpp"

namespace corridor::sim {

std::string path_segment(std::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto b = static_cast<unsigned char>(c);
    const bool unreserved = (b >= 'A' && b <= 'Z') || (b >= 'a' && b <= 'z') || (b >= '0' && b <= '9') || b == '-' ||
                            b == '.' || b == '_' || b == '~';
    if (unreserved) {
      out.push_back(c);
    } else {
      out.push_back('%');
      out.push_back(kHex[b >> 4]);
      out.push_back(kHex[b & 15]);
    }
  }
  return out;
}

namespace beast = boost::beast;
namespace http = beast::http;
using tcp = boost::asio::ip::tcp;

struct CorridorClient::Connection {
  boost::asio::io_context io;
  beast::tcp_stream stream{io};
  beast::flat_buffer buffer;
};

CorridorClient::CorridorClient(const std::string& url, std::string token) : token_(std::move(token)) {
  const std::string prefix = "http://";
  if (url.rfind(prefix, 0) != 0) throw SimError("--server must be an http:// URL such as http://127.0.0.1:8080, got '" + url + "'");
  std::string rest = url.substr(prefix.size());
  if (const auto slash = rest.find('/'); slash != std::string::npos) rest = rest.substr(0, slash);
  const auto colon = rest.rfind(':');
  host_ = colon == std::string::npos ? rest : rest.substr(0, colon);
  port_ = colon == std::string::npos ? "80" : rest.substr(colon + 1);
  if (host_.empty() || port_.empty()) throw SimError("--server '" + url + "' names no host or port");
}

CorridorClient::~CorridorClient() = default;

nlohmann::json CorridorClient::get(const std::string& target) { return send("GET", target, {}); }

nlohmann::json CorridorClient::post(const std::string& target, const nlohmann::json& body) {
  return send("POST", target, body.dump());
}

nlohmann::json CorridorClient::send(const std::string& method, const std::string& target, const std::string& body) {
  for (int attempt = 1;; ++attempt) {
    try {
      if (!connection_) {
        connection_ = std::make_unique<Connection>();
        tcp::resolver resolver(connection_->io);
        connection_->stream.connect(resolver.resolve(host_, port_));
      }
      http::request<http::string_body> req{method == "GET" ? http::verb::get : http::verb::post, target, 11};
      req.set(http::field::host, host_);
      req.set(http::field::authorization, "Bearer " + token_);
      req.keep_alive(true);
      if (method != "GET") {
        req.set(http::field::content_type, "application/json");
        req.body() = body;
        req.prepare_payload();
      }
      connection_->stream.expires_after(std::chrono::seconds(30));
      http::write(connection_->stream, req);
      http::response<http::string_body> res;
      http::read(connection_->stream, connection_->buffer, res);
      if (!res.keep_alive()) connection_.reset();
      nlohmann::json j = nlohmann::json::parse(res.body(), nullptr, false);
      if (res.result_int() < 200 || res.result_int() >= 300) {
        const std::string message = j.is_object() && j.contains("error") ? j["error"].value("message", res.body()) : res.body();
        throw SimError(method + " " + target + " answered " + std::to_string(res.result_int()) + ": " + message);
      }
      if (j.is_discarded()) throw SimError(method + " " + target + " answered with something that is not JSON");
      return j;
    } catch (const beast::system_error& e) {
      connection_.reset();
      if (attempt >= 2) {
        throw SimError("cannot reach the Corridor server at " + host_ + ":" + port_ + " (" + e.what() + ")");
      }
    }
  }
}

}  // namespace corridor::sim
