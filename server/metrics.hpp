// Prometheus text-format metrics: request counts and latencies per route and status, and the
// service's own counters (replans, preemptions). Thread-safe.
#pragma once

#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace corridor::server {

class Metrics {
 public:
  void observe_request(const std::string& route, int status, double seconds);
  void count(const std::string& name, double by = 1.0);
  void observe(const std::string& name, double seconds);  // a latency histogram
  void set_gauge(const std::string& name, double value);
  [[nodiscard]] std::string render() const;

 private:
  struct Histogram {
    std::vector<double> buckets;  // cumulative counts per bound
    double sum = 0;
    double count = 0;
  };
  static const std::vector<double>& bounds();
  static void add(Histogram& h, double seconds);

  mutable std::mutex mutex_;
  std::map<std::pair<std::string, int>, double> requests_;
  std::map<std::string, Histogram> request_latency_;
  std::map<std::string, double> counters_;
  std::map<std::string, Histogram> histograms_;
  std::map<std::string, double> gauges_;
};

}  // namespace corridor::server
