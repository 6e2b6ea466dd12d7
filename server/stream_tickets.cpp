#include "server/stream_tickets.hpp"

#include <algorithm>
#include <vector>

namespace corridor::server {

StreamTickets::StreamTickets(StreamTicketConfig config) : config_(config) {}

void StreamTickets::purge(double now_s) {
  std::erase_if(tickets_, [now_s](const auto& kv) { return kv.second.expires_s <= now_s; });
  if (tickets_.size() < config_.max_outstanding) return;
  // Still full of live tickets: drop the half that expires first.
  std::vector<double> expiries;
  expiries.reserve(tickets_.size());
  for (const auto& [t, e] : tickets_) expiries.push_back(e.expires_s);
  auto mid = expiries.begin() + static_cast<std::ptrdiff_t>(expiries.size() / 2);
  std::nth_element(expiries.begin(), mid, expiries.end());
  const double cut = *mid;
  std::erase_if(tickets_, [cut](const auto& kv) { return kv.second.expires_s <= cut; });
}

std::string StreamTickets::issue(const Principal& who, double now_s) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::lock_guard lock(mutex_);
  purge(now_s);
  std::string ticket;
  ticket.reserve(32);
  for (int word = 0; word < 4; ++word) {
    std::uint32_t bits = entropy_();
    for (int i = 0; i < 8; ++i, bits >>= 4) ticket.push_back(kHex[bits & 0xf]);
  }
  tickets_[ticket] = {who, now_s + config_.lifetime_s};
  return ticket;
}

std::optional<Principal> StreamTickets::redeem(const std::string& ticket, double now_s) {
  std::lock_guard lock(mutex_);
  auto it = tickets_.find(ticket);
  if (it == tickets_.end()) return std::nullopt;
  Entry e = std::move(it->second);
  tickets_.erase(it);
  if (e.expires_s <= now_s) return std::nullopt;
  return e.who;
}

}  // namespace corridor::server
