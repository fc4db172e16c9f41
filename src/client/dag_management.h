// The client's half of MANAGE-TRAVERSAL (zheng-chan 2006 §4, Fig. 2): "the arguments N and mode ... are set
// by the client according to the current condition of its selectively refined mesh". The mode: FREE while
// the mesh plus the most N splits can add stays within the triangle budget, BUDGET once it may not (the
// client can tell, since each vsplit adds at most two triangles and N bounds an answer's splits; not so for
// the constant-time traversal, whose N bounds evaluations, which stays in BUDGET mode). N: beyond the paper (its §7's future work),
// chosen per frame so that a frame's answer (DAG_VIEW sent to its last operation applied) fits a frame-time
// budget. The client decides both because only it sees its whole frame, the server's traversal, the link and
// its own applying together; and N and the mode are already DAG_VIEW's fields, so the wire is unchanged.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>

#include "client/client_session.h"
#include "protocol/client_messages.h"

namespace pms::client {

struct DagManagementOptions {
  // true: FREE or BUDGET per request by the paper's rule, with the configured request's budget (> 0);
  // false: the configured request's mode on every request.
  bool automatic = false;
  // > 0: N per request from the time the last answers took (lock-step: an answer is a frame's whole wait);
  // 0: the configured request's N on every request.
  double frame_budget_ms = 0;
};

class DagManagement {
 public:
  DagManagement(const protocol::DagView& configured, const DagManagementOptions& options);

  // The next request's mode, budget and N (its view left as configured) for `session`'s mesh, with
  // `in_flight` earlier requests not answered yet (each may still add up to 2 N triangles).
  protocol::DagView next(const ClientSession& session, uint32_t in_flight = 0) const;
  // An answer to a request with N = `asked` came in full: `ms` from sending it to its last operation
  // applied, with `collapses` and `splits` operations. Only with a frame budget does this change N: it
  // shrinks after two answers in a row over 85 % of the budget (at most halving), grows after one cut short
  // by N under it (at most doubling).
  void answered(uint32_t asked, double ms, uint64_t collapses, uint64_t splits);

  uint32_t max_ops() const { return max_ops_; }
  const DagManagementOptions& options() const { return options_; }
  const protocol::DagView& configured() const { return configured_; }  // what every request carries

  // N never drops below this: a frame over budget with few operations is over on fixed costs N cannot cut.
  static constexpr uint32_t kMinOps = 8;

 private:
  protocol::DagView configured_;
  DagManagementOptions options_;
  uint32_t max_ops_;
  double over_ms_ = 0;  // the last answer's time when it ran over the budget's target, else 0
};

// Whether the server answers `session`'s next DAG_VIEW with the converged cut of its view rather than N
// operations: while its mesh holds no split (the session's first view, or a resume from the base mesh;
// docs/internals.md, "The DAG mode"). Such an answer may add up to 2 kMaxDagOps triangles.
bool dag_answer_converges(const ClientSession& session);

// Whether a request for a mesh of `triangles` may go out in FREE mode under `budget`: the paper's rule, the
// mesh plus two triangles for each split the requests (`requests` of N = `max_ops`) may bring.
bool dag_free_mode_fits(uint64_t triangles, uint64_t budget, uint32_t max_ops, uint32_t requests);

}  // namespace pms::client
