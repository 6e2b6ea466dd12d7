// libFuzzer target for the request path: arbitrary method, target, token and body into the Router.
// Any response with a 5xx status, and any crash or sanitizer report, is a finding.
// Build with the `fuzz` preset (clang) and run scripts/fuzz.sh.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "maps/synthetic_grid.hpp"
#include "server/router.hpp"

namespace {

using namespace corridor;

struct Target {
  maps::RoadGraph graph = [] {
    maps::GridSpec spec;
    spec.rows = 6;
    spec.cols = 6;
    spec.seed = 3;
    spec.signal_fraction = 0.5;
    return maps::make_perturbed_grid(spec);
  }();
  server::DispatchService service{graph, {}, nullptr, 0.0};
  double now = 1.0;
  // The console's files too: the static routing (client routes, dot segments, odd bytes) is fuzzed
  // through the same entry point.
  server::Router router{service, make_auth(), {}, [this] { return now; },
                        std::make_shared<server::StaticSite>(std::vector<server::StaticAsset>{
                            {"/index.html", "<!doctype html>"}, {"/assets/app-1.js", "x"}})};

  static server::TokenAuth make_auth() {
    server::TokenAuth auth;
    auth.add("fuzz-token-0123456789", {"fuzz", server::kAllRoles, std::nullopt});
    return auth;
  }
};

const char* const kTargets[] = {"/v1/missions", "/v1/missions/1", "/v1/missions/1/cancel", "/v1/congestion",
                                "/v1/vehicles/amb-1/position", "/v1/signals/0/counts", "/v1/signals", "/v1/signals/7",
                                "/v1/missions?state=active", "/v1/health", "/metrics", "/v1/map",
                                "/v1/me", "/v1/stream/ticket", "/v1/vehicles", "/v1/missions/1/routes",
                                "/", "/assets/app-1.js", "/missions/1", "/assets/../index.html"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Target t;
  if (size < 2) return 0;
  const std::uint8_t selector = data[0];
  server::HttpRequest req;
  req.method = (selector & 1) != 0 ? "POST" : "GET";
  req.target = kTargets[(selector >> 1) % (sizeof kTargets / sizeof kTargets[0])];
  req.authorization = (data[1] & 1) != 0 ? "Bearer fuzz-token-0123456789" : "Bearer nope";
  req.body.assign(reinterpret_cast<const char*>(data + 2), size - 2);
  if ((data[1] & 2) != 0) {
    // The target comes from the input as well: its first line, the rest is the body.
    const auto newline = req.body.find('\n');
    req.target = req.body.substr(0, newline);
    req.body = newline == std::string::npos ? "" : req.body.substr(newline + 1);
  }
  (void)t.router.blocks(req);
  t.now += 0.5;
  const server::HttpResponse r = t.router.handle(req);
  if (r.status >= 500) std::abort();
  return 0;
}
