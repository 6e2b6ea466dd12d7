// Writes small OSM XML files for importer tests: nodes on a local grid, ways with tags.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "tests/temp_dir.hpp"

namespace corridor::maps::testing {

struct FixtureNode {
  long long id;
  double lat;
  double lon;
  std::map<std::string, std::string> tags;
};

struct FixtureWay {
  long long id;
  std::vector<long long> nodes;
  std::map<std::string, std::string> tags;
};

// A relation member: type 'n' (node) or 'w' (way), its id and role.
struct FixtureMember {
  char type;
  long long ref;
  std::string role;
};

struct FixtureRelation {
  long long id;
  std::vector<FixtureMember> members;
  std::map<std::string, std::string> tags;
};

inline std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"') out += "&quot;";
    else if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else out += c;
  }
  return out;
}

inline void write_osm(const std::filesystem::path& file, const std::vector<FixtureNode>& nodes,
                      const std::vector<FixtureWay>& ways, const std::vector<FixtureRelation>& relations = {}) {
  std::ofstream out(file);
  out << "<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\" generator=\"corridor-tests\">\n";
  out.precision(10);
  for (const auto& n : nodes) {
    out << "  <node id=\"" << n.id << "\" version=\"1\" lat=\"" << n.lat << "\" lon=\"" << n.lon << "\"";
    if (n.tags.empty()) {
      out << "/>\n";
      continue;
    }
    out << ">\n";
    for (const auto& [k, v] : n.tags) out << "    <tag k=\"" << xml_escape(k) << "\" v=\"" << xml_escape(v) << "\"/>\n";
    out << "  </node>\n";
  }
  for (const auto& w : ways) {
    out << "  <way id=\"" << w.id << "\" version=\"1\">\n";
    for (long long ref : w.nodes) out << "    <nd ref=\"" << ref << "\"/>\n";
    for (const auto& [k, v] : w.tags) out << "    <tag k=\"" << xml_escape(k) << "\" v=\"" << xml_escape(v) << "\"/>\n";
    out << "  </way>\n";
  }
  for (const auto& r : relations) {
    out << "  <relation id=\"" << r.id << "\" version=\"1\">\n";
    for (const auto& m : r.members) {
      out << "    <member type=\"" << (m.type == 'n' ? "node" : "way") << "\" ref=\"" << m.ref << "\" role=\""
          << xml_escape(m.role) << "\"/>\n";
    }
    for (const auto& [k, v] : r.tags) out << "    <tag k=\"" << xml_escape(k) << "\" v=\"" << xml_escape(v) << "\"/>\n";
    out << "  </relation>\n";
  }
  out << "</osm>\n";
}

using corridor::testing::TempDir;

// A node `x_m` east and `y_m` north of (47.0, 9.5).
inline FixtureNode at(long long id, double x_m, double y_m, std::map<std::string, std::string> tags = {}) {
  constexpr double kMetersPerDegLat = 111195.0;
  const double lon_scale = kMetersPerDegLat * std::cos(47.0 * M_PI / 180.0);
  return {id, 47.0 + y_m / kMetersPerDegLat, 9.5 + x_m / lon_scale, std::move(tags)};
}

inline std::filesystem::path shared_osm(const std::string& name) {
  return std::filesystem::path(CORRIDOR_SHARED_DATA_DIR) / "osm" / name;
}

}  // namespace corridor::maps::testing
