// Net-SNMP's own log messages (warnings and worse) through spdlog, as key=value lines like every
// other event, instead of on stderr. Both SNMP roles (agent and manager) call it before init_snmp.
#pragma once

namespace corridor::ntcip {

void route_snmp_logs_to_spdlog();

}  // namespace corridor::ntcip
