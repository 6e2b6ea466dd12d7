#include "server/static_site.hpp"

#include <stdexcept>

namespace corridor::server {
namespace {

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

StaticReply not_found(std::string_view path) {
  StaticReply r;
  r.status = 404;
  r.error_code = "not_found";
  r.error_message = "no such file: " + std::string(path.substr(0, 200));
  return r;
}

}  // namespace

const char* StaticSite::content_type_for(std::string_view path) {
  struct Type {
    std::string_view ext;
    const char* type;
  };
  static constexpr Type kTypes[] = {
      {".html", "text/html; charset=utf-8"},      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},              {".map", "application/json"},
      {".svg", "image/svg+xml"},                  {".png", "image/png"},
      {".jpg", "image/jpeg"},                     {".ico", "image/x-icon"},
      {".woff2", "font/woff2"},                   {".woff", "font/woff"},
      {".txt", "text/plain; charset=utf-8"},      {".webmanifest", "application/manifest+json"},
  };
  for (const Type& t : kTypes) {
    if (ends_with(path, t.ext)) return t.type;
  }
  return "application/octet-stream";
}

StaticSite::StaticSite(const std::vector<StaticAsset>& assets) {
  for (const StaticAsset& a : assets) {
    if (a.path.empty() || a.path.front() != '/') throw std::invalid_argument("asset path must start with '/'");
    files_[std::string(a.path)] = a.bytes;
  }
  auto it = files_.find("/index.html");
  if (it == files_.end()) throw std::invalid_argument("the console has no /index.html");
  index_ = it->second;
}

StaticReply StaticSite::file_reply(std::string_view path, std::string_view bytes) const {
  StaticReply r;
  r.content_type = content_type_for(path);
  r.body = bytes;
  r.headers.emplace_back("X-Content-Type-Options", "nosniff");
  r.headers.emplace_back("Referrer-Policy", "no-referrer");
  if (ends_with(path, ".html")) {
    // The page names its hashed assets, so it is revalidated every time; the assets never change.
    r.headers.emplace_back("Cache-Control", "no-cache");
    r.headers.emplace_back("Content-Security-Policy", kConsoleCsp);
    r.headers.emplace_back("X-Frame-Options", "DENY");
  } else if (path.rfind("/assets/", 0) == 0) {
    r.headers.emplace_back("Cache-Control", "public, max-age=31536000, immutable");
  } else {
    r.headers.emplace_back("Cache-Control", "public, max-age=3600");
  }
  return r;
}

StaticReply StaticSite::serve(std::string_view path) const {
  if (path.empty() || path.front() != '/' || path.size() > 1024 || path.find('\0') != std::string_view::npos ||
      path.find('\\') != std::string_view::npos || path.find("/.") != std::string_view::npos ||
      path.find("//") != std::string_view::npos) {
    return not_found(path);
  }
  if (path == "/") return file_reply("/index.html", index_);
  if (auto it = files_.find(std::string(path)); it != files_.end()) return file_reply(path, it->second);
  // A client-side route has no extension in its last segment; a missing file does.
  const std::string_view last = path.substr(path.rfind('/') + 1);
  if (last.find('.') == std::string_view::npos && path.rfind("/assets/", 0) != 0) return file_reply("/index.html", index_);
  return not_found(path);
}

}  // namespace corridor::server
