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

TEST(DagManagement, OverBudgetTwiceShrinksByTheTimeLeftAtMostHalving) {
  DagManagement m(configured(1000, 0), {false, 10});
  m.answered(1000, 12, 1000, 1000);  // aimed at 8 ms, took 12: one slow answer changes nothing
  EXPECT_EQ(m.max_ops(), 1000u);
  m.answered(1000, 10, 1000, 1000);  // over again: by the lesser overrun, 1000 * 8 / 10
  EXPECT_EQ(m.max_ops(), 800u);
  m.answered(800, 100, 800, 800);  // ten times over, after 10 ms: 800 * 8 / 10
  EXPECT_EQ(m.max_ops(), 640u);
  m.answered(640, 100, 640, 640);  // ten times over twice: halved, not a tenth
  EXPECT_EQ(m.max_ops(), 320u);
  m.answered(320, 12, 100, 100);  // over with only 100 operations: N was not what cost the time
  EXPECT_EQ(m.max_ops(), 160u);   // halved at most, though 100 * 8 / 12 is less
}

TEST(DagManagement, OneSlowAnswerBetweenFastOnesKeepsN) {
  DagManagement m(configured(500, 0), {false, 10});
  for (int i = 0; i < 5; ++i) {
    m.answered(500, 40, 500, 500);  // a time slice lost
    m.answered(500, 7.9, 100, 100);
  }
  EXPECT_EQ(m.max_ops(), 500u);
}

TEST(DagManagement, CutShortUnderBudgetGrowsAtMostDoubling) {
  DagManagement m(configured(100, 0), {false, 10});
  m.answered(100, 5, 100, 40);  // 100 collapses: cut short by N at 5 of 8 ms
  EXPECT_EQ(m.max_ops(), 160u);
  m.answered(160, 1, 20, 160);  // far under: doubled, not eightfold
  EXPECT_EQ(m.max_ops(), 320u);
  m.answered(320, 1, 20, 30);  // not cut short: says nothing about a larger N
  EXPECT_EQ(m.max_ops(), 320u);
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
