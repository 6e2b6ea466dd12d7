#include "ntcip/snmp_logging.hpp"

#include <net-snmp/net-snmp-config.h>
#include <net-snmp/net-snmp-includes.h>
#include <spdlog/spdlog.h>

#include <string>

namespace corridor::ntcip {
namespace {

int log_to_spdlog(int, int, void* serverarg, void*) {
  const auto* m = static_cast<snmp_log_message*>(serverarg);
  if (m->priority <= LOG_WARNING) {
    std::string text = m->msg != nullptr ? m->msg : "";
    while (!text.empty() && text.back() == '\n') text.pop_back();
    spdlog::warn("event=snmp_library message=\"{}\"", text);
  }
  return 0;
}

}  // namespace

void route_snmp_logs_to_spdlog() {
  snmp_register_callback(SNMP_CALLBACK_LIBRARY, SNMP_CALLBACK_LOGGING, log_to_spdlog, nullptr);
  snmp_enable_calllog();
}

}  // namespace corridor::ntcip
