// The HTTP attack classes, short: each group of src/bench/http_attackers.h against a real `pmstream serve
// --json` child over a generated terrain, with the deadlines cut to a second (the idle deadline to three,
// ten under a sanitizer) so each class meets them within the run. Asked of every group: the good client
// ends with its quiet flight's mesh, its p99 within kMaxP99Ratio of the quiet one (release only: the median
// of up to three pairs, http_attack_run.cpp), the server's RSS plus its sockets' kernel memory under the
// documented bound, CPU idle within 3 s, SIGTERM within 1 s, and the counters show the defence that acted.
// `pmstream-bench --only attacks` runs the same classes at the server's own deadlines.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "bench/http_attack_run.h"
#include "bench/http_attack_targets.h"
#include "test_support.h"

namespace pms::bench {
namespace {

using std::chrono::milliseconds;

class HttpAttacks : public ::testing::Test {
 protected:
  static const AttackSetup& setup() {
    static const AttackSetup s = [] {
      AttackSetup made = attack_setup(PMSTREAM_BINARY, build_terrain(PMSTREAM_BINARY, test::temp_dir(), 100000),
                                      test::kSanitized ? 40 : 120, 0.5f);
      made.request_timeout = made.write_timeout = milliseconds(1000);
      made.idle_timeout = milliseconds(test::kSanitized ? 10000 : 3000);
      made.min_attack = milliseconds(3000);
      made.compare_p99 = !test::kSanitized;
      if (test::kSanitized) made.slack = milliseconds(6000);
      return made;
    }();
    return s;
  }

  static AttackOutcome run(size_t group) {
    AttackOutcome outcome = run_attack_group(setup(), attack_groups()[group]);
    print(outcome);
    return outcome;
  }

  static const AttackTally& tally(const AttackOutcome& outcome, AttackClass attack) {
    for (size_t c = 0; c < outcome.classes.size(); ++c)
      if (outcome.classes[c] == attack) return outcome.tallies[c];
    throw std::logic_error("no such class in the group");
  }

  static uint64_t counter(const AttackOutcome& outcome, const char* name) {
    return outcome.http.value(name, uint64_t(0));
  }

  static void print(const AttackOutcome& o) {
    std::printf(
        "[ attacks  ] %s: p99 quiet %.1f ms (%zu answers, %.1f s), attacked %.1f ms (%zu, %.1f s), median ratio "
        "%.2f over %zu pair(s); server CPU %.2f s; RSS peak %.1f MB, sockets peak %.2f MB, bound %.1f MB; idle "
        "after %.2f s (%.1f %%); SIGTERM %.3f s; http %s%s\n",
        o.group.c_str(), p99(o.quiet.latency_ms), o.quiet.latency_ms.size(), o.quiet.seconds,
        p99(o.attacked.latency_ms), o.attacked.latency_ms.size(), o.attacked.seconds, o.median_ratio, o.pairs,
        o.attack_cpu_s, double(o.peak_rss) / 1e6, double(o.peak_sockets) / 1e6, double(o.memory_bound) / 1e6,
        o.idle_after_s, 100 * o.idle_use, o.sigterm_s, o.http.dump().c_str(),
        test::kSanitized ? " (sanitizer build: the p99 bound is the release run's)" : "");
    for (size_t c = 0; c < o.classes.size(); ++c) {
      const AttackTally& t = o.tallies[c];
      std::printf(
          "[ attacks  ]   %s: %llu rounds (%llu not connected), %llu answers (%llu 2xx/3xx, %llu 4xx, %llu 503, "
          "%llu other 5xx), %llu ended by the server (%llu reset), longest %llu ms, %llu late, %llu smuggled\n",
          attack_class_name(o.classes[c]), (unsigned long long)t.rounds.load(),
          (unsigned long long)t.connect_failures.load(), (unsigned long long)t.answers.load(),
          (unsigned long long)t.ok.load(), (unsigned long long)t.client_errors.load(),
          (unsigned long long)t.refused.load(), (unsigned long long)t.server_errors.load(),
          (unsigned long long)t.closed.load(), (unsigned long long)t.resets.load(),
          (unsigned long long)t.longest_close_ms.load(), (unsigned long long)t.late.load(),
          (unsigned long long)t.smuggled.load());
    }
  }

