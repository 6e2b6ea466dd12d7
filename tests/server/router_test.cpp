#include "server/router.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <future>
#include <random>

#include "maps/synthetic_grid.hpp"
#include "tests/server/api_fixture.hpp"
#include "tests/server/temp_db.hpp"

namespace corridor::server {
namespace {

using nlohmann::json;

const maps::RoadGraph& grid() { return testing::api_grid(); }

using testing::kDispatcher;
using testing::kSensor;
using testing::kViewer;
using testing::kAmb1;

struct Rig {
  DispatchService service{grid(), {}, nullptr, 0.0};
  double now = 100.0;
  Router router;

  Rig() : router(service, make_auth(), {}, [this] { return now; }) {}

  static TokenAuth make_auth() { return testing::api_auth(); }
  HttpResponse call(const std::string& method, const std::string& target, const std::string& auth = "",
                    const std::string& body = "") {
    return router.handle({method, target, auth, body});
  }
};

std::string ll(NodeId n) {
  const auto p = grid().projection().to_lat_lon(grid().position(n));
  return "{\"lat\":" + std::to_string(p.lat_deg) + ",\"lon\":" + std::to_string(p.lon_deg) + "}";
}

std::string mission_body(const std::string& vehicle) {
  return "{\"vehicle_id\":\"" + vehicle + "\",\"origin\":" + ll(NodeId{0}) + ",\"destination\":" +
         ll(NodeId{static_cast<std::uint32_t>(grid().node_count() - 1)}) + ",\"priority\":2}";
}

json body(const HttpResponse& r) { return json::parse(r.body); }

TEST(Router, CreateReadListCancelMission) {
  Rig rig;
  const auto created = rig.call("POST", "/v1/missions", kDispatcher, mission_body("amb-1"));
  ASSERT_EQ(created.status, 201) << created.body;
  const json m = body(created);
  EXPECT_EQ(m["state"], "active");
  EXPECT_EQ(m["route"]["type"], "Feature");
  EXPECT_GT(m["eta_s"].get<double>(), 0.0);
  EXPECT_TRUE(m["preemption"].is_array());
  const std::string id = std::to_string(m["id"].get<std::uint64_t>());
  EXPECT_EQ(rig.call("GET", "/v1/missions/" + id, kViewer).status, 200);
  const json active = body(rig.call("GET", "/v1/missions?state=active", kViewer));
  EXPECT_EQ(active["missions"].size(), 1u);
  EXPECT_EQ(rig.call("POST", "/v1/missions/" + id + "/cancel", kDispatcher).status, 200);
  EXPECT_EQ(body(rig.call("GET", "/v1/missions/" + id, kViewer))["state"], "cancelled");
  EXPECT_EQ(rig.call("POST", "/v1/missions/" + id + "/cancel", kDispatcher).status, 409);
  EXPECT_EQ(m["profile"], "ambulance");
  EXPECT_EQ(m["vmax_kmh"], 120.0);
  // A fire engine: its own profile, and its top speed unless the request gives one.
  std::string fire = mission_body("engine-1");
  fire.insert(fire.size() - 1, ",\"profile\":\"fire_engine\"");
  const auto engine = rig.call("POST", "/v1/missions", kDispatcher, fire);
  ASSERT_EQ(engine.status, 201) << engine.body;
  EXPECT_EQ(body(engine)["profile"], "fire_engine");
  EXPECT_EQ(body(engine)["vmax_kmh"], 90.0);
}

TEST(Router, AuthenticationAndRoles) {
  Rig rig;
  EXPECT_EQ(rig.call("GET", "/v1/health").status, 200);  // open
  EXPECT_EQ(rig.call("GET", "/v1/missions").status, 401);
  EXPECT_EQ(rig.call("GET", "/v1/missions", "Bearer not-a-token").status, 401);
  EXPECT_EQ(rig.call("GET", "/v1/missions", "Basic abc").status, 401);
  EXPECT_EQ(rig.call("POST", "/v1/missions", kViewer, mission_body("x")).status, 403);
  EXPECT_EQ(rig.call("POST", "/v1/congestion", kDispatcher, R"({"updates":[{"edge":0,"factor":2}]})").status, 403);
  EXPECT_EQ(rig.call("POST", "/v1/congestion", kSensor, R"({"updates":[{"edge":0,"factor":2}]})").status, 200);
  const std::string pos = R"({"lat":)" + std::to_string(grid().projection().to_lat_lon(grid().position(NodeId{0})).lat_deg) +
                          R"(,"lon":)" + std::to_string(grid().projection().to_lat_lon(grid().position(NodeId{0})).lon_deg) +
                          R"(,"timestamp":1})";
  EXPECT_EQ(rig.call("POST", "/v1/vehicles/amb-1/position", kAmb1, pos).status, 200);
  const auto other = rig.call("POST", "/v1/vehicles/amb-2/position", kAmb1, pos);
  EXPECT_EQ(other.status, 403);  // a vehicle reports for itself only
  EXPECT_EQ(body(other)["error"]["code"], "forbidden");
  // The token never appears in an error message.
  EXPECT_EQ(rig.call("GET", "/v1/missions", kAmb1).body.find("vehicle-amb1-token"), std::string::npos);
}

// A vehicle id that needs escaping in a URL ("unit 7" as "unit%207") names the same vehicle as in
// the mission's JSON; a malformed escape is a 400.
TEST(Router, PathParametersArePercentDecoded) {
  Rig rig;
  const auto created = rig.call("POST", "/v1/missions", kDispatcher, mission_body("unit 7"));
  ASSERT_EQ(created.status, 201) << created.body;
  const auto id = body(created)["id"].get<std::uint64_t>();
  const auto at = grid().projection().to_lat_lon(grid().position(NodeId{0}));
  const std::string pos = R"({"lat":)" + std::to_string(at.lat_deg) + R"(,"lon":)" + std::to_string(at.lon_deg) +
                          R"(,"timestamp":1})";
  const auto reported = rig.call("POST", "/v1/vehicles/unit%207/position", kDispatcher, pos);
  ASSERT_EQ(reported.status, 200) << reported.body;
  EXPECT_EQ(body(reported)["mission"], id);
  const json vehicles = body(rig.call("GET", "/v1/vehicles", kViewer));
  ASSERT_EQ(vehicles["vehicles"].size(), 1u) << vehicles.dump();
  EXPECT_EQ(vehicles["vehicles"][0]["vehicle_id"], "unit 7");
  for (const char* bad : {"/v1/vehicles/unit%2/position", "/v1/vehicles/unit%zz7/position", "/v1/vehicles/%/position"}) {
    const auto r = rig.call("POST", bad, kDispatcher, pos);
    EXPECT_EQ(r.status, 400) << bad;
    EXPECT_EQ(body(r)["error"]["code"], "bad_request") << bad;
  }
  EXPECT_EQ(rig.call("GET", "/v1/missions?state=%61ctive", kViewer).status, 200);  // "active"
}

// Ids are printable ASCII, 1 to 64 characters: a NUL, a CR/LF (a header smuggled into a log or a
// reply), a byte outside ASCII or an overlong id is a 400 that says which character; nothing is
// stored.
TEST(Router, IdsOutsidePrintableAsciiAreRefusedNamingTheCharacter) {
  Rig rig;
  const auto at = grid().projection().to_lat_lon(grid().position(NodeId{0}));
  const std::string pos = R"({"lat":)" + std::to_string(at.lat_deg) + R"(,"lon":)" + std::to_string(at.lon_deg) + R"(,"timestamp":1})";
  const std::vector<std::pair<std::string, std::string>> bad{{"a%00b", "character 2 is 0x00"},
                                                             {"a%0d%0aX-Injected:%201", "character 2 is 0x0d"},
                                                             {"caf%C3%A9", "character 4 is 0xc3"},
                                                             {std::string(65, 'x'), "65 characters long"},
                                                             {"%20lead", "begins or ends with a space"}};
  for (const auto& [id, says] : bad) {
    const auto r = rig.call("POST", "/v1/vehicles/" + id + "/position", kDispatcher, pos);
    EXPECT_EQ(r.status, 400) << id;
    EXPECT_NE(body(r)["error"]["message"].get<std::string>().find(says), std::string::npos) << id << ": " << r.body;
  }
  const auto created = rig.call("POST", "/v1/missions", kDispatcher, mission_body("amb\\u0000x"));
  EXPECT_EQ(created.status, 400) << created.body;
  EXPECT_NE(created.body.find("0x00"), std::string::npos) << created.body;
  EXPECT_TRUE(body(rig.call("GET", "/v1/vehicles", kViewer))["vehicles"].empty());
}

// A vehicle token without a vehicle id could report for any vehicle: refused when the config is
// read, not at the first report.
TEST(Router, AVehicleTokenMustNameItsVehicle) {
  TokenAuth auth;
  EXPECT_THROW(auth.add_from_config(json::parse(R"({"tokens":[{"token":"vehicle-no-id-0123456789","name":"amb-9","roles":["vehicle"]}]})")),
               AuthConfigError);
  EXPECT_THROW(auth.add_from_config(json::parse(
                   R"({"tokens":[{"token":"vehicle-no-id-0123456789","name":"amb-9","roles":["vehicle","viewer"],"vehicle_id":""}]})")),
               AuthConfigError);
  EXPECT_NO_THROW(auth.add_from_config(json::parse(
      R"({"tokens":[{"token":"control-room-0123456789","name":"desk","roles":["dispatcher","vehicle"]}]})")));
}

TEST(Router, BadInputsGetClearFourHundreds) {
  Rig rig;
  const std::pair<std::string, int> cases[] = {
      {"", 400},
      {"{", 400},
      {"[]", 400},
      {"{\"vehicle_id\":5}", 400},
      {"{\"vehicle_id\":\"a\"}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":\"x\",\"lon\":1}}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":NaN,\"lon\":1}}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":95,\"lon\":1}}", 422},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":1e400,\"lon\":1}}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":10,\"lon\":10},\"origin\":{\"lat\":10,\"lon\":10}}", 422},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":10,\"lon\":10},\"priority\":1.5}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":10,\"lon\":10},\"profile\":\"tank\"}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":10,\"lon\":10},\"profile\":\"/etc/passwd\"}", 400},
      {"{\"vehicle_id\":\"a\",\"destination\":{\"lat\":10,\"lon\":10},\"profile\":7}", 400},
  };
  for (const auto& [text, status] : cases) {
    const auto r = rig.call("POST", "/v1/missions", kDispatcher, text);
    EXPECT_EQ(r.status, status) << text << " -> " << r.body;
    const json err = body(r);
    EXPECT_TRUE(err["error"]["code"].is_string()) << r.body;
    EXPECT_FALSE(err["error"]["message"].get<std::string>().empty());
  }
  EXPECT_EQ(rig.call("GET", "/v1/missions/abc", kViewer).status, 400);
  EXPECT_EQ(rig.call("GET", "/v1/missions/99999", kViewer).status, 404);
  EXPECT_EQ(rig.call("GET", "/v1/missions?state=flying", kViewer).status, 400);
  EXPECT_EQ(rig.call("GET", "/v1/nothing", kViewer).status, 404);
  EXPECT_EQ(rig.call("DELETE", "/v1/missions", kDispatcher).status, 405);
  EXPECT_EQ(rig.call("POST", "/v1/congestion", kSensor, R"({"updates":[{"edge":-1,"factor":2}]})").status, 400);
  EXPECT_EQ(rig.call("POST", "/v1/congestion", kSensor, R"({"updates":[{"edge":999999,"factor":2}]})").status, 422);
  EXPECT_EQ(rig.call("POST", "/v1/congestion", kSensor, R"({"updates":"all"})").status, 400);
  EXPECT_EQ(rig.call("POST", "/v1/signals/0/counts", kSensor, R"({"approach":"Q","arrivals":1,"departures":0})").status, 400);
  EXPECT_EQ(rig.call("GET", "/v1/signals/123456789", kViewer).status, 404);
  EXPECT_EQ(rig.call("POST", "/v1/vehicles/amb-1/position", kDispatcher, R"({"lat":0,"lon":0,"timestamp":1})").status, 422);
}

