// The one place a viewer's mode is chosen by name: a new mode adds its line here and its own files. Native:
// the viewers it makes own their connections (TCP Link, HttpConnection).
#include "client/multilevel_viewer.h"
#include "client/receiver_viewer.h"
#include "client/session_viewer.h"
#include "client/viewer.h"
#include "common/error.h"
#include "protocol/stream_mode.h"

namespace pms::client {

std::unique_ptr<Viewer> open_viewer(const ViewerOptions& options, const std::string& model) {
  if (options.mode == "receiver")
    return std::make_unique<ReceiverViewer>(options.server, options.receiver, options.pacing, model);
  if (options.mode == "multilevel")
    return std::make_unique<MultilevelViewer>(options.server, options.multilevel, options.pacing, model);
  const std::optional<protocol::StreamMode> mode = protocol::mode_named(options.mode);
  if (!mode) fail("--mode", "'" + options.mode + "': this build streams in the modes " + viewer_mode_names());
  ClientOptions session = options.session;
  session.mode = *mode;
  // The other session modes make splits as they come (or as the server's cut says): nothing to blend.
  if (*mode != protocol::StreamMode::sender_driven) session.morph_frames = 0;
  return std::make_unique<SessionViewer>(options.server, session, options.pacing, model);
}

}  // namespace pms::client
