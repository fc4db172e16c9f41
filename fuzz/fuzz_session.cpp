// libFuzzer target for server::Session: the input is a program of client messages,
// well-formed and not, and transport events (pump, read the outbox, a deadline, reconnect), run against a real
// Session serving a real model, without sockets. The harness keeps the transport's rules (tcp_server.cpp: a
// frame over max_client_message ends the stream; no frame is handled and no slice pumped while more than
// send_queue_bytes wait), and after every call checks the bounds a hostile peer must not break: the work of
// one call, the session's memory, the outbox, no ERROR internal. Each session's outcome is checked against
// what it was sent (session_client.h): the right ERROR or none, every request answered, no split sent twice,
// also to a client that reconnected and resumed from its leaves. The DAG mode is a mode like the
// others: OPEN and resume it (the client's mesh as the front), DAG_VIEWs with every traversal, FREE and BUDGET,
// budgets and N at and over their bounds, wild views and repeated frame numbers, among VIEWs and the rest; the
// simulated client mirrors the session's cut and applies every DAG_OPS operation to it (legal, within the
// DAG_VIEW's budget and N), and a quiet session's cut must be that mirror.
// Small limits (slices of 64 nodes, batches of 16 splits, a 4 KB send queue) so slicing, batching and
// back-pressure happen on a model small enough for hundreds of runs a second under ASan.
#include <unistd.h>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "builder/build.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/wire_internal.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/session.h"
#include "session_client.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/vertex_id.h"