TEST(Router, SignalsMapHealthAndMetrics) {
  Rig rig;
  const json signals = body(rig.call("GET", "/v1/signals", kViewer));
  ASSERT_FALSE(signals["signals"].empty());
  const auto first = signals["signals"][0]["id"].get<std::uint32_t>();
  EXPECT_EQ(rig.call("GET", "/v1/signals/" + std::to_string(first), kViewer).status, 200);
  const std::string counts = "/v1/signals/" + std::to_string(first) + "/counts";
  EXPECT_EQ(rig.call("POST", counts, kSensor, R"({"approach":"N","arrivals":4,"departures":1})").status, 200);
  // A detector report may carry occupancy, a speed ratio and the standing queue instead.
  EXPECT_EQ(rig.call("POST", counts, kSensor, R"({"approach":"N","queue_m":42.5,"occupancy":0.4})").status, 200);
  EXPECT_EQ(rig.call("POST", counts, kSensor, R"({"approach":"E","speed_ratio":0.3})").status, 200);
  for (const char* bad : {R"({"approach":"N"})", R"({"approach":"N","arrivals":4})", R"({"approach":"N","queue_m":-1})",
                          R"({"approach":"N","occupancy":1.2})", R"({"approach":"N","queue_m":"far"})",
                          R"({"approach":"N","queue_m":1e300})"}) {
    EXPECT_EQ(rig.call("POST", counts, kSensor, bad).status, 400) << bad;
  }
  const json map = body(rig.call("GET", "/v1/map", kViewer));
  EXPECT_EQ(map["type"], "FeatureCollection");
  EXPECT_GT(map["features"].size(), grid().edge_count() / 3);
  const auto metrics = rig.call("GET", "/metrics");
  EXPECT_EQ(metrics.content_type.rfind("text/plain", 0), 0u);
  EXPECT_NE(metrics.body.find("corridor_http_requests_total{route=\"GET /v1/map\",status=\"200\"} 1"), std::string::npos)
      << metrics.body;
}

