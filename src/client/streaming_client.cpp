// The headless streaming client: ClientSession over a Link. A frame adapts the mesh to the camera and,
// only when the front needs vsplit packets the client does not have (kim-lee-kobbelt §5.3: never for a
// real leaf), sends VIEW and applies the answer's batches as they arrive.
#include <algorithm>
#include <thread>
#include <variant>

#include "client/client.h"
#include "common/error.h"

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

// Every connection, the first and each reconnect, gets the client's deadlines; the answer timeout is
// also how long a frame may take once it has begun to arrive.
std::unique_ptr<Link> open_link(const std::string& host, uint16_t port, const ClientOptions& options) {
  LinkOptions link;
  link.connect_timeout = options.connect_timeout;
  link.write_timeout = options.write_timeout;
  link.read_timeout = options.answer_timeout;
  return std::make_unique<Link>(host, port, link);
}

}  // namespace

StreamingClient::StreamingClient(const std::string& host, uint16_t port, const ClientOptions& options)
    : StreamingClient(open_link(host, port, options), options) {
  host_ = host;
  port_ = port;
}

StreamingClient::StreamingClient(std::unique_ptr<Transport> transport, const ClientOptions& options)
    : options_(options) {
  session_.adapt_options.tolerance = options.tolerance;
  session_.adapt_options.morph_frames = options.morph_frames;
  session_.adapt_options.max_ops = options.max_ops;
  session_.mode = options.mode;
  greet(std::move(transport));
}

StreamingClient::~StreamingClient() = default;

void StreamingClient::greet(std::unique_ptr<Transport> transport) {
  if (link_) {
    add(past_, link_->counters());
    link_.reset();
  }
  link_ = std::move(transport);
  link_->send(protocol::encode(protocol::Hello{protocol::kProtocolVersion, options_.name}));
  const protocol::Frame frame = expect(protocol::MessageType::hello_ok);
  protocol::decode_hello_ok(frame.payload);
}

// The next frame, which must be of `type`; an ERROR from the server becomes a pms::Error with its text.
protocol::Frame StreamingClient::expect(protocol::MessageType type) {
  std::optional<protocol::Frame> frame = link_->receive(options_.answer_timeout);
  if (!frame) throw ConnectionError("server: no answer within " + std::to_string(options_.answer_timeout.count()) + " ms");
  if (frame->type == protocol::MessageType::error) {
    const protocol::ErrorMessage e = protocol::decode_error(frame->payload);
    fail("server", protocol::to_string(e.code) + ": " + e.text);
  }
  if (frame->type != type)
    fail("server", "expected " + protocol::to_string(type) + ", got " + protocol::to_string(frame->type));
  return std::move(*frame);
}

protocol::Catalogue StreamingClient::list() {
  link_->send(protocol::encode(protocol::List{}));
  return protocol::decode_catalogue(expect(protocol::MessageType::catalogue).payload);
}

void StreamingClient::open(const std::string& model) {
  model_ = model;
  protocol::Open message{model, {}, options_.mode};
  if (session_.has_model()) message.resume = session_.known_leaves();
  link_->send(protocol::encode(message));
  session_.on_base(protocol::decode_base(expect(protocol::MessageType::base).payload));
}

void StreamingClient::resume(const std::string& host, uint16_t port) {
  if (!session_.has_model()) fail("resume", "no session to resume: open a model first");
  resume(open_link(host, port, options_));
}

void StreamingClient::resume(std::unique_ptr<Transport> transport) {
  if (!session_.has_model()) fail("resume", "no session to resume: open a model first");
  greet(std::move(transport));
  open(model_);
}

// Sends VIEW for the camera and applies every batch of its answer; returns the packets received.
size_t StreamingClient::request(const Camera& camera, FrameReport& report) {
  const uint32_t frame = ++frame_;
  const Clock::time_point sent = Clock::now();
  link_->send(protocol::encode(protocol::View{camera, options_.tolerance, frame}));
  report.requested = true;
  size_t received = 0;
  for (;;) {
    const protocol::Frame message = expect(protocol::MessageType::vsplits);
    const protocol::VSplits batch = protocol::decode_vsplits(message.payload, session_.context());
    session_.on_vsplits(batch);
    received += batch.splits.size();
    if (batch.frame == frame && batch.final) break;  // earlier VIEWs' batches are applied too
  }
  report.latency_ms = std::max(report.latency_ms, milliseconds_since(sent));
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
    const auto delay = options_.reconnect_delay * (1 << std::min<uint32_t>(attempts - 1, 10));
    std::this_thread::sleep_for(std::min<std::chrono::milliseconds>(delay, std::chrono::seconds(8)));
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
  const LinkCounters before = link_->counters();
  if (options_.mode == protocol::StreamMode::view_independent) {
    report.vsplits = request(camera, report);  // the splits are applied as they arrive
  } else {
    adapt_and_request(camera, report);
  }
  const LinkCounters after = link_->counters();
  report.up_bytes = after.bytes_up - before.bytes_up;
  report.down_bytes = after.bytes_down - before.bytes_down;
  report.faces = session_.mesh().face_count();
  return report;
}

void StreamingClient::adapt_and_request(const Camera& camera, FrameReport& report) {
  SelectiveRefinement& refinement = session_.refinement();
  refinement.set_view(session_.view_params(camera));
  // The server answers a VIEW with every split the view wants over its front, so one request per frame
  // normally suffices; a second only if the answer was cut short.
  for (int round = 0; round < 4; ++round) {
    FrameStats stats = refinement.adapt();
    // Without a cap one adapt() reaches the view's mesh for what is known; extra passes only finish
    // collapses that waited for a geomorph. Bounded, whatever the loop does.
    for (int pass = 0; pass < 64 && !stats.capped && stats.ops() > 0 && refinement.missing().empty(); ++pass)
      stats = refinement.adapt();
    if (refinement.missing().empty()) break;
    const size_t received = request(camera, report);
    report.vsplits += received;
    if (received == 0) break;  // the server has nothing more for this view
  }
}

void StreamingClient::settle(const Camera& camera) {
  frame(camera);
  if (options_.mode == protocol::StreamMode::sender_driven) session_.refinement().converge();
}

LinkCounters StreamingClient::counters() const {
  LinkCounters total = past_;
  if (link_) add(total, link_->counters());
  return total;
}

}  // namespace pms::client
