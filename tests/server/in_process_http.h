// An HTTP transport that is not a socket: each GET is answered in this process by the server's own routes
// over a real Catalogue (server::route, which the HTTP server calls for every request), and only when the
// test says so. While held, poll() answers nothing, so a frame returns with its GETs outstanding with no
// proxy and no clock; wait() answers the oldest GET (a server answering the client that waits for it).
// It shows the HTTP clients run over any client::HttpTransport, as the browser's fetch will be.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "client/http_transport.h"
#include "server/catalogue.h"
#include "server/limits.h"

namespace pms::test {

class InProcessHttp : public client::HttpTransport {
 public:
  explicit InProcessHttp(std::shared_ptr<const server::Catalogue> catalogue, uint32_t in_flight = 4);

  void post(const std::string& target) override;
  void poll() override;  // answers every pending GET, in order, unless held
  std::optional<client::HttpAnswer> take() override;
  void wait() override;  // answers the oldest pending GET, held or not
  size_t pending() const override { return posted_.size(); }
  size_t room() const override { return in_flight_ - posted_.size(); }
  // Bytes up: the request lines; down: the bodies (no headers travel in process).
  const client::HttpCounters& counters() const override { return counters_; }

  void hold(bool on) { held_ = on; }

 private:
  void answer_oldest();

  std::shared_ptr<const server::Catalogue> catalogue_;
  server::HttpLimits limits_;
  uint32_t in_flight_;
  bool held_ = false;
  struct Posted {
    std::string target;
    std::chrono::steady_clock::time_point at;
  };
  std::deque<Posted> posted_;
  std::deque<client::HttpAnswer> arrived_;
  client::HttpCounters counters_;
};

// A client of type Client (ReceiverClient, MultilevelClient) over an InProcessHttp whose handle the test
// keeps, to hold and release answers; `model` open.
template <class Client, class Options>
struct OverInProcess {
  OverInProcess(std::shared_ptr<const server::Catalogue> catalogue, const std::string& model, const Options& options,
                bool free_running) {
    auto owned = std::make_unique<InProcessHttp>(std::move(catalogue));
    http = owned.get();
    Options paced = options;
    paced.free_running = free_running;
    client = std::make_unique<Client>(std::move(owned), paced);
    client->open(model);
  }
  InProcessHttp* http;  // owned by the client
  std::unique_ptr<Client> client;
};

}  // namespace pms::test