namespace pms::fuzz {
namespace {

using protocol::ErrorCode;
using protocol::Frame;
using protocol::MessageType;
using protocol::StreamMode;

constexpr uint64_t kTerrainFaces = 2000;
constexpr int kMaxOps = 64;  // per input, so a run stays short whatever its length
constexpr int kMaxConnections = 8;

struct Fixture {
  std::shared_ptr<const server::Catalogue> catalogue;
  const server::ServedModel* served = nullptr;
  server::ServerLimits limits;
  float center[3] = {0, 0, 0}, diagonal = 1;
  uint64_t work_bound = 0;      // units one receive() or pump() may do
  uint64_t dag_work_bound = 0;  // the same in a DAG session, whose one turn is a whole traversal
  size_t tags_bound = 0;        // bytes of one set of active tags
  size_t state_bound = 0;       // Session::state_bytes()
  size_t outbox_bound = 0;      // bytes waiting in the outbox
  uint64_t quiet_pumps = 0;     // pumps after the last input before the session must have nothing left to do
};

Fixture make_fixture(const BuildOptions& options) {
  Fixture f;
  f.limits.max_client_message = 8192;  // a front of the whole model is ~700 bytes
  f.limits.max_server_message = 4096;
  f.limits.send_queue_bytes = 4096;
  f.limits.batch_splits = 16;
  f.limits.slice_work = 64;
  const BuildResult built = build_progressive_mesh(make_terrain(kTerrainFaces), options);
  // The served name is the file's stem. The file can go once mapped; a directory per process and model
  // keeps parallel fuzzing jobs apart.
  static int made = 0;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("pmstream-fuzz-session-" + std::to_string(getpid()) + "-" + std::to_string(made++));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "terrain.pms").string();
  write_pms(path, built.hierarchy, built.stats);
  f.catalogue = server::Catalogue::open({path});
  std::filesystem::remove_all(dir);
  f.catalogue->check_limits(f.limits);
  f.served = f.catalogue->find("terrain");
  const ModelData& model = f.served->model();
  float extent2 = 0;
  for (int i = 0; i < 3; ++i) {
    f.center[i] = 0.5f * (model.bbox_min[i] + model.bbox_max[i]);
    extent2 += (model.bbox_max[i] - model.bbox_min[i]) * (model.bbox_max[i] - model.bbox_min[i]);
  }
  f.diagonal = std::sqrt(extent2);
  // A slice may finish the dependency chain in hand (SelectiveStreamer::step): a unit per split in it and one
  // per child it ranks, so 2 x 64 on top cover a chain of 42 splits, far longer than a chain up these
  // hierarchies (depth 6 and 12) can be.
  f.work_bound = f.limits.slice_work + 2 * 64;
  // A DAG session's traversal is one turn bounded by the cut, not by slice_work (docs/internals.md, "The DAG
  // mode"): nodes evaluated, operations made and the cut's load and store, a few units per node at most
  // (Session.DagAnswersAreBoundedSlices: 8 per node for the converged first answer). A resume's last turn
  // loads the cut: a slice of leaves and every split node.
  f.dag_work_bound = 8 * uint64_t(f.served->tables->dag().size()) + f.limits.slice_work;
  // A window over every node, one bit each, and what growing it may leave unused (doubling at worst).
  f.tags_bound = 2 * (model.node_count() / 8 + 8 * sizeof(uint64_t)) + 64;
  // The tags, a resume's second set and a VIEW prefix's copy; a pending resume frame; the ranking,
  // batch and scratch within 64 KB.
  f.state_bound = sizeof(server::Session) + 3 * f.tags_bound + f.limits.max_client_message + (64u << 10);
  // The transport stops feeding and pumping once the queue is over its limit, so at most the frame that
  // crossed it and an ERROR come on top.
  f.outbox_bound = f.limits.send_queue_bytes + 2 * (f.limits.max_server_message + protocol::kFrameHeaderBytes);
  // Generous: a VIEW wanting the whole model touches each node a few times, in slices and batches.
  f.quiet_pumps = 4 * model.node_count() + 256;
  trace([&] {
    return "model: " + std::to_string(model.node_count()) + " nodes, " + std::to_string(model.root_count) +
           " trees, depth " + std::to_string(f.served->context.node_id_bits) + "; bounds: work " +
           std::to_string(f.work_bound) + ", state " + std::to_string(f.state_bound) + " bytes, outbox " +
           std::to_string(f.outbox_bound) + " bytes";
  });
  return f;
}

// The fuzz input read as a program: bytes and bits on demand, zeros once it runs out.
class Input {
 public:
  Input(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return at_ >= size_; }
  uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  bool bit() {
    if (bits_left_ == 0) {
      bits_ = byte();
      bits_left_ = 8;
    }
    --bits_left_;
    const bool b = bits_ & 1;
    bits_ >>= 1;
    return b;
  }
  uint16_t u16() {
    const uint16_t low = byte();
    return uint16_t(low | byte() << 8);
  }
  uint32_t u32() {
    const uint32_t low = u16();
    return low | uint32_t(u16()) << 16;
  }
  float signed_unit() { return float(byte()) / 127.5f - 1; }
  std::string text(size_t max) {
    std::string s(byte() % (max + 1), '\0');
    for (char& c : s) c = char(byte());
    return s;
  }

