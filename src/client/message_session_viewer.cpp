#include "client/message_session_viewer.h"

#include <chrono>
#include <utility>

#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/stream_mode.h"

namespace pms::client {
namespace {

using Clock = std::chrono::steady_clock;

ClientSession prepared_session(const ClientOptions& options, const ClientMode& mode) {
  ClientSession session;
  session.adapt_options = adapt_options_of(options);
  mode.prepare(session);
  return session;
}

protocol::DagView request_of(const ClientOptions& options) {
  protocol::DagView request = options.dag;
  request.view.tolerance = options.tolerance;
  return request;
}

}  // namespace

MessageSessionViewer::MessageSessionViewer(const ClientOptions& options, const std::string& model)
    : options_(options),
      model_(model),
      mode_(make_client_mode(options.mode)),
      session_(prepared_session(options, *mode_)) {
  free_ = std::make_unique<FreeRunningSession>(session_, *mode_, request_of(options));
  free_->set_ahead(options.ahead_frames);
  free_->restart();  // nothing is asked before BASE
}

MessageSessionViewer::~MessageSessionViewer() = default;

void MessageSessionViewer::queue(std::vector<uint8_t> frame) {
  counters_.bytes_up += frame.size();
  ++counters_.frames_up;
  outgoing_.push_back(std::move(frame));
}

void MessageSessionViewer::connected() {
  if (connected_) disconnected();
  connected_ = true;
  queue(hello_frame(options_.name));
  queue(protocol::encode(open_request(model_, *mode_, session_)));
}

void MessageSessionViewer::disconnected() {
  for (protocol::Frame frame; !reader_.failed() && reader_.next(frame);) apply(std::move(frame));
  connected_ = false;
  outgoing_.clear();
  greeting_ = {};
  reader_ = protocol::FrameReader();
  free_->restart();
}

void MessageSessionViewer::on_bytes(std::span<const uint8_t> bytes) {
  if (!connected_) return;  // a closed socket's last bytes: the resumed session starts afresh
  counters_.bytes_down += bytes.size();
  reader_.feed(bytes);
}

std::vector<std::vector<uint8_t>> MessageSessionViewer::take_outgoing() { return std::exchange(outgoing_, {}); }

void MessageSessionViewer::apply(protocol::Frame&& frame) {
  ++counters_.frames_down;
  if (std::optional<protocol::Frame> taken = greeting_.take(std::move(frame))) free_->on_frame(*taken, Clock::now());
}

void MessageSessionViewer::take_arrived() {
  const Clock::time_point until = Clock::now() + options_.apply_budget;
  for (protocol::Frame frame; reader_.next(frame);) {
    apply(std::move(frame));
    if (Clock::now() >= until) break;
  }
}

ViewerReport MessageSessionViewer::frame_view(const Camera& camera) {
  const LinkCounters before = counters_;
  take_arrived();
  if (!session_.has_model()) return opening_report();
  FrameReport r;
  std::vector<uint8_t> request = free_->frame(camera, Clock::now(), r);
  if (!request.empty()) queue(std::move(request));  // the core asks only while a session is open
  ViewerReport report;
  report.frame = r.frame;
  report.faces = r.faces;
  report.vertices = session_.mesh().vertex_count();
  report.received = r.vsplits;
  report.up_bytes = counters_.bytes_up - before.bytes_up;
  report.down_bytes = counters_.bytes_down - before.bytes_down;
  report.in_flight = free_->in_flight();
  report.latency_ms = r.latency_ms;
  report.satisfied = free_->satisfied();
  report.opening = free_->opening();
  return report;
}

void MessageSessionViewer::retune(const ViewerTuning& tuning) {
  if (tuning.tolerance) options_.tolerance = *tuning.tolerance;
  if (tuning.morph_frames && options_.mode == protocol::StreamMode::sender_driven)
    options_.morph_frames = *tuning.morph_frames;
  if (tuning.dag_traversal) options_.dag.traversal = *tuning.dag_traversal;
  if (tuning.dag_budget) {
    options_.dag.budget = *tuning.dag_budget;
    options_.dag.management = options_.dag.budget ? DagMode::budget : DagMode::free;
  }
  if (tuning.dag_max_ops) options_.dag.max_ops = *tuning.dag_max_ops;
  AdaptOptions adapt = session_.adapt_options;
  adapt.tolerance = options_.tolerance;
  adapt.morph_frames = options_.morph_frames;
  session_.set_adapt_options(adapt);
  free_->set_request(request_of(options_));
}

void MessageSessionViewer::settle(const Camera& camera) {
  (void)camera;
  fail("settle", "this viewer cannot wait for the network: frame() until settled()");
}

bool MessageSessionViewer::settled() const {
  return session_.has_model() && connected_ && free_->satisfied() && reader_.ready() == 0 && outgoing_.empty() &&
         !in_motion();
}

Mesh MessageSessionViewer::mesh() const { return session_.has_model() ? current_mesh(session_.refinement()) : Mesh{}; }

nlohmann::json MessageSessionViewer::totals() const {
  return {{"total_up_payload_bytes", counters_.payload_up()}, {"total_down_payload_bytes", counters_.payload_down()}};
}

}  // namespace pms::client
