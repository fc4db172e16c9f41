#include "server/work_budget.h"

#include <algorithm>

namespace pms::server {

void TokenBucket::refill(BudgetClock::time_point now) {
  if (now <= refilled_) return;
  tokens_ = std::min(rate_, tokens_ + rate_ * std::chrono::duration<double>(now - refilled_).count());
  refilled_ = now;
}

BudgetClock::duration TokenBucket::charge(double units, BudgetClock::time_point now) {
  if (rate_ <= 0) return BudgetClock::duration::zero();
  refill(now);
  tokens_ -= units;
  return wait(now);
}

BudgetClock::duration TokenBucket::wait(BudgetClock::time_point now) {
  if (rate_ <= 0) return BudgetClock::duration::zero();
  refill(now);
  if (tokens_ >= 0) return BudgetClock::duration::zero();
  return std::chrono::duration_cast<BudgetClock::duration>(std::chrono::duration<double>(-tokens_ / rate_));
}

bool TokenBucket::full(BudgetClock::time_point now) const {
  if (rate_ <= 0 || now <= refilled_) return rate_ <= 0 || tokens_ >= rate_;
  return tokens_ + rate_ * std::chrono::duration<double>(now - refilled_).count() >= rate_;
}

bool AddressBudgets::open(const ClientAddress& address, bool capped) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto [it, added] = entries_.try_emplace(address, Entry{0, TokenBucket(rate_)});
  if (capped && max_connections_ != 0 && it->second.connections >= max_connections_) return false;
  it->second.connections++;
  return true;
}

void AddressBudgets::close(const ClientAddress& address) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = entries_.find(address);
  if (it == entries_.end()) return;
  if (it->second.connections > 0) it->second.connections--;
  if (it->second.connections == 0 && it->second.bucket.full(BudgetClock::now())) entries_.erase(it);
}

BudgetClock::duration AddressBudgets::charge(const ClientAddress& address, double units, BudgetClock::time_point now) {
  if (rate_ <= 0) return BudgetClock::duration::zero();
  std::lock_guard<std::mutex> lock(mutex_);
  if (entries_.size() >= swept_at_size_) sweep(now);
  auto [it, added] = entries_.try_emplace(address, Entry{0, TokenBucket(rate_, now)});
  return it->second.bucket.charge(units, now);
}

size_t AddressBudgets::tracked() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return entries_.size();
}

// Amortised: the next sweep waits until the table has doubled over what survived this one.
void AddressBudgets::sweep(BudgetClock::time_point now) {
  std::erase_if(entries_, [&](auto& entry) { return entry.second.connections == 0 && entry.second.bucket.full(now); });
  swept_at_size_ = std::max<size_t>(1024, 2 * entries_.size());
}

}  // namespace pms::server
