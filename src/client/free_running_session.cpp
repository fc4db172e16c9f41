#include "client/free_running_session.h"

#include "common/camera.h"
#include "common/error.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"

namespace pms::client {
namespace {

bool same(const float (&a)[3], const float (&b)[3]) { return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; }

bool same_camera(const Camera& a, const Camera& b) {
  return same(a.eye, b.eye) && same(a.target, b.target) && same(a.up, b.up) && a.fovy_deg == b.fovy_deg &&
         a.width == b.width && a.height == b.height;
}

}  // namespace

// A frame budget is lock-step's: free-running, an answer's time is mostly the link's, which N does not set.
FreeRunningSession::FreeRunningSession(ClientSession& session, ClientMode& mode, const protocol::DagView& request,
                                       const DagManagementOptions& management)
    : session_(session), mode_(mode), management_(request, {management.automatic, 0}) {}

void FreeRunningSession::on_frame(const protocol::Frame& frame, Clock::time_point now) {
  switch (frame.type) {
    case protocol::MessageType::base:
      return on_base(frame);
    case protocol::MessageType::codec:
      if (!codec_due_) fail("server", "CODEC without a BASE before it");
      session_.on_codec(protocol::decode_codec(frame.payload, session_.context()));
      codec_due_ = opening_ = false;
      return;
    case protocol::MessageType::vsplits: {
      const protocol::VSplits batch = protocol::decode_vsplits(frame.payload, session_.context());
      session_.on_vsplits(batch);
      mode_.on_batch(batch, session_);
      if (batch.ahead) {  // answers no VIEW
        if (ahead_frames_ == 0) fail("server", "VSPLITS sent ahead to a client that sent no AHEAD");
        ahead_splits_ += batch.splits.size();
        splits_ += batch.splits.size();
        return;
      }
      return received(batch.splits.size(), batch.splits.size(), batch.frame, batch.final, now);
    }
    case protocol::MessageType::dag_ops: {
      const protocol::DagOps ops = protocol::decode_dag_ops(frame.payload, session_.context());
      const size_t splits = session_.apply_dag_ops(ops);
      return received(splits, splits + ops.collapses.size(), ops.frame, ops.final, now);
    }
    default:
      fail("server", "unexpected " + protocol::to_string(frame.type) + " in a streaming session");
  }
}

void FreeRunningSession::on_base(const protocol::Frame& frame) {
  session_.on_base(protocol::decode_base(frame.payload));  // a resumed session's: the model held
  codec_due_ = protocol::carries_split_records(mode_.wire_mode());
  opening_ = codec_due_;
}

void FreeRunningSession::received(uint64_t splits, uint64_t operations, uint32_t number, bool final,
                                  Clock::time_point now) {
  splits_ += splits;
  answer_operations_ += operations;
  if (!final) return;
  // The server answers only the newest of the requests that came while it was busy: a final batch closes
  // every earlier one too.
  while (!sent_.empty() && sent_.front().number <= number) {
    if (sent_.front().number == number)
      latency_ms_ = std::chrono::duration<double, std::milli>(now - sent_.front().at).count();
    sent_.pop_front();
  }
}

bool FreeRunningSession::wants_request(const Camera& camera) const {
  if (opening_ || !(lacks_ || mode_.asks_every_view())) return false;
  if (!asked_ || !same_camera(*asked_, camera)) return true;
  return sent_.empty() && answer_operations_ > 0 && rounds_ < mode_.rounds_per_view();
}

std::vector<uint8_t> FreeRunningSession::request(const Camera& camera, Clock::time_point now) {
  if (!asked_ || !same_camera(*asked_, camera)) rounds_ = 0;
  asked_ = camera;
  ++rounds_;
  answer_operations_ = 0;
  protocol::DagView request = management_.next(session_, in_flight());
  request.view.camera = camera;
  request.view.frame = ++requests_;
  sent_.push_back({requests_, now});
  return mode_.encode_request(request);
}

// Idle: no VIEW on the wire and the view lacks nothing; moving: there is a path to extrapolate.
std::vector<uint8_t> FreeRunningSession::ahead(const Camera& camera) {
  if (ahead_frames_ == 0 || mode_.wire_mode() != protocol::StreamMode::sender_driven || opening_ || !sent_.empty() || lacks_ || !previous_ || same_camera(*previous_, camera))
    return {};
  const std::optional<Camera> next = extrapolate(*previous_, camera, ahead_frames_);
  if (!next || camera_problem(*next)) return {};
  ++aheads_;
  return protocol::encode(protocol::Ahead{protocol::View{*next, management_.configured().view.tolerance, aheads_}});
}

std::vector<uint8_t> FreeRunningSession::frame(const Camera& camera, Clock::time_point now, FrameReport& report) {
  report.frame = ++frames_;
  lacks_ = mode_.adapt(camera, session_);
  std::vector<uint8_t> out;
  if (wants_request(camera)) out = request(camera, now);
  report.requested = !out.empty();
  if (out.empty()) out = ahead(camera);
  previous_ = camera;
  report.vsplits = splits_;
  report.latency_ms = latency_ms_;
  report.in_flight = in_flight();
  report.satisfied = satisfied();
  report.faces = session_.mesh().face_count();
  splits_ = 0;
  latency_ms_ = 0;
  return out;
}

void FreeRunningSession::set_request(const protocol::DagView& request) {
  management_ = DagManagement(request, management_.options());
  asked_.reset();
  rounds_ = 0;
}

void FreeRunningSession::restart() {
  sent_.clear();
  previous_.reset();
  asked_.reset();
  rounds_ = 0;
  answer_operations_ = 0;
  opening_ = true;
  codec_due_ = false;
}

}  // namespace pms::client
