// The Viewer of the receiver-driven mode (cheng-ooi 2008): a ReceiverClient over HTTP, its frames
// free-running (ReceiverOptions::free_running) or in lock-step as the pacing says. The URL constructor is
// the native build's (native_http_clients.cpp); the browser's hands in its fetch transport.
#pragma once
#include <string>

#include "client/receiver_client.h"
#include "client/viewer.h"

namespace pms::client {

class ReceiverViewer : public Viewer {
 public:
  // `server` is http://HOST:PORT[/prefix]; pms::Error naming --server otherwise.
  ReceiverViewer(const std::string& server, const ReceiverOptions& options, Pacing pacing, const std::string& model);
  // The browser's: free-running over `http`, ranking by `importance`; the model opens as answers come, and
  // frames report `opening` until it has. settle() needs a transport that can wait.
  ReceiverViewer(std::unique_ptr<HttpTransport> http, std::unique_ptr<ImportanceSource> importance,
                 const ReceiverOptions& options, const std::string& model);

  ViewerReport frame_view(const Camera& camera) override;
  void retune(const ViewerTuning& tuning) override;  // tolerance, geomorphs, prefetch, the idle fetch
  void settle(const Camera& camera) override { client_.settle(camera); }
  Mesh mesh() const override;
  ViewParams view_params(const Camera& camera) const override;
  const char* received_unit() const override { return "vsplits"; }
  uint64_t received_total() const override;
  uint64_t up_bytes() const override { return client_.counters().bytes_up; }
  uint64_t down_bytes() const override { return client_.counters().bytes_down; }
  nlohmann::json totals() const override;

  ReceiverClient& client() { return client_; }

 protected:
  const SelectiveRefinement* refinement() const override {
    return client_.session().has_model() ? &client_.session().refinement() : nullptr;
  }

 private:
  mutable ReceiverClient client_;
  ReceiverOptions options_;
  uint64_t unsatisfied_ = 0;  // frames that ended with the view wanting more
};

// `options` with free_running set as `pacing` says.
ReceiverOptions paced(ReceiverOptions options, Pacing pacing);

}  // namespace pms::client
