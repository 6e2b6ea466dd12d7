// Preemption's SignalController for SUMO traffic lights. While a light runs its program, SUMO runs
// it. A hold takes the light over with setRedYellowGreenState, through yellow and all-red; a
// release hands it back the same way, then restores the saved program and restarts it at a
// defined phase. Every state it sets is audited against the safety rules.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "maps/sumo_net.hpp"
#include "preemption/signal_controller.hpp"

namespace corridor::sim {

// The TraCI calls the controller needs, so that tests can stand in for SUMO.
class TrafficLightApi {
 public:
  virtual ~TrafficLightApi() = default;
  [[nodiscard]] virtual std::string state(const std::string& tls) = 0;
  [[nodiscard]] virtual int phase(const std::string& tls) = 0;
  [[nodiscard]] virtual double spent_s(const std::string& tls) = 0;  // in the current phase
  virtual void set_state(const std::string& tls, const std::string& state) = 0;
  virtual void set_program(const std::string& tls, const std::string& program_id) = 0;
  virtual void set_phase(const std::string& tls, int phase) = 0;
};

class SumoSignalController final : public preemption::SignalController {
 public:
  // `plans` are keyed by node and must outlive the controller; `sumo` gives each node's light.
  // `actuated` names the lights whose programs SUMO times itself (actuated, delay_based): their
  // phases' lengths are not known ahead.
  SumoSignalController(const std::unordered_map<NodeId, maps::SignalPlan>& plans,
                       const std::unordered_map<NodeId, const maps::SumoSignalPlan*>& sumo,
                       const std::unordered_map<std::string, std::vector<maps::SumoTlPhase>>& sumo_phases,
                       TrafficLightApi& api, const std::set<std::string>& actuated = {});

  // Advances yellow and all-red stages; call every simulation step.
  void update(double now_s);

  void hold(NodeId node, const maps::Phase& phase, double now_s) override;
  void release(NodeId node, std::size_t resume_step, double now_s) override;
  [[nodiscard]] preemption::SignalMode mode(NodeId node) const override;
  [[nodiscard]] double remaining_min_green_s(NodeId node, double now_s) const override;
  [[nodiscard]] std::optional<std::size_t> current_phase(NodeId node) const override;
  [[nodiscard]] std::optional<double> green_start_s(NodeId node, std::size_t movement) const override;
  // SUMO's program from its phase on show: every phase of a fixed program, only the shortest the
  // phase on show can be of an actuated one.
  [[nodiscard]] std::vector<preemption::ProgramInterval> program_forecast(NodeId node, double now_s,
                                                                          double horizon_s) const override;
  [[nodiscard]] preemption::HoldStage hold_stage(NodeId node) const override;
  [[nodiscard]] std::vector<preemption::Light> lights_shown(NodeId node) const override;

  // Breaches of the safety rules in the states this controller set; empty when all held.
  [[nodiscard]] const std::vector<std::string>& violations() const { return violations_; }
  // Lights taken over at least once, and how many of them are back on their program now.
  [[nodiscard]] std::size_t lights_taken_over() const;
  [[nodiscard]] std::size_t lights_on_program() const;
  [[nodiscard]] std::size_t holds_reached() const { return holds_reached_; }
  [[nodiscard]] std::size_t programs_restored() const { return programs_restored_; }

 private:
  enum class Stage { program, clear_yellow, clear_all_red, held, back_yellow, back_all_red };
  struct Light {
    NodeId node;
    const maps::SignalPlan* plan = nullptr;
    std::string tls;
    std::string program_id;
    std::vector<maps::SumoTlPhase> sumo_phases;
    std::vector<std::uint8_t> allowed_together;  // links × links: green together in the program
    Stage stage = Stage::program;
    double stage_start_s = 0.0;
    double wait_until_s = 0.0;  // a stage change is deferred until min green is served
    std::string shown;          // the state last set by this controller
    std::string target;         // the held state
    maps::Phase held_phase;
    double held_since_s = 0.0;
    bool release_pending = false;
    int resume_sumo_phase = 0;
    bool taken_over = false;
    bool actuated = false;
    // Audit: when each link took its current light.
    std::vector<double> since_s;
  };

  Light& light(NodeId node);
  const Light& light(NodeId node) const;
  void show(Light& l, const std::string& state, double now_s);
  void begin_return(Light& l, double now_s);
  void restore_program(Light& l, double now_s);
  [[nodiscard]] int sumo_phase_of_step(const Light& l, std::size_t step) const;
  [[nodiscard]] double program_min_green_left_s(Light& l) const;

  std::unordered_map<NodeId, Light> lights_;
  TrafficLightApi& api_;
  std::vector<std::string> violations_;
  std::size_t holds_reached_ = 0;
  std::size_t programs_restored_ = 0;
  double now_s_ = 0.0;
};

}  // namespace corridor::sim
