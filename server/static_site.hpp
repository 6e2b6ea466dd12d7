// The dispatch console's files, served at `/`: an index page, hashed assets and client-side routes,
// with content types, caching headers and a strict Content-Security-Policy. Transport-free, like
// the Router that calls it, so it is unit-tested and fuzzed without sockets.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace corridor::server {

// One embedded file: its URL path ("/index.html", "/assets/index-3f2a.js") and bytes. The bytes
// must outlive the site (they are compiled into the executable).
struct StaticAsset {
  std::string_view path;
  std::string_view bytes;
};

struct StaticReply {
  int status = 200;
  std::string content_type;
  std::string_view body;  // points into the asset
  std::vector<std::pair<std::string, std::string>> headers;
  std::string error_code;  // for a status other than 200: the JSON error's code and message
  std::string error_message;
};

// No inline scripts or styles, nothing from another origin, no framing: the console needs none.
inline constexpr const char* kConsoleCsp =
    "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; connect-src 'self'; "
    "font-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'; form-action 'self'";

class StaticSite {
 public:
  // Throws std::invalid_argument when there is no /index.html or a path is not absolute.
  explicit StaticSite(const std::vector<StaticAsset>& assets);

  // The answer for GET or HEAD of `path` (without its query): the asset; index.html for `/` and for
  // any extension-less path (a client-side route such as /missions/3); 404 for a missing file
  // (a name with an extension) and for anything malformed (dot segments, NUL, backslash, over 1 KiB).
  [[nodiscard]] StaticReply serve(std::string_view path) const;

  [[nodiscard]] std::size_t size() const { return files_.size(); }

  // By file extension; application/octet-stream when unknown.
  static const char* content_type_for(std::string_view path);

 private:
  [[nodiscard]] StaticReply file_reply(std::string_view path, std::string_view bytes) const;
  std::unordered_map<std::string, std::string_view> files_;
  std::string_view index_;
};

}  // namespace corridor::server
