// The Viewer of the session modes (sender, sender-plain, vi, dag): a StreamingClient over TCP, which
// resumes its session on a new connection when one is lost (ClientOptions::reconnect_attempts). Lock-step
// frames are the blocking StreamingClient::frame; free-running ones StreamingClient::frame_free_running,
// which never waits for the network (free_running_session.h).
#pragma once
#include <string>

#include "client/streaming_client.h"
#include "client/viewer.h"

namespace pms::client {

class SessionViewer : public Viewer {
 public:
  // `server` is HOST:PORT (TCP) or ws://HOST:PORT/ws (the HTTP port's WebSocket); pms::Error naming --server
  // otherwise.
  SessionViewer(const std::string& server, const ClientOptions& options, Pacing pacing, const std::string& model);

  ViewerReport frame_view(const Camera& camera) override;
  void settle(const Camera& camera) override;
  Mesh mesh() const override;
  ViewParams view_params(const Camera& camera) const override;
  const char* received_unit() const override { return "vsplits"; }
  uint64_t received_total() const override;
  uint64_t up_bytes() const override { return client_->counters().bytes_up; }
  uint64_t down_bytes() const override { return client_->counters().bytes_down; }
  nlohmann::json totals() const override;

  StreamingClient& client() { return *client_; }

 protected:
  const SelectiveRefinement* refinement() const override { return &client_->session().refinement(); }

 private:
  std::unique_ptr<StreamingClient> client_;
  Pacing pacing_;
  bool dag_;  // the DAG mode: its lock-step frames report the mode and N they asked with
};

// HOST:PORT split; pms::Error naming `where` for anything else.
void split_host_port(const std::string& text, std::string& host, uint16_t& port, const std::string& where);

}  // namespace pms::client
