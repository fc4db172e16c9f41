#include "client/sender_driven_client.h"

#include "spm/adapt.h"

namespace pms::client {
namespace {

// Adapts to the view set with what the hierarchy holds; true when the front needs packets it lacks.
bool adapt_with_held(SelectiveRefinement& refinement) {
  FrameStats stats = refinement.adapt();
  // Without a cap one adapt() reaches the view's mesh for what is known; extra passes only finish
  // collapses that waited for a geomorph. Bounded, whatever the loop does.
  for (int pass = 0; pass < 64 && !stats.capped && stats.ops() > 0 && refinement.missing().empty(); ++pass)
    stats = refinement.adapt();
  return refinement.lacks_packets();
}

}  // namespace

void SenderDrivenClient::frame(const Camera& camera, ClientSession& session, ViewRequests& server,
                               FrameReport& report) {
  SelectiveRefinement& refinement = session.refinement();
  refinement.set_view(session.view_params(camera));
  for (uint32_t round = 0; round < kRounds; ++round) {
    if (!adapt_with_held(refinement)) break;
    const size_t received = server.request_view(camera, {}, report);  // attaching them is all it takes
    report.vsplits += received;
    if (received == 0) break;  // the server has nothing more for this view
  }
}

bool SenderDrivenClient::adapt(const Camera& camera, ClientSession& session) {
  SelectiveRefinement& refinement = session.refinement();
  refinement.set_view(session.view_params(camera));
  // One pass a displayed frame: the next frame goes on from here, so the extra passes the blocking frame
  // makes (collapses that waited for a geomorph, parents their children's collapses left unwanted) happen
  // on the next frames. Until one finds nothing to do, the viewer is in_motion() (SelectiveRefinement::at_rest).
  refinement.adapt();
  return refinement.lacks_packets();
}

void SenderDrivenClient::settle(ClientSession& session) { session.refinement().converge(); }

}  // namespace pms::client
