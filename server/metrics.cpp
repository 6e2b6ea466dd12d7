#include "server/metrics.hpp"

#include <sstream>

namespace corridor::server {

const std::vector<double>& Metrics::bounds() {
  // 2 ms: the per-mission repair goal (docs/routing.md) needs its own bound.
  static const std::vector<double> b{0.0001, 0.0005, 0.001, 0.002, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.5, 1.0};
  return b;
}

void Metrics::add(Histogram& h, double seconds) {
  if (h.buckets.empty()) h.buckets.assign(bounds().size(), 0.0);
  for (std::size_t i = 0; i < bounds().size(); ++i) {
    if (seconds <= bounds()[i]) h.buckets[i] += 1;
  }
  h.sum += seconds;
  h.count += 1;
}

void Metrics::observe_request(const std::string& route, int status, double seconds) {
  std::lock_guard lock(mutex_);
  requests_[{route, status}] += 1;
  add(request_latency_[route], seconds);
}

void Metrics::count(const std::string& name, double by) {
  std::lock_guard lock(mutex_);
  counters_[name] += by;
}

void Metrics::observe(const std::string& name, double seconds) {
  std::lock_guard lock(mutex_);
  add(histograms_[name], seconds);
}

void Metrics::set_gauge(const std::string& name, double value) {
  std::lock_guard lock(mutex_);
  gauges_[name] = value;
}

std::string Metrics::render() const {
  std::lock_guard lock(mutex_);
  std::ostringstream out;
  auto histogram = [&](const std::string& name, const std::string& labels, const Histogram& h) {
    const std::string sep = labels.empty() ? "" : ",";
    for (std::size_t i = 0; i < bounds().size(); ++i) {
      out << name << "_bucket{" << labels << sep << "le=\"" << bounds()[i] << "\"} " << h.buckets[i] << '\n';
    }
    out << name << "_bucket{" << labels << sep << "le=\"+Inf\"} " << h.count << '\n';
    out << name << "_sum{" << labels << "} " << h.sum << '\n';
    out << name << "_count{" << labels << "} " << h.count << '\n';
  };
  out << "# HELP corridor_http_requests_total HTTP requests by route and status.\n";
  out << "# TYPE corridor_http_requests_total counter\n";
  for (const auto& [key, n] : requests_) {
    out << "corridor_http_requests_total{route=\"" << key.first << "\",status=\"" << key.second << "\"} " << n << '\n';
  }
  out << "# HELP corridor_http_request_duration_seconds Request handling time by route.\n";
  out << "# TYPE corridor_http_request_duration_seconds histogram\n";
  for (const auto& [route, h] : request_latency_) {
    histogram("corridor_http_request_duration_seconds", "route=\"" + route + "\"", h);
  }
  for (const auto& [name, n] : counters_) {
    out << "# TYPE corridor_" << name << " counter\ncorridor_" << name << ' ' << n << '\n';
  }
  for (const auto& [name, h] : histograms_) {
    out << "# TYPE corridor_" << name << " histogram\n";
    histogram("corridor_" + name, "", h);
  }
  for (const auto& [name, v] : gauges_) out << "# TYPE corridor_" << name << " gauge\ncorridor_" << name << ' ' << v << '\n';
  return out.str();
}

}  // namespace corridor::server
