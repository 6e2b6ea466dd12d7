// The controllers file (and the manifest, which is one): every field validated, every error naming
// its field; what is written reads back the same.
#include "ntcip/controllers_file.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/temp_dir.hpp"

namespace corridor::ntcip {
namespace {

using nlohmann::json;

json valid() {
  return json::parse(R"([{"osm_node_id": 21915639, "host": "10.1.2.3", "port": 161,
                           "snmp": {"version": "v2c", "read_community": "ro", "write_community": "rw"},
                           "preempts": [{"number": 1, "approach": "N"}, {"number": 2, "approach": "S", "movement": "S->E"}],
                           "phase_control": [{"approach": "E", "phases": [2, 6]}],
                           "phases": [{"number": 2, "movement": "E->W"}]},
                          {"tls_id": "cluster_1_2", "port": 16101,
                           "snmp": {"version": "v3", "user": "corridor", "auth_password": "authpass123",
                                    "priv_password": "privpass123"},
                           "preempts": [{"number": 1, "approach": "W"}], "priority_mode": "preempt"}])");
}

std::string error_of(const json& j) {
  try {
    (void)parse_controllers(j);
  } catch (const ControllersFileError& e) {
    return e.what();
  }
  return "";
}

TEST(ControllersFile, ReadsAValidFileAndWritesItBackTheSame) {
  const auto controllers = parse_controllers(valid());
  ASSERT_EQ(controllers.size(), 2u);
  EXPECT_EQ(controllers[0].id, "21915639");
  EXPECT_EQ(*controllers[0].osm_node_id, 21915639);
  EXPECT_EQ(controllers[0].host, "10.1.2.3");
  EXPECT_EQ(controllers[0].snmp.write_community, "rw");
  ASSERT_EQ(controllers[0].preempts.size(), 2u);
  EXPECT_EQ(controllers[0].preempts[1].approach, maps::Compass::south);
  EXPECT_EQ(*controllers[0].preempts[1].movement, "S->E");
  EXPECT_EQ(controllers[0].phase_control[0].phases, (std::vector<std::uint32_t>{2, 6}));
  EXPECT_EQ(controllers[1].snmp.version, SnmpVersion::v3);
  EXPECT_EQ(controllers[1].snmp.level, SecurityLevel::auth_priv);
  EXPECT_EQ(controllers[1].snmp.auth_protocol, "SHA");
  EXPECT_EQ(controllers[1].mode, PriorityMode::preempt);
  EXPECT_EQ(controllers[1].host, "127.0.0.1");
  const auto again = parse_controllers(to_json(controllers));
  EXPECT_EQ(to_json(again), to_json(controllers));
}

TEST(ControllersFile, EveryErrorNamesItsField) {
  const auto with = [](const std::string& pointer, const json& value) {
    json j = valid();
    j[json::json_pointer(pointer)] = value;
    return error_of(j);
  };
  EXPECT_NE(error_of(json::object()).find("must be a JSON array"), std::string::npos);
  EXPECT_NE(with("/0/port", 70000).find("controllers[0].port: must be within [1, 65535]"), std::string::npos);
  EXPECT_NE(with("/0/port", "161").find("controllers[0].port: must be an integer"), std::string::npos);
  EXPECT_NE(with("/0/preempts/1/approach", "Q").find("controllers[0].preempts[1].approach: must be one of N, E, S, W"),
            std::string::npos);
  EXPECT_NE(with("/0/preempts/1/number", 1).find("controllers[0].preempts[1].number: preempt 1 is wired twice"), std::string::npos);
  EXPECT_NE(with("/0/preempts/1/movement", "N->E").find("must start from its approach"), std::string::npos);
  EXPECT_NE(with("/0/snmp/version", "v4").find("controllers[0].snmp.version: must be v1, v2c or v3"), std::string::npos);
  EXPECT_NE(with("/1/snmp/auth_password", "short").find("controllers[1].snmp.auth_password: must be at least 8"), std::string::npos);
  EXPECT_NE(with("/0/snmp/user", "x").find("controllers[0].snmp.user: is for version v3"), std::string::npos);
  EXPECT_NE(with("/0/colour", "red").find("controllers[0].colour: unknown field"), std::string::npos);
  EXPECT_NE(with("/0/timeout_s", -1).find("controllers[0].timeout_s: must be within"), std::string::npos);
  EXPECT_NE(with("/0/id", std::string("a\nb")).find("controllers[0].id: character 2 is 0x0a"), std::string::npos);
  json shared = valid();
  shared[1]["host"] = "10.1.2.3";
  shared[1]["port"] = 161;
  EXPECT_NE(error_of(shared).find("controllers[1].port: 10.1.2.3:161 is another controller's"), std::string::npos);
  EXPECT_NE(with("/1/tls_id", nullptr).find("controllers[1].tls_id: must be a string"), std::string::npos);
  json both = valid();
  both[1]["osm_node_id"] = 5;
  EXPECT_NE(error_of(both).find("controllers[1]: give exactly one of osm_node_id"), std::string::npos);
  json none = valid();
  none[0].erase("preempts");
  EXPECT_NE(error_of(none).find("controllers[0].preempts: must wire at least one preempt"), std::string::npos);
  json twice = valid();
  twice[1] = twice[0];
  twice[1]["id"] = "another";
  twice[1]["port"] = 9;
  EXPECT_NE(error_of(twice).find("has two controllers"), std::string::npos);
}

// A file that is not JSON, or holds a number no double can hold (found by controllers_fuzzer), is
// refused as not JSON, naming the file, rather than escaping as JSON's own exception.
TEST(ControllersFile, AFileThatIsNotJsonOrOverflowsANumberIsRefusedNamingTheFile) {
  const corridor::testing::TempDir dir("controllers");
  const auto write = [&](const std::string& name, const std::string& text) {
    const auto p = dir.path() / name;
    std::ofstream(p) << text;
    return p;
  };
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"cut.json", R"([{"osm_node_id": 1, "port": )"},
                                   {"huge.json", R"([{"osm_node_id": 1, "port": 161, "keepalive_s": 2.0E1111111111}])"}}) {
    const auto p = write(name, text);
    try {
      (void)read_controllers_file(p);
      ADD_FAILURE() << name << " was accepted";
    } catch (const ControllersFileError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("is not JSON"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW((void)read_controllers_file(dir.path() / "missing.json"), ControllersFileError);
}

}  // namespace
}  // namespace corridor::ntcip
