#include "maps/graph_cache.hpp"

#include <array>
#include <cstring>
#include <fstream>
#include <span>
#include <type_traits>

#include "maps/errors.hpp"

namespace corridor::maps {
namespace {

constexpr std::array<char, 8> kMagic{'C', 'O', 'R', 'R', 'G', 'R', 'P', 'H'};

// FNV-1a over the payload: catches truncation and bit rot, not tampering.
class Checksum {
 public:
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 1099511628211ULL;
    }
  }
  [[nodiscard]] std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 14695981039346656037ULL;
};

class Writer {
 public:
  explicit Writer(std::ofstream& out) : out_(out) {}
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    raw(&v, sizeof(T));
  }
  template <class T>
  void array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    pod(static_cast<std::uint64_t>(v.size()));
    raw(v.data(), v.size() * sizeof(T));
  }
  [[nodiscard]] std::uint64_t checksum() const { return sum_.value(); }

 private:
  void raw(const void* p, std::size_t n) {
    out_.write(static_cast<const char*>(p), static_cast<std::streamsize>(n));
    sum_.add(p, n);
  }
  std::ofstream& out_;
  Checksum sum_;
};

class Reader {
 public:
  Reader(std::span<const char> bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {}
  template <class T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    std::memcpy(&v, take(sizeof(T)), sizeof(T));
    return v;
  }
  template <class T>
  void array(std::vector<T>& v) {
    const auto n = pod<std::uint64_t>();
    if (n > (bytes_.size() - pos_) / sizeof(T)) fail("array length exceeds the file");
    v.resize(n);
    const char* src = take(n * sizeof(T));
    if (n > 0) std::memcpy(v.data(), src, n * sizeof(T));  // an empty vector's data() may be null
  }
  [[nodiscard]] std::size_t position() const { return pos_; }
  [[noreturn]] void fail(const std::string& why) const {
    throw GraphCacheError("graph cache '" + name_ + "' is unusable: " + why);
  }

 private:
  const char* take(std::size_t n) {
    if (n > bytes_.size() - pos_) fail("file is truncated");
    const char* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
  }
  std::span<const char> bytes_;
  std::size_t pos_ = 0;
  std::string name_;
};

template <class Visitor>
void visit_arrays(Visitor&& v, auto& d) {
  v(d.node_x_m);
  v(d.node_y_m);
  v(d.node_osm_id);
  v(d.node_signalized);
  v(d.first_out);
  v(d.edge_tail);
  v(d.edge_head);
  v(d.edge_length_m);
  v(d.edge_speed_mps);
  v(d.edge_osm_way);
  v(d.edge_class);
  v(d.edge_twin);
  v(d.edge_name);
  v(d.edge_ref);
  v(d.strings.chars);
  v(d.strings.first);
  v(d.geometry_first);
  v(d.geometry);
  v(d.first_in);
  v(d.in_edge);
  v(d.landmarks.nodes);
  v(d.landmarks.from_ticks);
  v(d.landmarks.to_ticks);
  v(d.edge_limits);
  v(d.roundabout_edges);
  v(d.node_stop);
  v(d.restrictions.first);
  v(d.restrictions.edges);
  v(d.restrictions.only);
  v(d.restrictions.mode);
  v(d.restrictions.except);
  v(d.turns_in_edges);
  v(d.left_hand_traffic);
}

}  // namespace

CacheSource describe_source(const std::filesystem::path& source) {
  std::error_code ec;
  CacheSource s;
  s.size_bytes = std::filesystem::file_size(source, ec);
  if (ec) return {};
  const auto t = std::filesystem::last_write_time(source, ec);
  if (ec) return {};
  s.mtime_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
  return s;
}

void write_graph_cache(const std::filesystem::path& file, const RoadGraph& graph, const CacheSource& source) {
  auto tmp = file;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw GraphCacheError("cannot write graph cache '" + tmp.string() + "'");
    out.write(kMagic.data(), kMagic.size());
    const std::uint32_t version = kGraphCacheVersion;
    out.write(reinterpret_cast<const char*>(&version), sizeof version);
    Writer w(out);
    w.pod(source);
    w.pod(graph.data().origin);
    visit_arrays([&](const auto& a) { w.array(a); }, graph.data());
    const std::uint64_t sum = w.checksum();
    out.write(reinterpret_cast<const char*>(&sum), sizeof sum);
    out.flush();
    if (!out) {
      out.close();
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);
      throw GraphCacheError("failed writing graph cache '" + tmp.string() + "'");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    // A half-placed cache is no use to anyone: leave nothing behind but the error.
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw GraphCacheError("cannot move graph cache into place at '" + file.string() + "': " + ec.message());
  }
}

bool looks_like_graph_cache(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::array<char, 8> magic{};
  return in.read(magic.data(), magic.size()) && magic == kMagic;
}

RoadGraph read_graph_cache(const std::filesystem::path& file, CacheSource* source) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) throw GraphCacheError("graph cache not found: '" + file.string() + "'");
  const auto size = static_cast<std::size_t>(in.tellg());
  std::vector<char> bytes(size);
  in.seekg(0);
  if (!in.read(bytes.data(), static_cast<std::streamsize>(size))) {
    throw GraphCacheError("cannot read graph cache '" + file.string() + "'");
  }
  constexpr std::size_t kHeader = kMagic.size() + sizeof(std::uint32_t);
  if (size < kHeader + sizeof(std::uint64_t) || std::memcmp(bytes.data(), kMagic.data(), kMagic.size()) != 0) {
    throw GraphCacheError("'" + file.string() + "' is not a Corridor graph cache");
  }
  std::uint32_t version = 0;
  std::memcpy(&version, bytes.data() + kMagic.size(), sizeof version);
  if (version != kGraphCacheVersion) {
    throw GraphCacheError("graph cache '" + file.string() + "' has format version " + std::to_string(version) +
                          ", this build reads version " + std::to_string(kGraphCacheVersion) + "; re-import the map");
  }
  const std::span<const char> payload(bytes.data() + kHeader, size - kHeader - sizeof(std::uint64_t));
  std::uint64_t stored_sum = 0;
  std::memcpy(&stored_sum, bytes.data() + size - sizeof stored_sum, sizeof stored_sum);
  Checksum sum;
  sum.add(payload.data(), payload.size());
  Reader r(payload, file.string());
  if (sum.value() != stored_sum) r.fail("checksum mismatch (file corrupt or truncated)");
  const auto src = r.pod<CacheSource>();
  RoadGraphData d;
  d.origin = r.pod<LatLon>();
  visit_arrays([&](auto& a) { r.array(a); }, d);
  if (r.position() != payload.size()) r.fail("trailing bytes after the graph");
  if (source != nullptr) *source = src;
  try {
    return RoadGraph(std::move(d));
  } catch (const MapError& e) {
    r.fail(e.what());
  }
}

}  // namespace corridor::maps