 private:
  const uint8_t* data_;
  size_t size_, at_ = 0;
  uint8_t bits_ = 0;
  int bits_left_ = 0;
};

Frame to_frame(const std::vector<uint8_t>& bytes) {
  return Frame{MessageType(bytes[4]), {bytes.begin() + protocol::kFrameHeaderBytes, bytes.end()}};
}

// A front of trees [0, trees) shaped by the input, as the preorder code OPEN carries: at each node the
// model splits (with `overreach`, at any node: children the model lacks), one input bit says whether the
// client holds the split. Once the input runs out every node left is a leaf, so the front stays finite.
struct FrontShape {
  std::vector<bool> code;
  std::vector<VertexId> leaves;
};

void grow_front(Input& in, const ModelData& model, VertexId id, uint32_t node, bool overreach, FrontShape& out) {
  const bool splittable = node != kNone && !model.is_leaf(node);
  const bool split = (splittable || overreach) && in.bit();
  out.code.push_back(split);
  if (!split) {
    out.leaves.push_back(id);
    return;
  }
  if (id.depth() >= 63) return;  // the decoder refuses this split bit; nothing may follow it
  const uint32_t child = splittable ? model.first_child[node] : kNone;
  grow_front(in, model, id.child(0), child, overreach, out);
  grow_front(in, model, id.child(1), child == kNone ? kNone : child + 1, overreach, out);
}

FrontShape shape_front(Input& in, const ModelData& model, uint32_t trees, bool overreach) {
  FrontShape out;
  // A count far over the model's is refused from the payload's length; its codes need not all be written.
  const uint32_t written = std::min<uint32_t>(trees, model.root_count + 64);
  for (uint32_t t = 0; t < written; ++t)
    grow_front(in, model, {t, 1}, t < model.root_count ? t : kNone, overreach, out);
  return out;
}

float pick(Input& in, std::initializer_list<float> values) { return values.begin()[in.byte() % values.size()]; }

// Finite values around the model, as a viewer flying over it would send.
Camera near_camera(Input& in, const Fixture& f) {
  Camera c;
  float dir[3] = {in.signed_unit(), in.signed_unit(), in.signed_unit()};
  float norm = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  if (norm < 1e-3f) {
    dir[1] = norm = 1;
  }
  const float distance = f.diagonal * pick(in, {0.02f, 0.1f, 0.25f, 0.5f, 0.8f, 1.2f, 2, 5});
  for (int i = 0; i < 3; ++i) {
    c.eye[i] = f.center[i] + dir[i] / norm * distance;
    c.target[i] = f.center[i] + 0.4f * f.diagonal * in.signed_unit();
  }
  const int up = in.byte() % 3;
  for (int i = 0; i < 3; ++i) c.up[i] = i == up ? 1.0f : 0.0f;
  c.fovy_deg = float(10 + in.byte() % 120);
  c.width = uint32_t(pick(in, {1, 64, 320, 800, 1920, 65535}));
  c.height = uint32_t(pick(in, {1, 48, 240, 600, 1080, 65535}));
  return c;
}

// Values at the edges of float and of what the decoder accepts, or any bits at all.
float wild_float(Input& in) {
  const uint8_t b = in.byte();
  if (b >= 224) return std::bit_cast<float>(in.u32());
  static const float kWild[] = {0,
                                -0.0f,
                                FLT_MIN,
                                1e-7f,
                                1,
                                -1,
                                1e7f,
                                -1e7f,
                                1e30f,
                                -1e30f,
                                FLT_MAX,
                                -FLT_MAX,
                                179.99f,
                                std::numeric_limits<float>::infinity(),
                                std::numeric_limits<float>::quiet_NaN(),
                                std::numeric_limits<float>::denorm_min()};
  return kWild[b % (sizeof kWild / sizeof kWild[0])];
}

Camera wild_camera(Input& in) {
  Camera c;
  for (int i = 0; i < 3; ++i) c.eye[i] = wild_float(in);
  for (int i = 0; i < 3; ++i) c.target[i] = wild_float(in);
  for (int i = 0; i < 3; ++i) c.up[i] = wild_float(in);
  c.fovy_deg = wild_float(in);
  const auto viewport = [&] { return in.bit() ? in.u32() : uint32_t(pick(in, {0, 1, 2, 65535, 65536})); };
  c.width = viewport();
  c.height = viewport();
  return c;
}

// One connection: a session, what it was sent, and the client's frames the transport has not handed over.
struct Connection {
  explicit Connection(const Fixture& f)
      : session(f.catalogue, f.limits), expect(f.served->model(), f.served->tables->dag(), f.served->name) {}
  server::Session session;
  Expectation expect;
  std::deque<Frame> inbound;
  bool stream_dead = false;  // a frame over the limit: the reader hands out nothing after it
};

class Harness {
 public:
  explicit Harness(const Fixture& f)
      : f_(f),
        model_(f.served->model()),
        dag_(f.served->tables->dag()),
        client_(model_, dag_, f.limits),
        c_(std::make_unique<Connection>(f)) {}

  void run(Input& in) {
    for (int op = 0; op < kMaxOps && !in.empty(); ++op) step(in);
    settle();
    check_outcome();
  }

