#include "bench/fleet_session.h"

#include <exception>

#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "spm/split_codec.h"

namespace pms::bench {
namespace asio = boost::asio;
namespace {

constexpr FleetClock::duration kFramePeriod = std::chrono::microseconds(1'000'000 / 30);
// VIEWs a settling session sends for its last camera before it counts as unsatisfied: the server answers a
// VIEW with every split the view wants, so one is normal and more only follow an answer cut short.
constexpr uint32_t kSettleViews = 4;

bool same_split(const SplitRecord& a, const SplitRecord& b) {
  return a.vs == b.vs && a.cut_l == b.cut_l && a.cut_r == b.cut_r && a.info_t == b.info_t && a.info_u == b.info_u &&
         std::equal(a.position_t, a.position_t + 3, b.position_t) && a.has_normal == b.has_normal &&
         (!a.has_normal || std::equal(a.normal_t, a.normal_t + 3, b.normal_t)) && a.has_color == b.has_color &&
         (!a.has_color || std::equal(a.color_t, a.color_t + 4, b.color_t));
}

}  // namespace

FleetSession::FleetSession(asio::io_context& io, const FleetModel& model, SoakPath path, FleetCounters& counters,
                           FleetListener& listener)
    : socket_(io),
      tick_(io),
      model_(model),
      path_(std::move(path)),
      counters_(counters),
      listener_(listener),
      held_(model.model()) {}

void FleetSession::start(const asio::ip::tcp::endpoint& server) {
  stage_ = Stage::connecting;
  last_progress_ = FleetClock::now();
  socket_.async_connect(server, [this](const boost::system::error_code& ec) {
    if (closed_) return;
    if (ec) return fail("connect: " + ec.message());
    boost::system::error_code ignored;
    socket_.set_option(asio::ip::tcp::no_delay(true), ignored);
    stage_ = Stage::base;
    send(client::hello_frame("pmstream-bench load-fleet"));
    send(protocol::encode(protocol::Open{model_.served->name, {}, protocol::StreamMode::sender_driven}));
    start_read();
  });
}

void FleetSession::start_read() {
  socket_.async_read_some(asio::buffer(buffer_), [this](const boost::system::error_code& ec, size_t n) {
    if (closed_) return;
    if (ec) return fail("connection: " + ec.message());
    try {
      reader_.feed(buffer_.data(), n);
      for (protocol::Frame frame; !closed_ && reader_.next(frame);) on_frame(std::move(frame));
    } catch (const std::exception& e) {
      return fail(e.what());
    }
    if (!closed_) start_read();
  });
}

void FleetSession::on_frame(protocol::Frame received) {
  std::optional<protocol::Frame> frame = greeting_.take(std::move(received));  // an ERROR throws here
  if (!frame) return;
  last_progress_ = FleetClock::now();
  const auto expect = [&](protocol::MessageType type) {
    if (frame->type != type)
      pms::fail("server", "expected " + protocol::to_string(type) + ", got " + protocol::to_string(frame->type));
  };
  switch (stage_) {
    case Stage::base:
      expect(protocol::MessageType::base);
      return on_base(*frame);
    case Stage::codec:
      expect(protocol::MessageType::codec);
      context_.records = protocol::decode_codec(frame->payload, context_).codec;
      stage_ = Stage::first_view;
      camera_ = path_.at(frame_);
      return send_view(camera_);
    case Stage::first_view:
    case Stage::holding:
      expect(protocol::MessageType::vsplits);
      return on_batch(*frame);
    default:
      pms::fail("server", "a frame before the session was opened");
  }
}

void FleetSession::on_base(const protocol::Frame& frame) {
  const protocol::Base base = protocol::decode_base(frame.payload);
  context_ = protocol::stream_context(base);
  const protocol::StreamContext& served = model_.served->context;
  // The criteria and the held values are the load process's own copy of the model: it must be the one served.
  if (base.model != model_.served->name || context_.root_count != served.root_count ||
      context_.node_id_bits != served.node_id_bits || context_.grid.bits != served.grid.bits)
    pms::fail("server", "BASE is not of the model this load process mapped (another file, or --position-bits)");
  // What a client holds about a vertex it may be sent a split of: a held leaf's values, as it received them.
  context_.held = [this](VertexId vs, SplitContext& out) {
    const uint32_t node = model_.model().find(vs);
    if (node == kNone || !held_.holds(node)) return false;
    out = split_context(model_.model(), model_.positions, node);
    return true;
  };
  stage_ = Stage::codec;
}

void FleetSession::on_batch(const protocol::Frame& frame) {
  const protocol::VSplits batch = protocol::decode_vsplits(frame.payload, context_);
  if (!pending_) pms::fail("server", "VSPLITS when no VIEW was unanswered");
  if (batch.frame != view_frame_)
    pms::fail("server", "VSPLITS of frame " + std::to_string(batch.frame) + " while VIEW " + std::to_string(view_frame_) +
                       " is unanswered");
  for (const SplitRecord& split : batch.splits) check_split(split);
  counters_.splits += batch.splits.size();
  if (!batch.final) return;
  pending_ = false;
  const double ms = std::chrono::duration<double, std::milli>(FleetClock::now() - sent_at_).count();
  if (stage_ == Stage::first_view) {
    counters_.first_views.add(ms);
    stage_ = Stage::holding;
    return listener_.opened(*this);
  }
  counters_.views.add(ms);
  if (settling_) settle();
}

// The packet decoded against the held leaf's values; it must be the model's split, and of a leaf held.
void FleetSession::check_split(const SplitRecord& split) {
  const uint32_t node = held_.split(split.vs);
  const SplitRecord expected = protocol::split_record_of(
      split.vs, split_payload(model_.model(), model_.positions, node), context_.grid, *context_.records);
  if (!same_split(split, expected)) pms::fail("server", "the split of " + to_string(split.vs) + " is not the model's");
}

void FleetSession::send(std::vector<uint8_t> frame) {
  outbox_.push_back(std::move(frame));
  if (!writing_) write_next();
}

void FleetSession::write_next() {
  writing_ = true;
  asio::async_write(socket_, asio::buffer(outbox_.front()), [this](const boost::system::error_code& ec, size_t) {
    if (closed_) return;
    if (ec) return fail("send: " + ec.message());
    outbox_.pop_front();
    writing_ = false;
    if (!outbox_.empty()) write_next();
  });
}

void FleetSession::send_view(const Camera& camera) {
  pending_ = true;
  sent_at_ = last_progress_ = FleetClock::now();
  ++counters_.views_sent;
  send(protocol::encode(protocol::View{camera, model_.tolerance, ++view_frame_}));
}

bool FleetSession::lacks(const Camera& camera) const {
  const ModelData& model = model_.model();
  const ViewCriteria view = make_criteria(make_view(camera, model.bbox_min, model.bbox_max), model_.tolerance);
  const std::vector<NodeCriteria>& criteria = *model_.criteria;
  return held_.any_leaf([&](uint32_t node) { return qrefine(view, criteria[node]); });
}

void FleetSession::fly(FleetClock::duration offset) {
  if (closed_ || stage_ != Stage::holding) return;
  flying_ = true;
  settling_ = false;
  next_tick_ = FleetClock::now() + offset;
  tick_.expires_at(next_tick_);
  tick_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) on_tick();
  });
}

