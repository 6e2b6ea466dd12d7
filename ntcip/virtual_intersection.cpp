#include "ntcip/virtual_intersection.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "preemption/phase_selection.hpp"

namespace corridor::ntcip {
namespace {

// The table's column and index of an OID directly below `base`, or nullopt.
std::optional<std::uint32_t> index_under(const Oid& oid, const Oid& base) {
  if (oid.size() != base.size() + 1 || !std::equal(base.begin(), base.end(), oid.begin())) return std::nullopt;
  return oid.back();
}

Value integer(std::int64_t v) { return {Value::Type::integer, v, {}, {}}; }

const std::vector<Oid>& phase_control_columns() {
  static const std::vector<Oid> columns{oid::kPhaseControlGroupPhaseOmit, oid::kPhaseControlGroupHold,
                                        oid::kPhaseControlGroupForceOff, oid::kPhaseControlGroupVehCall};
  return columns;
}

}  // namespace

VirtualIntersection::VirtualIntersection(NodeId node, const maps::SignalPlan& plan, std::vector<PreemptInput> preempts,
                                         preemption::SignalController& controller, std::string description, VirtualTiming timing)
    : node_(node), plan_(plan), preempts_(std::move(preempts)), controller_(controller), description_(std::move(description)),
      timing_(timing) {
  std::sort(preempts_.begin(), preempts_.end(), [](const PreemptInput& a, const PreemptInput& b) { return a.number < b.number; });
  for (std::size_t i = 0; i < preempts_.size(); ++i) {
    if (preempts_[i].number != i + 1) throw std::invalid_argument("preempt numbers must run 1.." + std::to_string(preempts_.size()));
    const PreemptInput& p = preempts_[i];
    std::optional<std::size_t> movement = p.movement;
    if (movement && *movement >= plan.movements.size()) throw std::invalid_argument("a preempt's movement is not in the plan");
    // The approach's through movement stands for it; else its first.
    for (std::size_t m = 0; m < plan.movements.size() && !movement; ++m) {
      if (plan.movements[m].from == p.approach && plan.movements[m].turn == maps::Turn::through) movement = m;
    }
    for (std::size_t m = 0; m < plan.movements.size() && !movement; ++m) {
      if (plan.movements[m].from == p.approach) movement = m;
    }
    if (!movement) {
      throw std::invalid_argument("preempt " + std::to_string(p.number) + ": the intersection has no approach from " +
                                  std::string(1, maps::compass_letter(p.approach)));
    }
    preempt_phases_.push_back(
        preemption::select_phase(plan, *movement, std::nullopt, preemption::CongestionLevel::high).phase);
  }
  calls_.assign(preempts_.size(), {});
  groups_ = std::max<std::uint32_t>(1, static_cast<std::uint32_t>((plan.movements.size() + 7) / 8));
  omit_.assign(groups_, 0);
  hold_.assign(groups_, 0);
  force_off_.assign(groups_, 0);
  veh_call_.assign(groups_, 0);
  objects_ = {oid::kSysDescr, oid::kSysObjectId, oid::kSysUpTime, oid::kMaxPhases, oid::kMaxPhaseGroups, oid::kMaxPreempts};
  for (std::uint32_t g = 1; g <= groups_; ++g) {
    for (const Oid& c : {oid::kPhaseStatusGroupReds, oid::kPhaseStatusGroupYellows, oid::kPhaseStatusGroupGreens}) {
      objects_.push_back(column(c, g));
    }
    for (const Oid& c : phase_control_columns()) objects_.push_back(column(c, g));
  }
  for (std::uint32_t n = 1; n <= preempts_.size(); ++n) {
    objects_.push_back(column(oid::kPreemptState, n));
    objects_.push_back(column(oid::kPreemptControlState, n));
  }
  std::sort(objects_.begin(), objects_.end());
}

std::int32_t VirtualIntersection::lights_bits(std::uint32_t group, preemption::Light light) const {
  const std::vector<preemption::Light> lights = controller_.lights_shown(node_);
  std::vector<std::uint32_t> phases;
  for (std::size_t m = 0; m < lights.size(); ++m) {
    if (lights[m] == light) phases.push_back(static_cast<std::uint32_t>(m + 1));
  }
  return group_bits(group, phases);
}

std::optional<Value> VirtualIntersection::get(const Oid& o, double now_s) const {
  if (o == oid::kSysDescr) return Value{Value::Type::octets, 0, description_, {}};
  if (o == oid::kSysObjectId) return Value{Value::Type::object_id, 0, {}, oid::kAsc};
  if (o == oid::kSysUpTime) {
    const double up_s = started_s_ < 0.0 ? 0.0 : std::max(0.0, now_s - started_s_);
    return Value{Value::Type::timeticks, static_cast<std::int64_t>(std::fmod(up_s * 100.0, 4294967296.0)), {}, {}};
  }
  if (o == oid::kMaxPhases) return integer(static_cast<std::int64_t>(plan_.movements.size()));
  if (o == oid::kMaxPhaseGroups) return integer(groups_);
  if (o == oid::kMaxPreempts) return integer(static_cast<std::int64_t>(preempts_.size()));
  const auto in_groups = [&](const Oid& base) -> std::optional<std::uint32_t> {
    const auto g = index_under(o, base);
    return g && *g >= 1 && *g <= groups_ ? g : std::nullopt;
  };
  if (const auto g = in_groups(oid::kPhaseStatusGroupReds)) return integer(lights_bits(*g, preemption::Light::red));
  if (const auto g = in_groups(oid::kPhaseStatusGroupYellows)) return integer(lights_bits(*g, preemption::Light::yellow));
  if (const auto g = in_groups(oid::kPhaseStatusGroupGreens)) return integer(lights_bits(*g, preemption::Light::green));
  if (const auto g = in_groups(oid::kPhaseControlGroupPhaseOmit)) return integer(omit_[*g - 1]);
  if (const auto g = in_groups(oid::kPhaseControlGroupHold)) return integer(hold_[*g - 1]);
  if (const auto g = in_groups(oid::kPhaseControlGroupForceOff)) return integer(force_off_[*g - 1]);
  if (const auto g = in_groups(oid::kPhaseControlGroupVehCall)) return integer(veh_call_[*g - 1]);
  const auto in_preempts = [&](const Oid& base) -> std::optional<std::uint32_t> {
    const auto n = index_under(o, base);
    return n && *n >= 1 && *n <= preempts_.size() ? n : std::nullopt;
  };
  if (const auto n = in_preempts(oid::kPreemptState)) return integer(static_cast<std::int32_t>(preempt_state(*n)));
  if (const auto n = in_preempts(oid::kPreemptControlState)) return integer(calls_[*n - 1].on ? 1 : 0);
  return std::nullopt;
}

std::optional<Oid> VirtualIntersection::next(const Oid& o) const {
  const auto it = std::upper_bound(objects_.begin(), objects_.end(), o);
  if (it == objects_.end()) return std::nullopt;
  return *it;
}

SetStatus VirtualIntersection::check_set(const Oid& o, const Value& value) const {
  if (!std::binary_search(objects_.begin(), objects_.end(), o)) return SetStatus::no_such_object;
  const bool control = index_under(o, oid::kPreemptControlState).has_value();
  bool phase_control = false;
  for (const Oid& c : phase_control_columns()) phase_control = phase_control || index_under(o, c).has_value();
  if (!control && !phase_control) return SetStatus::not_writable;
  if (value.type != Value::Type::integer) return SetStatus::wrong_type;
  if (control && value.integer != 0 && value.integer != 1) return SetStatus::wrong_value;
  if (phase_control && (value.integer < 0 || value.integer > 255)) return SetStatus::wrong_value;
  return SetStatus::ok;
}

void VirtualIntersection::set(const Oid& o, const Value& value, double now_s) {
  if (check_set(o, value) != SetStatus::ok) return;
  if (const auto n = index_under(o, oid::kPreemptControlState)) {
    Call& c = calls_[*n - 1];
    if (value.integer == 1) {
      if (!c.on) spdlog::info("event=ntcip_call node={} preempt={} t={:.1f}", node_.v, *n, now_s);
      c.on = true;
      c.asserted_s = now_s;
    } else {
      if (c.on) spdlog::info("event=ntcip_call_removed node={} preempt={} t={:.1f}", node_.v, *n, now_s);
      c.on = false;
      c.locked_out = false;
    }
  } else {
    const std::size_t g = o.back() - 1;
    const auto bits = static_cast<std::int32_t>(value.integer);
    if (index_under(o, oid::kPhaseControlGroupPhaseOmit)) omit_[g] = bits;
    if (index_under(o, oid::kPhaseControlGroupHold)) hold_[g] = bits;
    if (index_under(o, oid::kPhaseControlGroupForceOff)) force_off_[g] = bits;
    if (index_under(o, oid::kPhaseControlGroupVehCall)) veh_call_[g] = bits;
  }
  step(now_s);
}

std::optional<std::uint32_t> VirtualIntersection::active_preempt() const {
  // NTCIP's order: the lowest-numbered preempt called is served.
  for (std::size_t i = 0; i < calls_.size(); ++i) {
    if (calls_[i].on && !calls_[i].locked_out) return static_cast<std::uint32_t>(i + 1);
  }
  return std::nullopt;
}

maps::Phase VirtualIntersection::phase_control_phase() const {
  maps::Phase phase;
  phase.label = "phase-control";
  phase.green.assign(plan_.movements.size(), 0);
  phase.min_green_s = plan_.phases.empty() ? 5.0 : plan_.phases.front().min_green_s;
  for (std::size_t m = 0; m < plan_.movements.size(); ++m) {
    const std::size_t g = m / 8;
    const auto bit = 1 << (m % 8);
    if (((hold_[g] | veh_call_[g]) & bit) == 0 || (omit_[g] & bit) != 0) continue;
    // Served in phase order; one that conflicts with a phase already served waits.
    bool compatible = true;
    for (std::size_t k = 0; k < m; ++k) compatible = compatible && !(phase.green[k] && plan_.conflicts(k, m));
    if (compatible) phase.green[m] = 1;
  }
  return phase;
}

std::size_t VirtualIntersection::exit_step(const maps::Phase& held) const {
  // Exit to the program step that serves most of what the preempt kept red.
  std::size_t best = 0, best_score = 0;
  for (std::size_t s = 0; s < plan_.program.size(); ++s) {
    std::size_t score = 0;
    const maps::Phase& p = plan_.phases[plan_.program[s].phase];
    for (std::size_t m = 0; m < plan_.movements.size(); ++m) score += p.serves(m) && !held.serves(m) ? 1 : 0;
    if (score > best_score) {
      best = s;
      best_score = score;
    }
  }
  return best;
}

void VirtualIntersection::release(double now_s) {
  controller_.release(node_, exit_step(held_), now_s);
  serving_ = Serving::none;
  exiting_ = true;
}

void VirtualIntersection::step(double now_s) {
  now_s_ = now_s;
  if (started_s_ < 0.0) started_s_ = now_s;
  for (std::size_t i = 0; i < calls_.size(); ++i) {
    Call& c = calls_[i];
    if (c.on && now_s - c.asserted_s > timing_.call_timeout_s) {
      // The watchdog: a call its sender stopped asserting is dropped.
      spdlog::warn("event=ntcip_call_timed_out node={} preempt={} t={:.1f} asserted_s={:.1f}", node_.v, i + 1, now_s, c.asserted_s);
      c.on = false;
      c.locked_out = false;
    }
    if (c.on && c.served_since_s >= 0.0 && now_s - c.served_since_s > timing_.max_presence_s && !c.locked_out) {
      spdlog::warn("event=ntcip_max_presence node={} preempt={} t={:.1f}", node_.v, i + 1, now_s);
      c.locked_out = true;
    }
  }
  const std::optional<std::uint32_t> active = active_preempt();
  for (std::size_t i = 0; i < calls_.size(); ++i) {
    if (!active || *active != i + 1) calls_[i].served_since_s = -1.0;
  }
  if (active) {
    if (serving_ != Serving::preempt || served_preempt_ != *active) {
      held_ = preempt_phases_[*active - 1];
      controller_.hold(node_, held_, now_s);
      serving_ = Serving::preempt;
      served_preempt_ = *active;
      exiting_ = false;
      calls_[*active - 1].served_since_s = now_s;
    }
    return;
  }
  const maps::Phase control = phase_control_phase();
  if (std::find(control.green.begin(), control.green.end(), 1) != control.green.end()) {
    if (serving_ != Serving::phase_control || control.green != held_.green) {
      held_ = control;
      controller_.hold(node_, held_, now_s);
      serving_ = Serving::phase_control;
      exiting_ = false;
    }
    return;
  }
  if (serving_ != Serving::none) release(now_s);
  if (exiting_ && controller_.hold_stage(node_) == preemption::HoldStage::none) {
    exiting_ = false;
    served_preempt_.reset();
  }
}

PreemptState VirtualIntersection::preempt_state(std::uint32_t number) const {
  if (number < 1 || number > calls_.size()) return PreemptState::other;
  const Call& c = calls_[number - 1];
  if (c.on && c.locked_out) return PreemptState::max_presence;
  if (serving_ == Serving::preempt && served_preempt_ == number) {
    return controller_.hold_stage(node_) == preemption::HoldStage::holding ? PreemptState::dwell : PreemptState::entry_started;
  }
  if (exiting_ && served_preempt_ == number) return PreemptState::exit_started;
  return c.on ? PreemptState::not_active_with_call : PreemptState::not_active;
}

const maps::Phase& VirtualIntersection::preempt_phase(std::uint32_t number) const { return preempt_phases_.at(number - 1); }

}  // namespace corridor::ntcip