 private:
  enum class Op : uint8_t {
    hello,
    list,
    open,
    resume,
    mangled_open,
    view,
    wild_view,
    dag_view,
    close,
    raw,
    pump,
    read,
    reconnect,
    timeout,
    park,
    ahead,
    count
  };

  void step(Input& in) {
    switch (Op(in.byte() % uint8_t(Op::count))) {
      case Op::hello:
        return send_hello(in);
      case Op::list:
        return send(protocol::encode(protocol::List{}));
      case Op::open:
        return send_open(in);
      case Op::resume:
        return send_resume(in);
      case Op::mangled_open:
        return send_mangled_open(in);
      case Op::view: {
        const Camera camera = near_camera(in, f_);
        return send_view(camera, pick(in, {0, 0.25f, 0.5f, 1, 2, 8, 100, 1e9f}));
      }
      case Op::ahead: {  // version 7's idle-time request, between VIEWs or instead of them
        const Camera camera = near_camera(in, f_);
        const float tolerance = pick(in, {0, 0.25f, 0.5f, 1, 2, 8, 100, 1e9f});
        return send(protocol::encode(protocol::Ahead{protocol::View{camera, tolerance, next_frame_++}}));
      }
      case Op::wild_view: {
        const Camera camera = wild_camera(in);
        return send_view(camera, wild_float(in));
      }
      case Op::dag_view:
        return send_dag_view(in);
      case Op::close:
        return send(protocol::encode(protocol::Close{}));
      case Op::raw:
        return send_raw(in);
      case Op::pump:
        return pump_slices(1 + in.byte() % 16);
      case Op::read:
        return read_frames(in.byte() % 4);
      case Op::reconnect:
        return reconnect(any_mode(in));
      case Op::timeout:
        return time_out();
      case Op::park:  // the connection's idle timer (ServerLimits::park_after_ms)
        return call([&] { c_->session.park(); });
      case Op::count:
        break;
    }
  }

  // ---- client messages ------------------------------------------------------------------------------