// The transport runs these off its I/O threads: they wait for storage or plan a whole route.
TEST(Router, OnlyRoutesThatWaitForStorageOrPlanningBlock) {
  Rig rig;
  auto blocks = [&](const std::string& method, const std::string& target) { return rig.router.blocks({method, target, "", ""}); };
  EXPECT_TRUE(blocks("POST", "/v1/missions"));
  EXPECT_TRUE(blocks("POST", "/v1/missions?dry=1"));
  EXPECT_TRUE(blocks("POST", "/v1/missions/7/cancel"));
  EXPECT_TRUE(blocks("POST", "/v1/congestion"));
  EXPECT_FALSE(blocks("POST", "/v1/vehicles/amb-1/position"));  // answered once durable, without waiting
  EXPECT_FALSE(blocks("GET", "/v1/missions"));
  EXPECT_FALSE(blocks("GET", "/v1/missions/7"));
  EXPECT_FALSE(blocks("GET", "/v1/congestion"));  // no such route: answered inline with 405
  EXPECT_FALSE(blocks("POST", "/no/such/path"));
  EXPECT_FALSE(blocks("POST", ""));
}

// Every mission repair a congestion report triggers is one sample of the per-replan histogram, so
// without position reports its count matches what the answers said was replanned.
TEST(Router, CongestionRepairsAreTimedPerMissionInTheMetrics) {
  Rig rig;
  const json m = body(rig.call("POST", "/v1/missions", kDispatcher, mission_body("amb-1")));
  ASSERT_EQ(rig.call("POST", "/v1/missions", kDispatcher, mission_body("amb-2")).status, 201);
  std::size_t replanned = 0;
  for (const auto& edge : m["route"]["properties"]["edges"]) {
    const json answer = body(rig.call("POST", "/v1/congestion", kSensor,
                                      R"({"updates":[{"edge":)" + edge.dump() + R"(,"factor":3}]})"));
    replanned += answer["missions_replanned"].get<std::size_t>();
    EXPECT_EQ(answer["missions_repaired_by_reports"], 0);  // no position report ran meanwhile
  }
  ASSERT_GE(replanned, 2u);
  const std::string metrics = rig.call("GET", "/metrics").body;
  EXPECT_NE(metrics.find("corridor_congestion_mission_replan_seconds_count{} " + std::to_string(replanned) + "\n"),
            std::string::npos)
      << metrics;
  EXPECT_NE(metrics.find("corridor_congestion_mission_replan_cpu_seconds_count{} " + std::to_string(replanned) + "\n"),
            std::string::npos)
      << metrics;
  EXPECT_NE(metrics.find("corridor_replans_total " + std::to_string(replanned) + "\n"), std::string::npos) << metrics;
  // No position report ran between them, so none repaired a mission first (the bench reads this).
  EXPECT_NE(metrics.find("\ncorridor_congestion_missions_repaired_by_reports_total 0\n"), std::string::npos) << metrics;
}

