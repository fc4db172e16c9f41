// The headless streaming client: a ClientSession and a ClientMode over a ServerConnection, reconnecting and
// resuming when a connection is lost.
#include <algorithm>
#include <thread>
#include <variant>

#include "client/link.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "client/websocket_link.h"
#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"

namespace pms::client {
namespace {

using Clock = std::chrono::steady_clock;

double milliseconds_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

void add(LinkCounters& total, const LinkCounters& more) {
  total.bytes_up += more.bytes_up;
  total.bytes_down += more.bytes_down;
  total.frames_up += more.frames_up;
  total.frames_down += more.frames_down;
}

// The longest wait between two reconnect attempts: a server back after a long outage is found soon enough.
constexpr std::chrono::seconds kMaxReconnectDelay(8);

// Before reconnect attempt `attempt` (from 1): reconnect_delay, then twice that, and so on, up to
// kMaxReconnectDelay.
std::chrono::milliseconds backoff(const ClientOptions& options, uint32_t attempt) {
  const auto delay = options.reconnect_delay * (1 << std::min<uint32_t>(attempt - 1, 10));
  return std::min<std::chrono::milliseconds>(delay, kMaxReconnectDelay);
}

// Every connection, the first and each reconnect, gets the client's deadlines; the answer timeout is
// also how long a frame may take once it has begun to arrive.
std::unique_ptr<Transport> open_link(const std::string& host, uint16_t port, const ClientOptions& options) {
  LinkOptions link;
  link.connect_timeout = options.connect_timeout;
  link.write_timeout = options.write_timeout;
  link.read_timeout = options.answer_timeout;
  if (!options.websocket_path.empty())
    return std::make_unique<WebSocketLink>(host, port, options.websocket_path, link);
  return std::make_unique<Link>(host, port, link);
}

}  // namespace

StreamingClient::StreamingClient(const std::string& host, uint16_t port, const ClientOptions& options)
    : StreamingClient(open_link(host, port, options), options) {
  host_ = host;
  port_ = port;
}

StreamingClient::StreamingClient(std::unique_ptr<Transport> transport, const ClientOptions& options)
    : options_(options), dag_management_(options.dag, options.dag_management) {
  prepare();
  greet(std::move(transport));
}

StreamingClient::StreamingClient(const std::string& host, uint16_t port, const ClientOptions& options,
                                 const std::string& model)
    : options_(options), host_(host), port_(port), dag_management_(options.dag, options.dag_management) {
  prepare();
  greet(open_link(host, port, options), Greeting::pipelined);
  open(model);
}

StreamingClient::~StreamingClient() = default;

void StreamingClient::prepare() {
  session_.adapt_options = adapt_options_of(options_);
  mode_ = make_client_mode(options_.mode);
  mode_->prepare(session_);
}

void StreamingClient::close_connection() {
  if (!server_) return;
  add(past_, server_->counters());
  server_.reset();
}

void StreamingClient::greet(std::unique_ptr<Transport> transport, Greeting greeting) {
  close_connection();
  server_ = std::make_unique<ServerConnection>(std::move(transport), options_.name, options_.answer_timeout, greeting);
}

protocol::Catalogue StreamingClient::list() { return server_->list(); }

protocol::Open StreamingClient::open_message() const { return open_request(model_, *mode_, session_); }

void StreamingClient::open(const std::string& model) {
  model_ = model;
  const protocol::Open message = open_message();
  session_.on_base(server_->open(message));
  if (protocol::carries_split_records(message.mode)) session_.on_codec(server_->next_codec(session_.context()));
}

void StreamingClient::resume(const std::string& host, uint16_t port) {
  if (!session_.has_model()) fail("resume", "no session to resume: open a model first");
  resume(open_link(host, port, options_));
}

void StreamingClient::resume(std::unique_ptr<Transport> transport) {
  if (!session_.has_model()) fail("resume", "no session to resume: open a model first");
  greet(std::move(transport), Greeting::pipelined);
  open(model_);
}

size_t StreamingClient::request_view(const Camera& camera, const BatchHandler& on_batch, FrameReport& report) {
  const uint32_t frame = ++frame_;
  const Clock::time_point sent = Clock::now();
  server_->send_view(camera, options_.tolerance, frame);
  report.requested = true;
  size_t received = 0;
  for (;;) {
    const protocol::VSplits batch = server_->next_batch(session_.context());
    session_.on_vsplits(batch);
    if (on_batch) on_batch(batch);
    received += batch.splits.size();
    if (batch.frame == frame && batch.final) break;  // earlier VIEWs' batches are applied too
  }
  report.latency_ms = std::max(report.latency_ms, milliseconds_since(sent));
  return received;
}

size_t StreamingClient::request_dag_view(const Camera& camera, FrameReport& report) {
  protocol::DagView request = dag_management_.next(session_);
  request.view = {camera, options_.tolerance, ++frame_};
  last_dag_request_ = request;
  const Clock::time_point sent = Clock::now();
  server_->send(protocol::encode(request));
  report.requested = true;
  size_t received = 0, collapses = 0;
  for (;;) {
    const protocol::DagOps ops = server_->next_dag_ops(session_.context());
    received += session_.apply_dag_ops(ops);
    collapses += ops.collapses.size();
    if (ops.frame == request.view.frame && ops.final) break;
  }
  const double ms = milliseconds_since(sent);
  dag_management_.answered(request.max_ops, ms, collapses, received);
  report.latency_ms = std::max(report.latency_ms, ms);
  return received;
}

FrameReport StreamingClient::frame(const Camera& camera) {
  uint32_t attempts = 0;  // over the whole frame: a server that takes the session and drops it again ends too
  for (;;) {
    try {
      return frame_once(camera);
    } catch (const ConnectionError& lost) {
      if (host_.empty()) throw;
      reconnect(lost.what(), attempts);
    }
  }
}

// Resumes the session on a new connection, waiting longer before each attempt; throws the last reason
// once the attempts are used up.
void StreamingClient::reconnect(std::string reason, uint32_t& attempts) {
  for (;;) {
    if (attempts >= options_.reconnect_attempts) throw ConnectionError(reason);
    ++attempts;
    if (options_.on_reconnect) options_.on_reconnect(reason, attempts);
    std::this_thread::sleep_for(backoff(options_, attempts));
    try {
      resume(host_, port_);
      return;
    } catch (const ConnectionError& e) {
      reason = e.what();
    }
  }
}

FrameReport StreamingClient::frame_once(const Camera& camera) {
  if (!session_.has_model()) fail("stream", "no model open");
  FrameReport report;
  report.frame = frame_ + 1;
  const LinkCounters before = server_->counters();
  mode_->frame(camera, session_, *this, report);
  const LinkCounters after = server_->counters();
  report.up_bytes = after.bytes_up - before.bytes_up;
  report.down_bytes = after.bytes_down - before.bytes_down;
  report.faces = session_.mesh().face_count();
  return report;
}

void StreamingClient::settle(const Camera& camera) {
  frame(camera);
  for (uint32_t round = 1; mode_->answers_are_capped() && round < mode_->rounds_per_view(); ++round) {
    const uint64_t before = session_.mesh().changes();
    frame(camera);
    if (session_.mesh().changes() == before) break;
  }
  mode_->settle(session_);
}

// ---- free-running ----

FreeRunningSession& StreamingClient::free_running() {
  if (!free_) {
    protocol::DagView request = options_.dag;
    request.view.tolerance = options_.tolerance;
    free_ = std::make_unique<FreeRunningSession>(session_, *mode_, request, options_.dag_management);
    free_->set_ahead(options_.ahead_frames);
  }
  return *free_;
}

FrameReport StreamingClient::frame_free_running(const Camera& camera) {
  if (!session_.has_model()) fail("stream", "no model open");
  FreeRunningSession& core = free_running();
  const LinkCounters before = counters();
  if (!server_ && Clock::now() >= resume_due_) try_resume();
  take_arrived();
  FrameReport report;
  const std::vector<uint8_t> request = core.frame(camera, Clock::now(), report);
  if (!request.empty()) {  // the core asks only while a session is open, so server_ is there
    try {
      server_->send(request);
    } catch (const ConnectionError& e) {
      lost(e.what());
    }
  }
  const LinkCounters after = counters();
  report.up_bytes = after.bytes_up - before.bytes_up;
  report.down_bytes = after.bytes_down - before.bytes_down;
  report.in_flight = core.in_flight();  // again: a send that found the connection gone
  report.satisfied = core.satisfied();
  return report;
}

void StreamingClient::take_arrived() {
  if (!server_) return;
  const Clock::time_point until = Clock::now() + options_.apply_budget;
  try {
    while (Clock::now() < until) {
      std::optional<protocol::Frame> frame = server_->poll();
      if (!frame) break;
      free_->on_frame(*frame, Clock::now());
    }
  } catch (const ConnectionError& e) {
    return lost(e.what());  // what arrived before the loss is applied: the Link hands it over first
  }
  if (!free_->opening()) attempts_ = 0;
}

// With the attempts used up, the reason is the frame's error; otherwise the next attempt is due after the
// backoff, and frames go on with the mesh held meanwhile.
void StreamingClient::lost(std::string reason) {
  if (host_.empty() || attempts_ >= options_.reconnect_attempts) throw ConnectionError(reason);
  close_connection();
  free_->restart();
  lost_reason_ = std::move(reason);
  resume_due_ = Clock::now() + backoff(options_, attempts_ + 1);
}

// HELLO and OPEN (the front held) go out together; BASE and CODEC are taken by later frames as they come.
void StreamingClient::try_resume() {
  ++attempts_;
  if (options_.on_reconnect) options_.on_reconnect(lost_reason_, attempts_);
  try {
    greet(open_link(host_, port_, options_), Greeting::pipelined);
    server_->send_open(open_message());
  } catch (const ConnectionError& e) {
    lost(e.what());
  }
}

void StreamingClient::await_answers() {
  try {
    while (server_ && (free_->in_flight() > 0 || free_->opening())) free_->on_frame(server_->next(), Clock::now());
  } catch (const ConnectionError& e) {
    lost(e.what());
  }
}

void StreamingClient::settle_free_running(const Camera& camera) {
  for (;;) {
    const FrameReport report = frame_free_running(camera);
    if (!server_) {  // settling may wait: the backoff's delay, then the attempt
      std::this_thread::sleep_until(resume_due_);
      continue;
    }
    if (!report.requested && report.in_flight == 0 && !free_->opening()) break;
    await_answers();
  }
  mode_->settle(session_);
}

LinkCounters StreamingClient::counters() const {
  LinkCounters total = past_;
  if (server_) add(total, server_->counters());
  return total;
}

}  // namespace pms::client