  void send(const std::vector<uint8_t>& bytes) { send(to_frame(bytes)); }
  void send(Frame frame) {
    // A client whose session ended starts another, so the rest of the program still reaches a session.
    if (c_->session.closing()) reconnect(client_.mode());
    c_->inbound.push_back(std::move(frame));
    deliver();
  }
  void send_hello(Input& in) {
    protocol::Hello hello;
    if (!in.bit()) hello.version = in.u16();
    hello.client_name = in.text(8);
    send(protocol::encode(hello));
  }
  std::string model_name(Input& in) {
    switch (in.byte() % 4) {
      case 0:
        return "terrai";
      case 1:
        return in.text(16);
      default:
        return f_.served->name;
    }
  }
  static StreamMode any_mode(Input& in) {
    constexpr StreamMode kModes[] = {StreamMode::sender_driven, StreamMode::view_independent, StreamMode::sender_plain,
                                     StreamMode::dag};
    return kModes[in.byte() % 4];
  }
  void send_open(Input& in) {
    const StreamMode mode = any_mode(in);
    send(protocol::encode(protocol::Open{model_name(in), {}, mode}));
  }
  // A cut of the real hierarchy, encoded as a client would: the server must accept it (sender-driven). In the
  // DAG mode the front is a mesh, which the server takes when it is a cut of the DAG: one grown by legal
  // splits, or any front of the hierarchy (mostly refused).
  void send_resume(Input& in) {
    const uint8_t pick = in.byte() % 8;
    const StreamMode mode = pick == 0   ? StreamMode::view_independent
                            : pick == 1 ? StreamMode::sender_plain
                            : pick < 5  ? StreamMode::dag
                                        : StreamMode::sender_driven;
    const std::string name = model_name(in);
    const bool dag_cut = mode == StreamMode::dag && in.bit();
    const std::vector<VertexId> front =
        dag_cut ? cut_front(model_, grow_cut(in)) : shape_front(in, model_, model_.root_count, false).leaves;
    send(protocol::encode(protocol::Open{name, front, mode}));
  }
  // Up to 255 legal splits, each of a split candidate the input points at when it is in Fs.
  DagCut grow_cut(Input& in) {
    DagCut cut(dag_);
    for (int k = in.byte(); k > 0; --k) {
      uint32_t n = cut.next_candidate(in.u16() % dag_.size());
      if (n == kNone) n = cut.next_candidate(0);
      if (n != kNone && cut.in_fs(n)) cut.split(n);
    }
    return cut;
  }
  // Fronts the server must mostly refuse, written bit by bit as no encoder would: other tree counts,
  // leaves below the model's, a byte added, dropped or a bit flipped (Expectation sorts out which still hold).
  void send_mangled_open(Input& in) {
    const uint32_t roots = model_.root_count;
    uint32_t trees = roots;
    switch (in.byte() % 6) {
      case 1:
        trees = roots - std::min<uint32_t>(roots - 1, 1 + in.byte() % 4);
        break;
      case 2:
        trees = roots + 1 + in.byte() % 4;
        break;
      case 3:
        trees = 0;
        break;
      case 4:
        trees = in.u32();
        break;
      case 5:
        trees = 1;
        break;
    }
    const bool overreach = in.bit();
    const uint8_t mode_bits = in.byte() % 8;  // bit 1 view-independent, 2 plain, 3 DAG: any two are refused
    const std::string name = model_name(in);
    protocol::Writer w(MessageType::open);
    w.string(name, protocol::kMaxNameBytes, "model");
    w.u8(uint8_t(1 | mode_bits << 1));
    w.u32(trees);
    for (bool split : shape_front(in, model_, trees, overreach).code) w.bits(split, 1);
    Frame frame = to_frame(w.finish());
    switch (in.byte() % 4) {
      case 1:
        frame.payload.push_back(in.byte());
        break;
      case 2:
        if (!frame.payload.empty()) frame.payload.pop_back();
        break;
      case 3: {
        const uint32_t bit = in.u16() % uint32_t(8 * frame.payload.size());
        frame.payload[bit / 8] ^= uint8_t(1u << (bit % 8));
        break;
      }
    }
    send(std::move(frame));
  }
  void send_view(const Camera& camera, float tolerance) {
    send(protocol::encode(protocol::View{camera, tolerance, next_frame_++}));
  }
  // A well-formed DAG_VIEW with hostile choices: each traversal and management (or a code none is), budgets and
  // N at and beyond their bounds, a near or wild view, a frame number new, repeated or from anywhere.
  void send_dag_view(Input& in) {
    protocol::DagView m;
    const bool wild = in.byte() < 48;
    m.view.camera = wild ? wild_camera(in) : near_camera(in, f_);
    m.view.tolerance = wild ? wild_float(in) : pick(in, {0, 0.25f, 0.5f, 1, 2, 8, 100, 1e9f});
    const uint8_t frame = in.byte();
    m.view.frame = frame < 200 ? next_frame_++ : frame < 240 ? next_frame_ - 1 - frame % 4 : in.u32();
    const uint8_t traversal = in.byte();
    m.traversal = DagTraversal(traversal < 252 ? traversal % 3 : traversal);
    const uint8_t management = in.byte();
    m.management = DagMode(management < 252 ? management % 2 : management);
    const uint64_t faces = dag_.base_faces();
    const uint64_t budgets[] = {0,
                                1,
                                2,
                                faces - 1,
                                faces,
                                faces + 16,
                                2 * faces,
                                500,
                                3000,
                                1u << 20,
                                protocol::kMaxDagBudget,
                                protocol::kMaxDagBudget + 1,
                                UINT64_MAX,
                                in.u32()};
    const uint8_t budget = in.byte();
    if (m.management == DagMode::budget || budget >= 240) m.budget = budgets[budget % std::size(budgets)];
    const uint32_t max_ops[] = {
        0,          1,       2, 3, 16, 300, protocol::kMaxDagOps - 1, protocol::kMaxDagOps, protocol::kMaxDagOps + 1,
        UINT32_MAX, in.u16()};
    m.max_ops = max_ops[in.byte() % std::size(max_ops)];
    send(protocol::encode(m));
  }
  void send_raw(Input& in) {
    static const uint8_t kTypes[] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x81, 0x86, 0x00};
    const uint8_t t = in.byte();
    Frame frame;
    frame.type = MessageType(t < 240 ? kTypes[t % std::size(kTypes)] : t);
    const uint8_t length = in.byte();
    const size_t size = length < 200   ? length % 64
                        : length < 248 ? size_t(in.u16() % 1024)
                                       : f_.limits.max_client_message + 1 + in.byte();
    frame.payload.resize(size);
    for (uint8_t& b : frame.payload) b = in.byte();
    send(std::move(frame));
  }