// Per-token token bucket: a burst is allowed, then 429 until time refills it; other tokens are
// not affected.
TEST(Router, APositionIsAnsweredOnlyOnceStoredAndA503WhenItCannotBe) {
  TempDb db;
  Store store(db.path());
  DispatchService service(grid(), {}, &store, 0.0);
  Router router(service, Rig::make_auth(), {}, [] { return 100.0; });
  const std::string pos = R"({"lat":)" + std::to_string(grid().projection().to_lat_lon(grid().position(NodeId{0})).lat_deg) +
                          R"(,"lon":)" + std::to_string(grid().projection().to_lat_lon(grid().position(NodeId{0})).lon_deg) +
                          R"(,"timestamp":1,"source":"gps"})";
  auto post = [&] {
    std::promise<std::pair<int, std::size_t>> answered;
    router.handle_async({"POST", "/v1/vehicles/amb-1/position", kAmb1, pos}, [&](HttpResponse r) {
      // What the client is told must already be in the database.
      answered.set_value({r.status, r.status == 200 ? store.count("positions") : 0});
    });
    return answered.get_future().get();
  };
  EXPECT_EQ(post(), std::make_pair(200, std::size_t{1}));
  EXPECT_EQ(post(), std::make_pair(200, std::size_t{2}));

  // The positions table disappears under the server: the write fails, so the answer is a 503.
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(db.path().c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, "DROP TABLE positions", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);
  EXPECT_EQ(post().first, 503);
  const HttpResponse sync = router.handle({"POST", "/v1/vehicles/amb-1/position", kAmb1, pos});
  EXPECT_EQ(sync.status, 503);
  EXPECT_NE(sync.body.find("storage_unavailable"), std::string::npos);
}

