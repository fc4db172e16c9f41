// One client's session (docs/protocol.md, "Session"): HELLO, LIST, OPEN and CLOSE here, the rest in the
// mode OPEN chose. Every call is bounded: receive() decodes and records, pump() does one slice of what
// the mode has pending.
#include "server/session.h"

#include <new>
#include <string>
#include <utility>
#include <variant>

#include "protocol/dispatch.h"
#include "protocol/server_messages.h"

namespace pms::server {

using protocol::ErrorCode;
using protocol::ProtocolError;

Session::Session(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits)
    : catalogue_(std::move(catalogue)),
      list_frame_(catalogue_->catalogue_frame()),
      builds_(catalogue_->shared_table_builds()),
      limits_(limits) {}

Session::~Session() { stop_waiting(); }

void Session::wake_with(const void* group, std::function<void()> wake) { waiter_ = {this, group, std::move(wake)}; }

void Session::stop_waiting() {
  if (waiting_) builds_->forget_owner(this);
  waiting_.reset();
}

bool Session::has_work() const {
  if (closing_) return false;
  if (waiting_) return tables_settled();
  return mode_ && mode_->has_work();
}

bool Session::tables_settled() const {
  const auto state = model_->tables->state(served_mode_of(waiting_->header.mode));
  return state == ModelTables::State::ready || state == ModelTables::State::failed;
}

void Session::queue(std::vector<uint8_t> frame) {
  outbox_.push_back(std::make_shared<const std::vector<uint8_t>>(std::move(frame)));
}

void Session::abort_with(ErrorCode code, const std::string& text) {
  if (closing_) return;
  if (mode_) mode_->stop();
  stop_waiting();
  error_ = code;
  error_text_ = text;
  // The ERROR text is the peer's to read, never over its frame limit.
  queue(protocol::encode(protocol::ErrorMessage{code, text.substr(0, 512)}));
  closing_ = true;
}

// Anything but a protocol error is the server's fault: the session ends, the process goes on.
void Session::fault(const char* what) {
  if (closing_) return;
  try {
    abort_with(ErrorCode::internal, std::string("internal error: ") + what);
  } catch (const std::bad_alloc&) {  // no memory even for the ERROR: end without it
    outbox_.clear();
    error_ = ErrorCode::internal;
    closing_ = true;
  }
}

void Session::receive(protocol::Frame frame) {
  last_work_ = 0;
  if (closing_) return;
  try {
    handle(frame);
  } catch (const ProtocolError& e) {
    abort_with(e.code, e.what());
  } catch (const Error& e) {
    abort_with(ErrorCode::bad_message, e.what());
  } catch (const std::exception& e) {
    fault(e.what());
  }
}

void Session::handle(protocol::Frame& frame) {
  if (frame.type == protocol::MessageType::open) {  // its front is decoded by pump(), a slice at a time
    if (!greeted_) throw ProtocolError(ErrorCode::out_of_order, "OPEN before HELLO");
    on_open(protocol::decode_open_header(frame.payload), frame);
    return;
  }
  const protocol::ClientMessage message = protocol::decode_client_message(frame);
  if (!greeted_ && !std::holds_alternative<protocol::Hello>(message))
    throw ProtocolError(ErrorCode::out_of_order, protocol::to_string(frame.type) + " before HELLO");
  if (std::holds_alternative<protocol::List>(message)) {
    outbox_.push_back(list_frame_);
  } else if (std::holds_alternative<protocol::Close>(message)) {
    if (mode_) mode_->stop();
    stop_waiting();
    closing_ = true;
  } else if (std::holds_alternative<protocol::Hello>(message)) {
    on_hello(std::get<protocol::Hello>(message));
  } else {
    if (waiting_) throw ProtocolError(ErrorCode::out_of_order, protocol::to_string(frame.type) + " before BASE");
    if (!mode_) throw ProtocolError(ErrorCode::out_of_order, protocol::to_string(frame.type) + " before OPEN");
    if (std::holds_alternative<protocol::Ahead>(message) && version_ < 7)
      throw ProtocolError(ErrorCode::out_of_order, "AHEAD: not in a session greeted with version 6");
    mode_->receive(message);
  }
}

void Session::on_hello(const protocol::Hello& m) {
  if (greeted_) throw ProtocolError(ErrorCode::out_of_order, "HELLO: sent twice");
  if (m.version < protocol::kMinProtocolVersion || m.version > protocol::kProtocolVersion)
    throw ProtocolError(ErrorCode::unsupported_version,
                        "HELLO: protocol version " + std::to_string(m.version) + " (this server speaks " +
                            std::to_string(protocol::kMinProtocolVersion) + " to " +
                            std::to_string(protocol::kProtocolVersion) + ")");
  greeted_ = true;
  version_ = m.version;
  protocol::HelloOk ok;
  ok.version = m.version;
  ok.server_name = "pmstream";
  ok.max_client_message = limits_.max_client_message;
  ok.max_server_message = limits_.max_server_message;
  queue(protocol::encode(ok));
}

void Session::on_open(const protocol::OpenHeader& m, protocol::Frame& frame) {
  if (model_) throw ProtocolError(ErrorCode::out_of_order, "OPEN: a model is already open in this session");
  const ServedModel* model = catalogue_->find(m.model);
  if (!model) throw ProtocolError(ErrorCode::unknown_model, "OPEN: no model named '" + m.model + "'");
  model_ = model;
  model_hold_ = model->shared_from_this();
  catalogue_.reset();
  mode_kind_ = m.mode;
  TableBuilds& builds = *builds_;
  if (builds.request(*model, served_mode_of(m.mode), waiter_)) return open_mode(m, frame);
  waiting_ = WaitingOpen{m, std::move(frame)};
  if (!waiter_.wake) {
    builds.wait(*model, served_mode_of(m.mode));
    finish_open();
  }
}

void Session::open_mode(const protocol::OpenHeader& m, protocol::Frame& frame) {
  mode_ = open_session_mode(m, frame, ModeContext{*model_, limits_, outbox_, phases_});
}

// The tables an OPEN waited for have settled: BASE (the mode opens), or the build's failure as ERROR.
void Session::finish_open() {
  WaitingOpen open = std::move(*waiting_);
  waiting_.reset();
  const ServedMode mode = served_mode_of(open.header.mode);
  if (!model_->tables->ready(mode))
    throw ProtocolError(ErrorCode::internal, std::string("OPEN: the model's ") + served_mode_name(mode) +
                                                 " tables could not be built: " + model_->tables->failure(mode));
  open_mode(open.header, open.frame);
}

bool Session::pump() {
  last_work_ = 0;
  if (!has_work()) return false;
  try {
    if (waiting_) {
      finish_open();
      return true;
    }
    mode_->pump(last_work_);
  } catch (const ProtocolError& e) {
    abort_with(e.code, e.what());
  } catch (const std::exception& e) {
    fault(e.what());
  }
  return true;
}

}  // namespace pms::server