  // A new connection (the old one lost, or ended): the client resumes from the leaves it holds
  // (kim-lee-kobbelt §5.3), or opens afresh in `mode` when it has none or streams view-independently
  // (which cannot resume). An ended session's outcome is checked first.
  void reconnect(StreamMode mode) {
    if (connections_ >= kMaxConnections) return;
    ++connections_;
    if (c_->session.closing()) {
      read_frames(0);  // the transport flushes what a closing session queued before it closes
      check_outcome();
    }
    protocol::Open open{f_.served->name, {}, client_.has_front() ? client_.mode() : mode};
    if (client_.has_front() && open.mode != StreamMode::view_independent) open.resume = client_.resume_front();
    trace([&] { return "reconnect, resuming from " + std::to_string(open.resume.size()) + " leaves"; });
    c_ = std::make_unique<Connection>(f_);
    client_.reconnect();
    send(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "fuzz"}));
    send(protocol::encode(open));
  }

  // ---- the transport --------------------------------------------------------------------------------

  // A deadline passed (handshake, idle, a frame or a write taking too long): the transport ends the session
  // whatever it was doing, in the middle of a resume or an answer too.
  void time_out() {
    server::Session& s = c_->session;
    if (s.closing()) return;  // abort_with() has nothing to end
    c_->expect.aborted(ErrorCode::timeout);
    call([&] { s.abort_with(ErrorCode::timeout, "a deadline passed"); });
  }

  size_t queued_bytes() {
    size_t bytes = 0;
    for (const server::Buffer& b : c_->session.outbox()) bytes += b->size();
    return bytes;
  }
  bool queue_full() { return queued_bytes() > f_.limits.send_queue_bytes; }

  void deliver() {
    server::Session& s = c_->session;
    while (!c_->inbound.empty() && !c_->stream_dead && !s.closing() && !queue_full()) {
      const Frame frame = std::move(c_->inbound.front());
      c_->inbound.pop_front();
      trace([&] {
        return "-> " + protocol::to_string(frame.type) + ", " + std::to_string(frame.payload.size()) + " bytes";
      });
      if (frame.payload.size() > f_.limits.max_client_message) {
        c_->stream_dead = true;
        c_->expect.aborted(ErrorCode::too_large);
        call([&] { s.abort_with(ErrorCode::too_large, "frame over the limit"); });
        return;
      }
      c_->expect.received(frame, client_);
      call([&] { s.receive(frame); });
    }
  }

  void pump_slices(int slices) {
    server::Session& s = c_->session;
    for (int i = 0; i < slices && !queue_full(); ++i) {
      const bool work = s.has_work();
      bool did = false;
      call([&] { did = s.pump(); });
      trace([&] {
        return "pump: " + std::to_string(s.last_work()) + " units, state " + std::to_string(s.state_bytes()) +
               " bytes, " + std::to_string(queued_bytes()) + " bytes queued";
      });
      if (did != work) fail(work ? "has_work() but pump() did nothing" : "pump() did something with no work");
      if (!work) break;
    }
    deliver();
  }

  void read_frames(size_t count) {  // 0: all
    auto& outbox = c_->session.outbox();
    for (size_t n = 0; !outbox.empty() && (count == 0 || n < count); ++n) {
      client_.read(*outbox.front());
      outbox.pop_front();
    }
    deliver();
  }

  // Every receive(), pump() and abort_with() goes through here: the bounds hold after each call.
  template <class Call>
  void call(Call&& fn) {
    server::Session& s = c_->session;
    const bool was_closing = s.closing();
    const size_t before = s.outbox().size();
    fn();
    const uint64_t work_bound = s.mode() == StreamMode::dag ? f_.dag_work_bound : f_.work_bound;
    if (s.last_work() > work_bound)
      fail("one call did " + std::to_string(s.last_work()) + " work units, over " + std::to_string(work_bound));
    if (s.state_bytes() > f_.state_bound)
      fail("state_bytes() " + std::to_string(s.state_bytes()) + " over " + std::to_string(f_.state_bound));
    if (s.front_bytes() > f_.tags_bound)
      fail("the front holds " + std::to_string(s.front_bytes()) + " bytes, over " + std::to_string(f_.tags_bound));
    if (s.error() == ErrorCode::internal) fail("ERROR internal: " + newest_error_text());
    if (was_closing && s.outbox().size() > before) fail("a frame queued after the session closed");
    if (s.closing() && s.has_work()) fail("has_work() on a closing session");
    for (size_t i = before; i < s.outbox().size(); ++i)
      if (s.outbox()[i]->size() > f_.limits.max_server_message + protocol::kFrameHeaderBytes)
        fail("a frame of " + std::to_string(s.outbox()[i]->size()) + " bytes, over max_server_message");
    if (queued_bytes() > f_.outbox_bound) fail("the outbox holds " + std::to_string(queued_bytes()) + " bytes");
  }
  std::string newest_error_text() {
    const auto& outbox = c_->session.outbox();
    if (outbox.empty()) return "(no ERROR queued)";
    try {
      return protocol::decode_error(to_frame(*outbox.back()).payload).text;
    } catch (const protocol::ProtocolError& e) {
      return std::string("(undecodable: ") + e.what() + ")";
    }
  }

  // The client reads everything and the transport pumps until the session has nothing left to do.
  void settle() {
    server::Session& s = c_->session;
    for (uint64_t pumps = 0;;) {
      read_frames(0);
      if (!s.has_work()) {
        if (s.outbox().empty()) return;
        continue;
      }
      if (++pumps > f_.quiet_pumps)
        fail("the session still has work after " + std::to_string(f_.quiet_pumps) + " pumps");
      pump_slices(1);
    }
  }

  void check_outcome() {
    const server::Session& s = c_->session;
    const Expectation& expect = c_->expect;
    if (const auto error = s.error()) {
      if (!expect.allows(*error))
        fail("ended with ERROR " + protocol::to_string(*error) +
             ", which nothing sent calls for: " + client_.error_text());
      return check(client_.error() == error, "the ERROR the client read is not error()");
    }
    // A CLOSE may come before pump() has checked a bad resume front: the session then ends without the ERROR.
    if (expect.closed()) return check(s.closing(), "CLOSE did not close the session");
    if (expect.must_fail()) fail("the session accepted a message it must refuse");
    check(!s.closing(), "the session closed with neither ERROR nor CLOSE");
    client_.check_answered(s);
  }

  const Fixture& f_;
  const ModelData& model_;
  const Dag& dag_;
  SimulatedClient client_;
  std::unique_ptr<Connection> c_;
  uint32_t next_frame_ = 0;
  int connections_ = 1;
};

}  // namespace
}  // namespace pms::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using pms::fuzz::Fixture, pms::fuzz::make_fixture;
  // The default build (balanced rounds down to 64 roots: depth 6 here), and one as deep as the real scans'
  // hierarchies (one collapse at a time down to 8 roots: depth 12), where dependency chains are long.
  static const Fixture fixtures[2] = {make_fixture(pms::BuildOptions{}),
                                      make_fixture(pms::BuildOptions{.greedy = true, .base_vertices = 8})};
  pms::fuzz::Input in(data, size);
  const Fixture& fixture = fixtures[in.byte() & 1];
  pms::fuzz::Harness(fixture).run(in);
  return 0;
}