TEST(Router, RateLimitPerToken) {
  DispatchService service(grid(), {}, nullptr, 0.0);
  double now = 0.0;
  RouterConfig config;
  config.burst_per_token = 5;
  config.rate_per_token_per_s = 2;
  Router router(service, Rig::make_auth(), config, [&] { return now; });
  for (int i = 0; i < 5; ++i) EXPECT_EQ(router.handle({"GET", "/v1/signals", kViewer, ""}).status, 200);
  const auto limited = router.handle({"GET", "/v1/signals", kViewer, ""});
  EXPECT_EQ(limited.status, 429);
  EXPECT_EQ(body(limited)["error"]["code"], "rate_limited");
  EXPECT_EQ(router.handle({"GET", "/v1/signals", kDispatcher, ""}).status, 200);  // its own bucket
  now += 1.0;  // two more requests' worth
  EXPECT_EQ(router.handle({"GET", "/v1/signals", kViewer, ""}).status, 200);
  EXPECT_EQ(router.handle({"GET", "/v1/signals", kViewer, ""}).status, 200);
  EXPECT_EQ(router.handle({"GET", "/v1/signals", kViewer, ""}).status, 429);
  EXPECT_EQ(router.handle({"GET", "/v1/health", "", ""}).status, 200);  // open endpoints are not limited
}

