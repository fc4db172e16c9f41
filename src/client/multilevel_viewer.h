// The Viewer of the multilevel mode (gueziec et al. 1999): a MultilevelClient over HTTP, free-running
// (MultilevelOptions::free_running) or in lock-step as the pacing says. What it receives is levels, not
// splits (received_unit()).
#pragma once
#include <string>

#include "client/multilevel_client.h"
#include "client/viewer.h"

namespace pms::client {

class MultilevelViewer : public Viewer {
 public:
  // `server` is http://HOST:PORT[/prefix]; pms::Error naming --server otherwise.
  MultilevelViewer(const std::string& server, const MultilevelOptions& options, Pacing pacing,
                   const std::string& model);
  // The browser's: free-running over `http`; the model opens as answers come, and frames report `opening`
  // until it has. settle() needs a transport that can wait.
  MultilevelViewer(std::unique_ptr<HttpTransport> http, const MultilevelOptions& options, const std::string& model);

  ViewerReport frame_view(const Camera& camera) override;
  void retune(const ViewerTuning& tuning) override;  // tolerance, LOD budget, geomorphs
  void settle(const Camera& camera) override { client_.settle(camera); }
  Mesh mesh() const override { return client_.opened() ? client_.current_mesh() : Mesh{}; }
  ViewParams view_params(const Camera& camera) const override { return client_.view_params(camera); }
  const char* received_unit() const override { return "levels"; }
  uint64_t received_total() const override { return client_.arrivals().size(); }
  uint64_t up_bytes() const override { return client_.counters().bytes_up; }
  uint64_t down_bytes() const override { return client_.counters().bytes_down; }
  nlohmann::json totals() const override;
  // A LOD switch's geomorph under way, or the last camera's LOD not yet shown.
  bool in_motion() const override { return client_.in_motion(); }

  MultilevelClient& client() { return client_; }

 private:
  MultilevelClient client_;
  MultilevelOptions options_;
};

// `options` with free_running set as `pacing` says.
MultilevelOptions paced(MultilevelOptions options, Pacing pacing);

}  // namespace pms::client
