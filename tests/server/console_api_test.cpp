// What the dispatch console reads: who the token is, stream tickets, vehicles, route history with
// reasons, event payloads and their order, signal states, and the console's own files.
#include <gtest/gtest.h>

#include "maps/synthetic_grid.hpp"
#include "tests/server/api_fixture.hpp"
#include "server/json_codec.hpp"
#include "server/router.hpp"

namespace corridor::server {
namespace {

using nlohmann::json;

const maps::RoadGraph& grid() { return testing::api_grid(); }

using testing::kDispatcher;
using testing::kSensor;
using testing::kViewer;

const std::string kIndex = "<!doctype html><script type=module src=/assets/app-1.js></script>";
const std::string kScript = "console.log(1)";

std::shared_ptr<const StaticSite> site() {
  return std::make_shared<StaticSite>(std::vector<StaticAsset>{{"/index.html", kIndex}, {"/assets/app-1.js", kScript},
                                                               {"/favicon.svg", "<svg/>"}});
}

struct Rig {
  DispatchService service{grid(), {}, nullptr, 0.0};
  double now = 100.0;
  std::vector<DispatchEvent> events;
  std::size_t subscription;
  Router router;

  Rig() : router(service, make_auth(), {}, [this] { return now; }, site()) {
    subscription = service.subscribe([this](const DispatchEvent& e) { events.push_back(e); });
  }
  ~Rig() { service.unsubscribe(subscription); }

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

json body(const HttpResponse& r) { return json::parse(r.body); }

std::string header(const HttpResponse& r, const std::string& name) {
  for (const auto& [k, v] : r.headers) {
    if (k == name) return v;
  }
  return {};
}

TEST(ConsoleApi, MeNamesTheTokensRoles) {
  Rig rig;
  const json me = body(rig.call("GET", "/v1/me", kViewer));
  EXPECT_EQ(me["name"], "wall");
  EXPECT_EQ(me["roles"], json::array({"viewer"}));
  EXPECT_TRUE(me["vehicle_id"].is_null());
  EXPECT_EQ(rig.call("GET", "/v1/me").status, 401);
}

TEST(ConsoleApi, StreamTicketIsSingleUseAndShortLived) {
  Rig rig;
  EXPECT_EQ(rig.call("POST", "/v1/stream/ticket", kSensor).status, 403);  // a sensor may not read the stream
  const json t = body(rig.call("POST", "/v1/stream/ticket", kViewer));
  const std::string ticket = t["ticket"];
  EXPECT_EQ(ticket.size(), 32u);
  EXPECT_GT(t["expires_in_s"].get<double>(), 0.0);
  const auto who = rig.router.authorize_stream("", "/v1/stream?ticket=" + ticket + "&mission=3");
  ASSERT_TRUE(who.has_value());
  EXPECT_EQ(who->name, "wall");
  EXPECT_FALSE(rig.router.authorize_stream("", "/v1/stream?ticket=" + ticket).has_value());  // used up
  const std::string late = body(rig.call("POST", "/v1/stream/ticket", kViewer))["ticket"];
  rig.now += 31.0;
  EXPECT_FALSE(rig.router.authorize_stream("", "/v1/stream?ticket=" + late).has_value());  // expired
  EXPECT_FALSE(rig.router.authorize_stream("", "/v1/stream?ticket=00000000000000000000000000000000").has_value());
  // A bad ticket is not rescued by a good header, and the header still works alone.
  EXPECT_FALSE(rig.router.authorize_stream(kViewer, "/v1/stream?ticket=nope").has_value());
  EXPECT_TRUE(rig.router.authorize_stream(kViewer, "/v1/stream").has_value());
  // A malformed query carries no ticket, but the header still counts.
  EXPECT_TRUE(rig.router.authorize_stream(kViewer, "/v1/stream?mission=%zz").has_value());
  EXPECT_FALSE(rig.router.authorize_stream("", "/v1/stream?ticket=%zz").has_value());
}

TEST(StreamTickets, ManyOutstandingTicketsStayBounded) {
  StreamTickets tickets({30.0, 100});
  const Principal who{"wall", static_cast<std::uint8_t>(Role::viewer), std::nullopt};
  std::vector<std::string> issued;
  for (int i = 0; i < 1000; ++i) issued.push_back(tickets.issue(who, i * 0.001));
  // The newest are still good; the oldest were dropped to keep the table bounded.
  EXPECT_TRUE(tickets.redeem(issued.back(), 1.0).has_value());
  EXPECT_FALSE(tickets.redeem(issued.front(), 1.0).has_value());
}

TEST(ConsoleApi, VehiclesRouteHistoryAndEventPayloads) {
  Rig rig;
  const std::string origin = ll(NodeId{0});
  const std::string destination = ll(NodeId{static_cast<std::uint32_t>(grid().node_count() - 1)});
  const auto p = grid().projection().to_lat_lon(grid().position(NodeId{0}));
  ASSERT_EQ(rig.call("POST", "/v1/vehicles/amb-1/position", kDispatcher,
                     "{\"lat\":" + std::to_string(p.lat_deg) + ",\"lon\":" + std::to_string(p.lon_deg) +
                         ",\"heading_deg\":90,\"speed_mps\":3,\"timestamp\":5}")
                .status,
            200);
  const auto created = rig.call("POST", "/v1/missions", kDispatcher,
                                "{\"vehicle_id\":\"amb-1\",\"origin\":" + origin + ",\"destination\":" + destination + "}");
  ASSERT_EQ(created.status, 201) << created.body;
  const json m = body(created);
  const std::uint64_t id = m["id"];
  EXPECT_NEAR(m["eta_at_s"].get<double>(), rig.now + m["eta_s"].get<double>(), 1e-6);
  const json& props = m["route"]["properties"];
  EXPECT_EQ(props["congestion_factors"].size(), props["edges"].size());
  EXPECT_EQ(props["edge_coordinate_index"].size(), props["edges"].size());
  EXPECT_EQ(props["steps"].front()["maneuver"]["type"], "depart");
  EXPECT_EQ(props["steps"].back()["maneuver"]["type"], "arrive");

  const json vehicles = body(rig.call("GET", "/v1/vehicles", kViewer))["vehicles"];
  ASSERT_EQ(vehicles.size(), 1u);
  EXPECT_EQ(vehicles[0]["vehicle_id"], "amb-1");
  EXPECT_EQ(vehicles[0]["mission"], id);
  EXPECT_EQ(vehicles[0]["heading_deg"], 90.0);

  // Congestion on the route's first edge after the start changes the route, for a stated reason.
  const std::uint32_t blocked = props["edges"][1];
  rig.now += 1.0;
  const auto jam = rig.call("POST", "/v1/congestion", kSensor,
                            "{\"updates\":[{\"edge\":" + std::to_string(blocked) + ",\"factor\":500}]}");
  ASSERT_EQ(jam.status, 200) << jam.body;
  const json after = body(rig.call("GET", "/v1/missions/" + std::to_string(id), kViewer));
  const json revisions = body(rig.call("GET", "/v1/missions/" + std::to_string(id) + "/routes", kViewer))["revisions"];
  ASSERT_EQ(revisions.size(), after["route_revision"].get<std::size_t>());
  ASSERT_GE(revisions.size(), 2u);
  EXPECT_EQ(revisions[0]["reason"], "dispatch");
  EXPECT_EQ(revisions[1]["reason"], "congestion");
  EXPECT_EQ(revisions[1]["geometry"]["type"], "LineString");
  EXPECT_EQ(rig.call("GET", "/v1/missions/999/routes", kViewer).status, 404);

  // Events are numbered in order and carry what a console draws without asking again.
  ASSERT_FALSE(rig.events.empty());
  for (std::size_t i = 1; i < rig.events.size(); ++i) EXPECT_GT(rig.events[i].seq, rig.events[i - 1].seq);
  bool saw_created = false, saw_change = false, saw_applied = false;
  for (const auto& e : rig.events) {
    const json j = event_to_json(e);
    if (e.kind == "mission_created") {
      saw_created = true;
      EXPECT_EQ(j["vehicle_id"], "amb-1");
      EXPECT_EQ(j["revision"], 1);
    }
    if (e.kind == "route_changed") {
      saw_change = true;
      EXPECT_EQ(j["reason"], "congestion");
      EXPECT_EQ(j["revision"], 2);
    }
    if (e.kind == "congestion_applied") {
      saw_applied = true;
      EXPECT_EQ(j["edges_changed"], 1);
    }
    if (e.kind.rfind("preemption_", 0) == 0) {
      EXPECT_TRUE(j["signal"].is_number());
    }
  }
  EXPECT_TRUE(saw_created && saw_change && saw_applied);

  // A position event carries the fix.
  rig.events.clear();
  const auto q = grid().projection().to_lat_lon(grid().point_along(EdgeId{after["route"]["properties"]["edges"][0].get<std::uint32_t>()}, 5.0));
  ASSERT_EQ(rig.call("POST", "/v1/vehicles/amb-1/position", kDispatcher,
                     "{\"lat\":" + std::to_string(q.lat_deg) + ",\"lon\":" + std::to_string(q.lon_deg) + ",\"timestamp\":6}")
                .status,
            200);
  auto pos = std::find_if(rig.events.begin(), rig.events.end(), [](const auto& e) { return e.kind == "position"; });
  ASSERT_NE(pos, rig.events.end());
  const json pj = event_to_json(*pos);
  EXPECT_NEAR(pj["lat"].get<double>(), q.lat_deg, 1e-6);
  EXPECT_NEAR(pj["lon"].get<double>(), q.lon_deg, 1e-6);
  EXPECT_TRUE(pj["heading_deg"].is_null());
  EXPECT_EQ(pj["vehicle_id"], "amb-1");
}

TEST(PositionApi, AnswersWhatTheTrackerMadeOfTheReport) {
  Rig rig;
  const auto p = grid().projection().to_lat_lon(grid().point_along(EdgeId{5}, 20.0));
  const std::string body = "{\"lat\":" + std::to_string(p.lat_deg) + ",\"lon\":" + std::to_string(p.lon_deg) + ",\"timestamp\":7}";
  const json first = json::parse(rig.call("POST", "/v1/vehicles/amb-9/position", kDispatcher, body).body);
  EXPECT_EQ(first["disposition"], "followed");
  EXPECT_EQ(first["followed"], true);
  EXPECT_TRUE(first["edge"] == 5 || first["edge"] == grid().twin(EdgeId{5}).v) << first.dump();
  EXPECT_GT(first["match_confidence"].get<double>(), 0.0);
  EXPECT_NEAR(first["raw"]["lat"].get<double>(), p.lat_deg, 1e-6);
  const json again = json::parse(rig.call("POST", "/v1/vehicles/amb-9/position", kDispatcher, body).body);
  EXPECT_EQ(again["disposition"], "duplicate");
  EXPECT_EQ(again["followed"], false);
  EXPECT_TRUE(again["edge"].is_null());
}

TEST(ConsoleApi, SignalStateFollowsItsPreemption) {
  Rig rig;
  const json signals = body(rig.call("GET", "/v1/signals", kViewer))["signals"];
  ASSERT_FALSE(signals.empty());
  for (const auto& s : signals) EXPECT_EQ(s["state"], "normal");
  const auto created = rig.call("POST", "/v1/missions", kDispatcher,
                                "{\"vehicle_id\":\"amb-1\",\"origin\":" + ll(NodeId{0}) + ",\"destination\":" +
                                    ll(NodeId{static_cast<std::uint32_t>(grid().node_count() - 1)}) + "}");
  ASSERT_EQ(created.status, 201);
  const json all = body(created)["preemption"];
  // The first crossing may already be held; the first one still planned is "scheduled".
  json schedule = json::array();
  for (const auto& e : all) {
    if (e["state"] == "planned") schedule.push_back(e);
  }
  ASSERT_FALSE(schedule.empty()) << all.dump();
  const std::uint32_t first = schedule[0]["signal"];
  const std::string state = body(rig.call("GET", "/v1/signals/" + std::to_string(first), kViewer))["state"];
  ASSERT_EQ(state, "scheduled") << schedule.dump();
  // Let time run to the first hold's start: the signal is held, and a signal_state event said so.
  rig.events.clear();
  const double start_s = schedule[0]["start_s"];
  for (double t = rig.now; t <= start_s + 10.0; t += 1.0) rig.service.tick(t);
  EXPECT_EQ(body(rig.call("GET", "/v1/signals/" + std::to_string(first), kViewer))["state"], "held");
  const bool announced = std::any_of(rig.events.begin(), rig.events.end(), [&](const DispatchEvent& e) {
    return e.kind == "signal_state" && e.signal && e.signal->v == first && e.state == "held";
  });
  EXPECT_TRUE(announced);
}

TEST(ConsoleSite, ServesTheAppWithTypesCachingAndPolicy) {
  Rig rig;
  // The console's page, whatever its query holds (the API's percent-decoding is not the site's).
  EXPECT_EQ(rig.call("GET", "/?x=%zz").status, 200);
  const auto index = rig.call("GET", "/");
  ASSERT_EQ(index.status, 200);
  EXPECT_EQ(index.body, kIndex);
  EXPECT_EQ(index.content_type, "text/html; charset=utf-8");
  EXPECT_EQ(header(index, "Cache-Control"), "no-cache");
  EXPECT_NE(header(index, "Content-Security-Policy").find("script-src 'self'"), std::string::npos);
  EXPECT_EQ(header(index, "Content-Security-Policy").find("unsafe-inline"), std::string::npos);
  EXPECT_EQ(header(index, "X-Content-Type-Options"), "nosniff");

  const auto script = rig.call("GET", "/assets/app-1.js?v=2");
  ASSERT_EQ(script.status, 200);
  EXPECT_EQ(script.body, kScript);
  EXPECT_EQ(script.content_type, "text/javascript; charset=utf-8");
  EXPECT_NE(header(script, "Cache-Control").find("immutable"), std::string::npos);
  EXPECT_EQ(rig.call("GET", "/favicon.svg").content_type, "image/svg+xml");

  // Client-side routes get the app; missing files and tricks get a JSON 404; the API is untouched.
  EXPECT_EQ(rig.call("GET", "/missions/3").body, kIndex);
  for (const std::string bad : {"/assets/missing.js", "/nope.css", "/assets/../index.html", "/a//b", "/.env",
                                "/x\\y", "/assets/app-1"}) {
    const auto r = rig.call("GET", bad);
    EXPECT_EQ(r.status, 404) << bad;
    EXPECT_EQ(body(r)["error"]["code"], "not_found") << bad;
  }
  EXPECT_EQ(rig.call("POST", "/", "", "{}").status, 405);
  EXPECT_EQ(rig.call("HEAD", "/").status, 200);
  EXPECT_EQ(rig.call("GET", "/v1/nothing", kViewer).status, 404);
  EXPECT_EQ(body(rig.call("GET", "/v1/nothing", kViewer))["error"]["message"].get<std::string>().rfind("no such endpoint", 0), 0u);
  EXPECT_EQ(rig.call("GET", "/v1/health").status, 200);
}

TEST(ConsoleSite, RefusesASiteWithoutAnIndex) {
  using Assets = std::vector<StaticAsset>;
  EXPECT_THROW(StaticSite(Assets{{"/app.js", "x"}}), std::invalid_argument);
  EXPECT_THROW(StaticSite(Assets{{"index.html", "x"}}), std::invalid_argument);
}

}  // namespace
}  // namespace corridor::server