// The OpenAPI document lists exactly the routes the router serves, and only those.
TEST(Router, OpenApiMatchesTheImplementation) {
  Rig rig;
  const json api = body(rig.call("GET", "/v1/openapi.json"));
  EXPECT_EQ(api["openapi"], "3.0.3");
  std::size_t operations = 0;
  for (const auto& [path, methods] : api["paths"].items()) {
    for (const auto& [method, op] : methods.items()) {
      ++operations;
      if (path == "/v1/stream") continue;  // served by the transport's upgrade
      std::string concrete = path;
      for (const std::string p : {"{id}"}) {
        const auto at = concrete.find(p);
        if (at != std::string::npos) concrete.replace(at, p.size(), "1");
      }
      std::string upper = method;
      for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      const auto r = rig.call(upper, concrete, kDispatcher, "{}");
      EXPECT_NE(r.status, 405) << upper << " " << path;
      EXPECT_FALSE(r.status == 404 && body(r)["error"]["message"].get<std::string>().rfind("no such endpoint", 0) == 0)
          << upper << " " << path;
      EXPECT_TRUE(op.contains("responses")) << path;
    }
  }
  EXPECT_EQ(operations, 20u);
}

// Random and mutated requests: the router answers every one with a status below 500.
TEST(Router, FuzzedRequestsNeverCrashOrFailInternally) {
  Rig rig;
  std::mt19937_64 rng(99);
  const std::vector<std::string> targets{"/v1/missions", "/v1/missions/1", "/v1/missions/1/cancel", "/v1/congestion",
                                         "/v1/vehicles/amb-1/position", "/v1/signals/0/counts", "/v1/signals", "/v1/map",
                                         "/v1/missions?state=active", "/v1//missions", "/", "/v1/missions/%00"};
  const std::vector<std::string> seeds{mission_body("amb-9"), R"({"updates":[{"edge":3,"speed_kmh":10,"expires_in_s":5}]})",
                                       R"({"lat":47.14,"lon":9.52,"timestamp":3,"heading_deg":90,"source":"vo"})",
                                       R"({"approach":"E","arrivals":2,"departures":1})"};
  const std::vector<std::string> auths{kDispatcher, kSensor, kViewer, kAmb1, "", "Bearer x"};
  for (int i = 0; i < 20000; ++i) {
    std::string text = seeds[rng() % seeds.size()];
    const int edits = static_cast<int>(rng() % 6);
    for (int k = 0; k < edits && !text.empty(); ++k) {
      const std::size_t at = rng() % text.size();
      switch (rng() % 4) {
        case 0: text[at] = static_cast<char>(rng() % 256); break;
        case 1: text.erase(at, 1 + rng() % 5); break;
        case 2: text.insert(at, std::string(1 + rng() % 3, "{}[]\",:0123456789-.eE"[rng() % 21])); break;
        default: text.insert(at, "1e308"); break;
      }
    }
    rig.now += 0.01;
    const auto r = rig.call(rng() % 5 == 0 ? "GET" : "POST", targets[rng() % targets.size()], auths[rng() % auths.size()], text);
    ASSERT_LT(r.status, 500) << r.body << " for " << text;
    EXPECT_FALSE(json::parse(r.body, nullptr, false).is_discarded()) << r.body;
  }
}

}  // namespace
}  // namespace corridor::server