void FleetSession::on_tick() {
  if (closed_ || !flying_) return;
  camera_ = path_.at(++frame_);
  ++counters_.frames;
  if (pending_) {
    ++counters_.frames_waiting;  // the viewer flies on with what it holds
  } else if (lacks(camera_)) {
    send_view(camera_);
  }
  // A late tick is not made up with a burst of frames.
  next_tick_ = std::max(next_tick_ + kFramePeriod, FleetClock::now());
  tick_.expires_at(next_tick_);
  tick_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) on_tick();
  });
}

void FleetSession::stop_flying() {
  if (closed_ || !flying_) return;
  flying_ = false;
  tick_.cancel();
  settling_ = true;
  settle_views_ = 0;
  if (!pending_) settle();
}

void FleetSession::settle() {
  if (!lacks(camera_)) {
    settling_ = false;
    return listener_.settled(*this, true);
  }
  if (settle_views_++ < kSettleViews) return send_view(camera_);
  settling_ = false;
  listener_.settled(*this, false);
}

void FleetSession::check_deadline(FleetClock::time_point now) {
  const bool waiting = stage_ != Stage::holding || pending_;
  if (!closed_ && stage_ != Stage::idle && waiting && now - last_progress_ > model_.answer_timeout)
    fail("no answer within " + std::to_string(model_.answer_timeout.count()) + " ms");
}

void FleetSession::close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ignored;
  tick_.cancel();
  socket_.close(ignored);
}

void FleetSession::fail(const std::string& why) {
  if (closed_) return;
  failed_ = true;
  error_ = why;
  const bool in_step = settling_ || flying_;
  settling_ = flying_ = false;
  close();
  listener_.failed(*this);
  if (in_step) listener_.settled(*this, false);
}

}  // namespace pms::bench
