#include "client/dag_client.h"

namespace pms::client {

// One DAG_VIEW a frame: the client cannot tell on its own whether its mesh suits the view.
void DagClient::frame(const Camera& camera, ClientSession&, ViewRequests& server, FrameReport& report) {
  report.vsplits = server.request_dag_view(camera, report);
}

}  // namespace pms::client
