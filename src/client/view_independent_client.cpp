#include "client/view_independent_client.h"

#include "common/error.h"
#include "pm/split_record.h"

namespace pms::client {

void ViewIndependentClient::frame(const Camera& camera, ClientSession& session, ViewRequests& server,
                                  FrameReport& report) {
  report.vsplits = server.request_view(camera, [&session](const protocol::VSplits& batch) {
    // PM order: a split's ancestors and cut-vertex splits came earlier, so it can be made now.
    for (const SplitRecord& split : batch.splits)
      if (!session.mesh().vsplit(session.hierarchy().find(split.vs)).done)
        fail("VSPLITS", "split of " + to_string(split.vs) + " arrived before a split it needs (not in PM order)");
  }, report);
}

}  // namespace pms::client
