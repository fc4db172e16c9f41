// zheng-chan 2006 §4 (the client sets MANAGE-TRAVERSAL's mode and N) and §7 (N chosen at run time).
#include "client/dag_management.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace pms::client {
namespace {

// N aims a frame at this share of the budget, so that one frame's noise stays within it.
constexpr double kHeadroom = 0.85;
// A frame over budget halves N at most, so one slow frame (a busy machine) does not throw the rest away.
constexpr double kMaxShrink = 0.5;
// A frame cut short by N under budget at most doubles it.
constexpr double kMaxGrowth = 2;

uint32_t clamp_ops(double n) {
  return uint32_t(std::clamp(n, double(DagManagement::kMinOps), double(protocol::kMaxDagOps)));
}

}  // namespace

bool dag_free_mode_fits(uint64_t triangles, uint64_t budget, uint32_t max_ops, uint32_t requests) {
  return triangles + 2 * uint64_t(max_ops) * requests <= budget;
}

DagManagement::DagManagement(const protocol::DagView& configured, const DagManagementOptions& options)
    : configured_(configured), options_(options), max_ops_(configured.max_ops) {
  if (options.automatic && configured.budget == 0) fail("--management auto", "needs a triangle budget (--budget)");
  if (!(options.frame_budget_ms >= 0) || !std::isfinite(options.frame_budget_ms))
    fail("--frame-budget-ms", "must be a finite time ≥ 0");
}

bool dag_answer_converges(const ClientSession& session) {
  return session.mesh().vertex_count() == session.base().positions.size() / 3;
}

protocol::DagView DagManagement::next(const ClientSession& session, uint32_t in_flight) const {
  protocol::DagView request = configured_;
  request.max_ops = max_ops_;
  if (!options_.automatic) return request;
  // §4: "the client knows when to set the traversal mode to BUDGET-MODE since the maximum number of
  // possible new triangles is predictable to the client due to the mesh-change constraint".
  // Constant-time's N bounds the nodes it evaluates, not the splits their needs force: nothing bounds what
  // its answer may add, so it stays in BUDGET mode.
  const uint32_t n = dag_answer_converges(session) ? protocol::kMaxDagOps : max_ops_;
  const bool free = configured_.traversal != DagTraversal::constant_time &&
                    dag_free_mode_fits(session.mesh().face_count(), configured_.budget, n, in_flight + 1);
  request.management = free ? DagMode::free : DagMode::budget;
  request.budget = free ? 0 : configured_.budget;
  return request;
}

// Proportional: the time of an answer grows with its operations (plus costs N does not change, such as the
// priority traversal's evaluation of the whole front), so N scales by the time left over the time taken.
// An answer N did not cut short says nothing about a larger N, and keeps it unless it was over budget. Only
// the second of two answers over budget in a row shrinks N, by the lesser overrun: one slow answer is as
// often the machine (a time slice lost to another process) as the operations.
void DagManagement::answered(uint32_t asked, double ms, uint64_t collapses, uint64_t splits) {
  if (!(options_.frame_budget_ms > 0) || !(ms > 0)) return;
  const double target = kHeadroom * options_.frame_budget_ms;
  const uint64_t done = std::max(collapses, splits);
  const double over_before = over_ms_;
  over_ms_ = ms > target ? ms : 0;
  if (ms > target) {
    if (over_before == 0) return;
    const double scaled = double(std::min<uint64_t>(done, asked)) * target / std::min(ms, over_before);
    max_ops_ = std::min(max_ops_, clamp_ops(std::max(scaled, kMaxShrink * max_ops_)));
  } else if (done >= asked) {
    max_ops_ = std::max(max_ops_, clamp_ops(max_ops_ * std::min(kMaxGrowth, target / ms)));
  }
}

}  // namespace pms::client
