// The HTTP clients and their viewers as the native build makes them: over an HttpConnection (Boost.Beast) and, for the
// receiver-driven one, ranking with the software renderer. Apart from the clients' own files, which the
// browser build compiles without asio or the renderer (CMakeLists.txt, pms_browser_core).
#include <memory>
#include <utility>

#include "client/http_connection.h"
#include "client/multilevel_client.h"
#include "client/multilevel_viewer.h"
#include "client/receiver_client.h"
#include "client/receiver_viewer.h"
#include "client/screen_importance.h"

namespace pms::client {

// The ranking renders on the caller's thread alone (RenderOptions{1}).
ReceiverClient::ReceiverClient(std::unique_ptr<HttpTransport> http, const ReceiverOptions& options)
    : ReceiverClient(std::move(http), std::make_unique<ScreenImportance>(RenderOptions{1}), options) {}

ReceiverClient::ReceiverClient(const HttpUrl& server, const ReceiverOptions& options)
    : ReceiverClient(std::make_unique<HttpConnection>(server, options.http), options) {}

MultilevelClient::MultilevelClient(const HttpUrl& server, const MultilevelOptions& options)
    : MultilevelClient(std::make_unique<HttpConnection>(server, options.http), options) {}

ReceiverViewer::ReceiverViewer(const std::string& server, const ReceiverOptions& options, Pacing pacing,
                               const std::string& model)
    : client_(parse_http_url(server), paced(options, pacing)), options_(paced(options, pacing)) {
  client_.open(model);
}

MultilevelViewer::MultilevelViewer(const std::string& server, const MultilevelOptions& options, Pacing pacing,
                                   const std::string& model)
    : client_(parse_http_url(server), paced(options, pacing)), options_(paced(options, pacing)) {
  client_.open(model);
}

}  // namespace pms::client
