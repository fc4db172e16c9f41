// The HTTP budgets: a token bucket that goes into debt, and per-address connections and buckets whose debt
// outlives the address's connections.
#include <gtest/gtest.h>

#include "server/work_budget.h"

namespace pms::server {
namespace {

using std::chrono::milliseconds;

TEST(WorkBudget, ABucketLendsASecondsWorthThenMakesItsOwnerWait) {
  const BudgetClock::time_point t0{};
  TokenBucket bucket(1000, t0);
  EXPECT_EQ(bucket.charge(600, t0), BudgetClock::duration::zero());
  EXPECT_EQ(bucket.charge(400, t0), BudgetClock::duration::zero());
  // 500 units of debt at 1000 a second: half a second.
  EXPECT_EQ(std::chrono::duration_cast<milliseconds>(bucket.charge(500, t0)), milliseconds(500));
  EXPECT_EQ(std::chrono::duration_cast<milliseconds>(bucket.wait(t0 + milliseconds(200))), milliseconds(300));
  EXPECT_EQ(bucket.wait(t0 + milliseconds(500)), BudgetClock::duration::zero());
  EXPECT_FALSE(bucket.full(t0 + milliseconds(1000)));
  EXPECT_TRUE(bucket.full(t0 + milliseconds(1500)));  // never more than a second's worth saved
  EXPECT_EQ(bucket.charge(1000, t0 + milliseconds(5000)), BudgetClock::duration::zero());
  EXPECT_GT(bucket.charge(1, t0 + milliseconds(5000)), BudgetClock::duration::zero());
}

TEST(WorkBudget, ARateOfZeroIsNoLimit) {
  TokenBucket bucket(0);
  EXPECT_EQ(bucket.charge(1e12, BudgetClock::now()), BudgetClock::duration::zero());
  AddressBudgets addresses(0, 0);
  const ClientAddress a{};
  for (int i = 0; i < 10000; ++i) EXPECT_TRUE(addresses.open(a, true));
  EXPECT_EQ(addresses.charge(a, 1e12, BudgetClock::now()), BudgetClock::duration::zero());
}

TEST(WorkBudget, ConnectionsArePerAddressAndAProxyIsNotCapped) {
  AddressBudgets addresses(2, 1000);
  ClientAddress a{}, b{};
  b.bytes[15] = 1;
  EXPECT_TRUE(addresses.open(a, true));
  EXPECT_TRUE(addresses.open(a, true));
  EXPECT_FALSE(addresses.open(a, true));
  EXPECT_TRUE(addresses.open(b, true));
  EXPECT_TRUE(addresses.open(a, false));  // a trusted proxy: only the server's total bounds it
  addresses.close(a);
  addresses.close(a);
  EXPECT_TRUE(addresses.open(a, true));
  EXPECT_EQ(addresses.tracked(), 2u);
}

TEST(WorkBudget, ADebtOutlivesTheConnectionsThatMadeIt) {
  AddressBudgets addresses(4, 1000);
  const ClientAddress a{};
  const BudgetClock::time_point now = BudgetClock::now();
  ASSERT_TRUE(addresses.open(a, true));
  EXPECT_GT(addresses.charge(a, 5000, now), milliseconds(3900));
  addresses.close(a);
  EXPECT_EQ(addresses.tracked(), 1u);  // reconnecting does not refill the budget
  ASSERT_TRUE(addresses.open(a, true));
  EXPECT_GT(addresses.charge(a, 1, now), milliseconds(3900));
  addresses.close(a);
}

}  // namespace
}  // namespace pms::server
