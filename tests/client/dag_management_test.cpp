// The client's half of MANAGE-TRAVERSAL (client/dag_management.h): the paper's FREE/BUDGET rule as arithmetic,
// and N from the frame time left: it shrinks after a second answer in a row over budget (at most halving),
// grows after one cut short by N under it (at most doubling), holds otherwise, and stays within
// [kMinOps, kMaxDagOps]. The
// switch itself over a real session: tests/server/dag_streaming_test.cpp.
#include <gtest/gtest.h>

#include "client/dag_management.h"
#include "common/error.h"

namespace pms::client {
namespace {

protocol::DagView configured(uint32_t n, uint64_t budget) {
  protocol::DagView request;
  request.max_ops = n;
  request.management = budget ? DagMode::budget : DagMode::free;
  request.budget = budget;
  return request;
}

TEST(DagManagement, FreeWhileTheMeshPlusTwoNFits) {
  EXPECT_TRUE(dag_free_mode_fits(59400, 60000, 300, 1));   // 59,400 + 600 = the budget
  EXPECT_FALSE(dag_free_mode_fits(59401, 60000, 300, 1));  // one triangle more may exceed it
  EXPECT_FALSE(dag_free_mode_fits(59000, 60000, 300, 2));  // a request in flight may add its 600 too
  EXPECT_TRUE(dag_free_mode_fits(58800, 60000, 300, 2));
}

TEST(DagManagement, AutomaticNeedsABudget) {
  EXPECT_THROW(DagManagement(configured(300, 0), {true, 0}), Error);
  EXPECT_THROW(DagManagement(configured(300, 1000), {false, -1}), Error);
  EXPECT_NO_THROW(DagManagement(configured(300, 1000), {true, 0}));
}

TEST(DagManagement, WithoutAFrameBudgetNIsTheRequests) {
  DagManagement m(configured(300, 0), {});
  m.answered(300, 1000, 300, 300);
  m.answered(300, 0.001, 300, 300);
  EXPECT_EQ(m.max_ops(), 300u);
}

// A 20 ms budget: N aims at 85 % of it, 17 ms.
TEST(DagManagement, OverBudgetTwiceShrinksByTheTimeLeftAtMostHalving) {
  DagManagement m(configured(1000, 0), {false, 20});
  m.answered(1000, 20, 1000, 1000);  // took 20: one slow answer changes nothing
  EXPECT_EQ(m.max_ops(), 1000u);
  m.answered(1000, 20, 1000, 1000);  // over again: 1000 * 17 / 20
  EXPECT_EQ(m.max_ops(), 850u);
  m.answered(850, 200, 850, 850);  // ten times over after 20 ms: by the lesser overrun, 850 * 17 / 20
  EXPECT_EQ(m.max_ops(), 722u);
  m.answered(722, 200, 722, 722);  // ten times over twice: halved, not a tenth
  EXPECT_EQ(m.max_ops(), 361u);
  m.answered(361, 24, 100, 100);  // over with only 100 operations: N was not what cost the time
  EXPECT_EQ(m.max_ops(), 180u);   // halved at most, though 100 * 17 / 24 is less
}

TEST(DagManagement, OneSlowAnswerBetweenFastOnesKeepsN) {
  DagManagement m(configured(500, 0), {false, 20});
  for (int i = 0; i < 5; ++i) {
    m.answered(500, 80, 500, 500);  // a time slice lost
    m.answered(500, 16.9, 100, 100);
  }
  EXPECT_EQ(m.max_ops(), 500u);
}

TEST(DagManagement, CutShortUnderBudgetGrowsAtMostDoubling) {
  DagManagement m(configured(100, 0), {false, 20});
  m.answered(100, 10, 100, 40);  // 100 collapses: cut short by N at 10 of 17 ms
  EXPECT_EQ(m.max_ops(), 170u);
  m.answered(170, 1, 20, 170);  // far under: doubled, not seventeenfold
  EXPECT_EQ(m.max_ops(), 340u);
  m.answered(340, 1, 20, 30);  // not cut short: says nothing about a larger N
  EXPECT_EQ(m.max_ops(), 340u);
}

TEST(DagManagement, NStaysWithinItsBounds) {
  DagManagement low(configured(10, 0), {false, 10});
  for (int i = 0; i < 12; ++i) low.answered(low.max_ops(), 1000, low.max_ops(), 0);
  EXPECT_EQ(low.max_ops(), DagManagement::kMinOps);
  DagManagement high(configured(protocol::kMaxDagOps / 2, 0), {false, 10});
  for (int i = 0; i < 4; ++i) high.answered(high.max_ops(), 0.01, high.max_ops(), 0);
  EXPECT_EQ(high.max_ops(), protocol::kMaxDagOps);
}

}  // namespace
}  // namespace pms::client
