#include "app/preemption_command.hpp"

#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "preemption/phase_selection.hpp"

namespace corridor::app {
namespace {

void print_table(const char* title, const preemption::DecisionTables& t,
                 const std::vector<std::vector<std::string>>& cells) {
  std::cout << title << " (row: vehicle movement, column: phase currently green)\n";
  std::cout << std::setw(8) << "";
  for (const auto& p : t.phases) std::cout << std::setw(6) << p;
  std::cout << '\n';
  for (std::size_t m = 0; m < t.movements.size(); ++m) {
    std::cout << std::setw(8) << t.movements[m];
    for (const auto& cell : cells[m]) std::cout << std::setw(6) << cell;
    std::cout << '\n';
  }
  std::cout << '\n';
}

void run_tables(bool json) {
  const preemption::DecisionTables t = preemption::nema_decision_tables();
  std::size_t agree = 0, cells = 0;
  for (std::size_t m = 0; m < t.movements.size(); ++m) {
    for (std::size_t p = 0; p < t.phases.size(); ++p) {
      agree += t.high[m][p] == t.low[m][p] ? 1 : 0;
      ++cells;
    }
  }
  if (json) {
    std::cout << nlohmann::json{{"movements", t.movements}, {"phases", t.phases}, {"high", t.high}, {"low", t.low}}.dump()
              << '\n';
    return;
  }
  print_table("High congestion: every movement of the vehicle's approach", t, t.high);
  print_table("Low congestion: keep a serving phase, else serve the other approaches best", t, t.low);
  std::cout << "The tables agree in " << agree << " of " << cells << " cells (" << agree << "/" << cells << " = "
            << static_cast<double>(agree) / static_cast<double>(cells) << ").\n";
}

}  // namespace

void register_preemption_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("preemption", "Signal preemption tools");
  cmd->require_subcommand(1);
  auto json = std::make_shared<bool>(false);
  auto* tables = cmd->add_subcommand("tables", "Print the phase-decision tables for the NEMA 8-phase plan");
  tables->add_flag("--json", *json, "print {movements, phases, high, low} as JSON");
  tables->callback([json] { run_tables(*json); });
}

}  // namespace corridor::app