  // What every group must leave behind.
  static void expect_unhurt(const AttackOutcome& o) {
    ASSERT_EQ(o.error, "");
    EXPECT_EQ(o.quiet.error, "") << "the quiet flight failed";
    EXPECT_EQ(o.attacked.error, "") << "the good client failed under attack";
    EXPECT_TRUE(o.same_mesh) << "the attacked flight does not end with the quiet flight's mesh";
    // A sanitizer build's time and memory are not the product's (its allocator keeps freed blocks in
    // quarantine): the p99 and memory bounds are the release run's.
    if (!test::kSanitized) {
      EXPECT_LE(o.median_ratio, kMaxP99Ratio) << "median attacked / quiet p99 ratio";
      EXPECT_LE(o.peak_total, o.memory_bound) << "RSS plus the server's socket memory, at their peak";
    }
    EXPECT_GE(o.idle_after_s, 0) << "CPU " << 100 * o.idle_use << " % of a core, 3 s after the attack";
    EXPECT_LE(o.sigterm_s, 1.0) << "SIGTERM to exit";
    for (size_t c = 0; c < o.classes.size(); ++c)
      EXPECT_EQ(o.tallies[c].server_errors, 0u) << attack_class_name(o.classes[c]) << ": a 5xx of the server's own";
  }
};

TEST_F(HttpAttacks, SlowPeersAreEndedByTheirDeadlines) {
  const AttackOutcome o = run(0);
  expect_unhurt(o);
  for (AttackClass attack : {AttackClass::slowloris, AttackClass::dripped_body, AttackClass::unread_pipeline}) {
    EXPECT_GT(tally(o, attack).closed, 0u) << attack_class_name(attack);
    EXPECT_EQ(tally(o, attack).late, 0u) << attack_class_name(attack) << ": not ended by its deadline";
  }
  EXPECT_GT(tally(o, AttackClass::unread_pipeline).resets, 0u) << "never-reading pipeliners must be reset";
  EXPECT_GT(counter(o, "connections_reset"), 0u);
}

TEST_F(HttpAttacks, ParsingPipeliningAndExpensiveRequestsAreRefusedOrBudgeted) {
  const AttackOutcome o = run(1);
  expect_unhurt(o);
  EXPECT_GT(tally(o, AttackClass::malformed).client_errors, 0u);
  EXPECT_EQ(tally(o, AttackClass::malformed).late, 0u) << "a malformed request not answered at once";
  const AttackTally& bombs = tally(o, AttackClass::bombs);
  EXPECT_GT(bombs.statuses_413, 0u);
  EXPECT_GT(bombs.statuses_414, 0u);
  EXPECT_GT(bombs.statuses_431, 0u);
  EXPECT_EQ(bombs.late, 0u) << "a bomb not refused at once";
  EXPECT_GT(tally(o, AttackClass::expensive_pipeline).ok, 0u);
  EXPECT_GT(tally(o, AttackClass::expensive_head).ok, 0u);
  EXPECT_EQ(tally(o, AttackClass::smuggling).smuggled, 0u) << "a request behind a refused framing was answered";
  EXPECT_EQ(tally(o, AttackClass::smuggling).late, 0u) << "a smuggling attempt's connection left open";
  EXPECT_GT(counter(o, "budget_waits") + counter(o, "sliced_answers"), 0u);
  std::printf("[ attacks  ] expensive request: %s\n", setup().expensive_note.c_str());
}

TEST_F(HttpAttacks, AConnectionFloodIsCappedPerAddress) {
  const AttackOutcome o = run(2);
  expect_unhurt(o);
  EXPECT_GT(tally(o, AttackClass::connection_flood).refused, 0u);
  EXPECT_GT(counter(o, "connections_refused_per_address"), 0u);
}

}  // namespace
}  // namespace pms::bench
