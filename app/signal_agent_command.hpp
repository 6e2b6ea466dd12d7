// `corridor signal-agent`: virtual NTCIP 1202 controllers for every signal of a map, each an SNMP
// agent on its own UDP port, running the map's normal programs and real preempt sequences.
#pragma once

#include <CLI/CLI.hpp>

namespace corridor::app {

void register_signal_agent_command(CLI::App& app);

}  // namespace corridor::app
