// What one HTTP client may take of the server (docs/operating.md, "HTTP"): connections at once per
// address, and work per second per address and per connection, as token buckets. Work is counted in
// units of about one split record encoded (http_cost.h says what a request costs). A client over its
// budget is not refused: its connections are not read until the budget has refilled, so a viewer that
// asks a lot is slowed, never broken, and a host that asks too much cannot take the threads from others.
#pragma once
#include <chrono>
#include <cstdint>
#include <mutex>
#include <unordered_map>

#include "server/client_address.h"

namespace pms::server {

using BudgetClock = std::chrono::steady_clock;

// `rate` units a second, at most `rate` saved (a second's worth of burst); 0 = unlimited. Goes into debt
// by what is charged: the time until the debt is repaid is how long its owner waits.
class TokenBucket {
 public:
  explicit TokenBucket(double rate = 0, BudgetClock::time_point now = BudgetClock::now())
      : rate_(rate), tokens_(rate), refilled_(now) {}

  // Takes `units`; the wait until the bucket is no longer in debt (zero when it is not).
  BudgetClock::duration charge(double units, BudgetClock::time_point now);
  // The wait until it is no longer in debt, without charging.
  BudgetClock::duration wait(BudgetClock::time_point now);
  bool full(BudgetClock::time_point now) const;

 private:
  void refill(BudgetClock::time_point now);

  double rate_;
  double tokens_;
  BudgetClock::time_point refilled_;
};

// Every client address's connections and work bucket, shared by the HTTP server's threads.
class AddressBudgets {
 public:
  // At most `max_connections` per address (0 = any), `rate` units a second per address (0 = unlimited).
  AddressBudgets(uint32_t max_connections, double rate) : max_connections_(max_connections), rate_(rate) {}

  // A connection from `address` begins: false, and nothing counted, when the address has its maximum.
  // `capped` false for a trusted proxy, which carries many clients' connections.
  bool open(const ClientAddress& address, bool capped);
  void close(const ClientAddress& address);
  // Charges `units` to `address`: the wait before its connections may be read again.
  BudgetClock::duration charge(const ClientAddress& address, double units, BudgetClock::time_point now);
  // Addresses tracked now: those with a connection or a debt (a bound: max connections + recent debtors).
  size_t tracked() const;

 private:
  struct Entry {
    uint32_t connections = 0;
    TokenBucket bucket;
  };
  // Drops addresses with no connection and a full bucket, a sweep every so many charges: what an address
  // owes outlives its connections, so reconnecting does not refill a budget.
  void sweep(BudgetClock::time_point now);

  const uint32_t max_connections_;
  const double rate_;
  mutable std::mutex mutex_;
  std::unordered_map<ClientAddress, Entry, ClientAddressHash> entries_;
  size_t swept_at_size_ = 1024;
};

}  // namespace pms::server
