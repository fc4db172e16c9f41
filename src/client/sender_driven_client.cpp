#include "client/sender_driven_client.h"

#include "spm/adapt.h"

namespace pms::client {

void SenderDrivenClient::frame(const Camera& camera, ClientSession& session, ViewRequests& server,
                               FrameReport& report) {
  SelectiveRefinement& refinement = session.refinement();
  refinement.set_view(session.view_params(camera));
  // The server answers a VIEW with every split the view wants over its front, so one request per frame
  // normally suffices; a second only if the answer was cut short.
  for (int round = 0; round < 4; ++round) {
    FrameStats stats = refinement.adapt();
    // Without a cap one adapt() reaches the view's mesh for what is known; extra passes only finish
    // collapses that waited for a geomorph. Bounded, whatever the loop does.
    for (int pass = 0; pass < 64 && !stats.capped && stats.ops() > 0 && refinement.missing().empty(); ++pass)
      stats = refinement.adapt();
    if (refinement.missing().empty()) break;
    const size_t received = server.request_view(camera, {}, report);  // attaching them is all it takes
    report.vsplits += received;
    if (received == 0) break;  // the server has nothing more for this view
  }
}

void SenderDrivenClient::settle(ClientSession& session) { session.refinement().converge(); }

}  // namespace pms::client
