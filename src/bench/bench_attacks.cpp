// The "attacks" group: the HTTP attack classes of http_attackers.h at the server's own deadlines, in their
// three groups one after the other (slow peers; parsing, pipelining and expensive requests; connection
// floods), each group's classes at once with ten attackers each on 127.0.0.2 ... 127.0.0.5, beside a good
// receiver-driven client from 127.0.0.1 on dragon (the terrain without ../shared/models). Each group
// lasts past the longest deadline its classes must meet. docs/architecture.md says what each figure means;
// tests/bench/http_attacks_test.cpp runs the same classes short.
#include <algorithm>
#include <cstdio>

#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/bench_refine.h"
#include "bench/http_attack_run.h"
#include "bench/http_attack_targets.h"
#include "bench/report.h"

namespace pms::bench {
namespace {

using nlohmann::json;
using std::chrono::milliseconds;

constexpr uint64_t kTerrainFaces = 200000;
constexpr uint32_t kFrames = 180, kQuickFrames = 60;
constexpr float kTolerance = 1;     // pixels
const milliseconds kOutlast(3000);  // past the longest deadline, so that each class meets it

std::string mb(uint64_t bytes) { return fixed(double(bytes) / 1e6, 1); }

// Dragon's .pms, or the terrain's when there are no shared models (said in `model`).
std::string model_pms(BenchContext& context, std::string& model) {
  if (!context.models_dir.empty()) {
    model = "dragon";
    return prepare_model(context, model).pms.string();
  }
  model = "terrain:" + std::to_string(kTerrainFaces) + " (../shared/models not found)";
  return build_terrain(context.pmstream_exe, context.temp_dir, kTerrainFaces);
}

uint64_t counter(const AttackOutcome& o, const char* name) { return o.http.value(name, uint64_t(0)); }

// The bounds a group must meet, and which it missed.
std::string verdict(const AttackOutcome& o) {
  std::string missed;
  auto check = [&](bool ok, const std::string& what) {
    if (!ok) missed += (missed.empty() ? "" : ", ") + what;
  };
  check(o.same_mesh, "mesh");
  check(o.median_ratio <= kMaxP99Ratio, "p99");
  check(o.peak_total <= o.memory_bound, "memory");
  check(o.idle_after_s >= 0, "idle");
  check(o.sigterm_s <= 1, "SIGTERM");
  for (size_t c = 0; c < o.classes.size(); ++c) {
    check(o.tallies[c].late == 0, std::string(attack_class_name(o.classes[c])) + " late");
    check(o.tallies[c].smuggled == 0, std::string(attack_class_name(o.classes[c])) + " answered");
  }
  return missed.empty() ? "met" : "missed: " + missed;
}

Table group_table() {
  return Table({{"group", false},
                {"quiet p99 ms"},
                {"attacked p99 ms"},
                {"ratio (pairs)"},
                {"answers"},
                {"server CPU s"},
                {"RSS peak MB"},
                {"socket peak MB"},
                {"RSS + sockets / bound MB"},
                {"idle after s"},
                {"SIGTERM s"},
                {"refused per address"},
                {"reset"},
                {"budget waits"},
                {"sliced"},
                {"bounds", false}});
}

std::vector<std::string> group_row(const AttackOutcome& o) {
  if (!o.error.empty()) return {o.group, "", "", "", "", "", "", "", "", "", "", "", "", "", "", "failed"};
  return {o.group,
          fixed(p99(o.quiet.latency_ms), 1),
          fixed(p99(o.attacked.latency_ms), 1),
          fixed(o.median_ratio, 2) + " (" + std::to_string(o.pairs) + ")",
          thousands(o.attacked.latency_ms.size()),
          fixed(o.attack_cpu_s, 2),
          mb(o.peak_rss),
          fixed(double(o.peak_sockets) / 1e6, 2),
          mb(o.peak_total) + " / " + mb(o.memory_bound),
          o.idle_after_s >= 0 ? fixed(o.idle_after_s, 1) : "> 3",
          fixed(o.sigterm_s, 3),
          thousands(counter(o, "connections_refused_per_address")),
          thousands(counter(o, "connections_reset")),
          thousands(counter(o, "budget_waits")),
          thousands(counter(o, "sliced_answers")),
          verdict(o)};
}

Table class_table() {
  return Table({{"class", false},
                {"rounds"},
                {"answers"},
                {"4xx"},
                {"503"},
                {"other 5xx"},
                {"ended by server"},
                {"of those reset"},
                {"longest ms"},
                {"late"},
                {"smuggled"}});
}

std::vector<std::string> class_row(AttackClass attack, const AttackTally& t) {
  return {attack_class_name(attack),     thousands(t.rounds),        thousands(t.answers), thousands(t.client_errors),
          thousands(t.refused),          thousands(t.server_errors), thousands(t.closed),  thousands(t.resets),
          thousands(t.longest_close_ms), thousands(t.late),          thousands(t.smuggled)};
}

json outcome_json(const AttackOutcome& o) {
  json classes = json::array();
  for (size_t c = 0; c < o.classes.size(); ++c) {
    const AttackTally& t = o.tallies[c];
    classes.push_back({{"class", attack_class_name(o.classes[c])},
                       {"rounds", t.rounds.load()},
                       {"answers", t.answers.load()},
                       {"client_errors", t.client_errors.load()},
                       {"refused", t.refused.load()},
                       {"server_errors", t.server_errors.load()},
                       {"closed", t.closed.load()},
                       {"resets", t.resets.load()},
                       {"longest_close_ms", t.longest_close_ms.load()},
                       {"late", t.late.load()},
                       {"smuggled", t.smuggled.load()}});
  }
  return {{"group", o.group},
          {"error", o.error},
          {"quiet_p99_ms", p99(o.quiet.latency_ms)},
          {"attacked_p99_ms", p99(o.attacked.latency_ms)},
          {"median_ratio", o.median_ratio},
          {"pairs", o.pairs},
          {"answers", o.attacked.latency_ms.size()},
          {"same_mesh", o.same_mesh},
          {"server_cpu_s", o.attack_cpu_s},
          {"quiet_rss_bytes", o.quiet_rss},
          {"peak_rss_bytes", o.peak_rss},
          {"peak_socket_bytes", o.peak_sockets},
          {"peak_total_bytes", o.peak_total},
          {"memory_bound_bytes", o.memory_bound},
          {"idle_after_s", o.idle_after_s},
          {"sigterm_s", o.sigterm_s},
          {"http", o.http},
          {"classes", classes},
          {"bounds", verdict(o)}};
}

}  // namespace

void run_attacks_group(BenchContext& context) {
  std::string section = "## attacks: the HTTP server under one hostile host per class\n\n";
  std::string model;
  AttackSetup setup = attack_setup(context.pmstream_exe, model_pms(context, model),
                                   context.options.quick ? kQuickFrames : kFrames, kTolerance);
  setup.min_attack = std::max({setup.request_timeout, setup.write_timeout}) + kOutlast;
  section += "Model " + model + "; the good client flies a " + std::to_string(setup.path.size()) + "-frame orbit at " +
             fixed(kTolerance, 1) +
             " px; ten attackers per class on four addresses; the "
             "server's default limits and deadlines, `--threads 2 --preload receiver`. The expensive request: " +
             setup.expensive_note + ".\n\n";
  Table groups = group_table(), classes = class_table();
  print_now("\n" + section + groups.header());
  json out = json::array();
  std::string class_text;
  for (const AttackGroup& group : attack_groups()) {
    std::fprintf(stderr, "bench: attacks, %s\n", group.name);
    const AttackOutcome o = run_attack_group(setup, group);
    if (!o.error.empty()) context.failures.push_back(std::string("attacks ") + group.name + ": " + o.error);
    print_now(groups.add_row(group_row(o)));
    for (size_t c = 0; c < o.classes.size(); ++c) classes.add_row(class_row(o.classes[c], o.tallies[c]));
    out.push_back(outcome_json(o));
  }
  section += groups.markdown() + "\nWhat the attackers saw, per class:\n\n" + classes.markdown() + "\n";
  print_now("\n" + classes.markdown());
  write_text_file(context.options.out_dir / "attacks.json", json{{"model", model}, {"groups", out}}.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
