// Client -> server messages other than OPEN (open.cpp): HELLO, LIST, VIEW, CLOSE, DAG_VIEW (docs/protocol.md).
#include <cstring>

#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/wire_internal.h"

namespace pms::protocol {
namespace {

// Viewports beyond this are not screens; the bound keeps pixel_angle and friends far from denormals.
constexpr uint32_t kMaxViewport = 65535;

void write_vec3(Writer& w, const float v[3]) {
  for (int i = 0; i < 3; ++i) w.f32(v[i]);
}
void read_vec3(Reader& r, float v[3], const char* field) {
  for (int i = 0; i < 3; ++i) v[i] = r.finite_f32(field);
}

void expect_empty(std::span<const uint8_t> payload, MessageType type) {
  Reader r(payload, type);
  r.expect_end();
}

void write_view(Writer& w, const View& m) {
  write_vec3(w, m.camera.eye);
  write_vec3(w, m.camera.target);
  write_vec3(w, m.camera.up);
  w.f32(m.camera.fovy_deg);
  w.u32(m.camera.width);
  w.u32(m.camera.height);
  w.f32(m.tolerance);
  w.u32(m.frame);
}

View read_view(Reader& r) {
  View m;
  read_vec3(r, m.camera.eye, "eye");
  read_vec3(r, m.camera.target, "target");
  read_vec3(r, m.camera.up, "up");
  m.camera.fovy_deg = r.finite_f32("fovy_deg");
  m.camera.width = r.u32("width");
  m.camera.height = r.u32("height");
  m.tolerance = r.finite_f32("tolerance");
  m.frame = r.u32("frame");
  return m;
}

void check_view(Reader& r, const View& m) {
  if (m.camera.width < 1 || m.camera.width > kMaxViewport || m.camera.height < 1 || m.camera.height > kMaxViewport)
    r.fail(ErrorCode::bad_message, "viewport", "must be 1..65535 pixels each way");
  if (!(m.tolerance >= 0)) r.fail(ErrorCode::bad_message, "tolerance", "is negative");
  // The server will call make_view() with the model's box: a camera it would refuse (eye on the target,
  // up along the view direction, fovy outside (0, 180)) is the client's error, reported here.
  const float box_min[3] = {-1, -1, -1}, box_max[3] = {1, 1, 1};
  try {
    (void)make_view(m.camera, box_min, box_max);
  } catch (const Error& e) {
    std::string why = e.what();
    if (why.rfind("camera: ", 0) == 0) why.erase(0, 8);  // make_view's own prefix; the field says it already
    r.fail(ErrorCode::bad_message, "camera", why);
  }
}

}  // namespace

std::optional<DagTraversal> dag_traversal_named(std::string_view name) {
  if (name == "priority") return DagTraversal::priority;
  if (name == "linear") return DagTraversal::linear;
  if (name == "constant") return DagTraversal::constant_time;
  return std::nullopt;
}

const char* dag_traversal_name(DagTraversal traversal) {
  switch (traversal) {
    case DagTraversal::linear: return "linear";
    case DagTraversal::constant_time: return "constant";
    case DagTraversal::priority: break;
  }
  return "priority";
}

std::vector<uint8_t> encode(const Hello& m) {
  Writer w(MessageType::hello);
  for (char c : kMagic) w.u8(uint8_t(c));
  w.u16(m.version);
  w.string(m.client_name, kMaxNameBytes, "client name");
  return w.finish();
}

Hello decode_hello(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::hello);
  char magic[4];
  for (char& c : magic) c = char(r.u8("magic"));
  if (std::memcmp(magic, kMagic, sizeof magic) != 0) r.fail(ErrorCode::bad_message, "magic", "is not PMST");
  Hello m;
  m.version = r.u16("version");
  m.client_name = r.string(kMaxNameBytes, "client name");
  r.expect_end();
  return m;
}

std::vector<uint8_t> encode(const List&) { return Writer(MessageType::list).finish(); }
List decode_list(std::span<const uint8_t> payload) {
  expect_empty(payload, MessageType::list);
  return {};
}

std::vector<uint8_t> encode(const Close&) { return Writer(MessageType::close).finish(); }
Close decode_close(std::span<const uint8_t> payload) {
  expect_empty(payload, MessageType::close);
  return {};
}

std::vector<uint8_t> encode(const View& m) {
  Writer w(MessageType::view);
  write_view(w, m);
  return w.finish();
}

View decode_view(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::view);
  const View m = read_view(r);
  r.expect_end();
  check_view(r, m);
  return m;
}

std::vector<uint8_t> encode(const Ahead& m) {
  Writer w(MessageType::ahead);
  write_view(w, m.view);
  return w.finish();
}

Ahead decode_ahead(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::ahead);
  const Ahead m{read_view(r)};
  r.expect_end();
  check_view(r, m.view);
  return m;
}

std::vector<uint8_t> encode(const DagView& m) {
  Writer w(MessageType::dag_view);
  write_view(w, m.view);
  w.u32(m.max_ops);
  w.u8(uint8_t(m.traversal));
  w.u8(uint8_t(m.management));
  w.u64(m.budget);
  return w.finish();
}

DagView decode_dag_view(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::dag_view);
  DagView m;
  m.view = read_view(r);
  m.max_ops = r.u32("max ops");
  const uint8_t traversal = r.u8("traversal"), management = r.u8("management");
  m.budget = r.u64("budget");
  r.expect_end();
  check_view(r, m.view);
  if (m.max_ops < 1 || m.max_ops > kMaxDagOps) r.fail(ErrorCode::bad_message, "max ops", "must be 1..65536");
  if (traversal > uint8_t(DagTraversal::constant_time))
    r.fail(ErrorCode::bad_message, "traversal", "is not priority (0), linear (1) or constant-time (2)");
  if (management > uint8_t(DagMode::budget))
    r.fail(ErrorCode::bad_message, "management", "is not free (0) or budget (1)");
  m.traversal = DagTraversal(traversal);
  m.management = DagMode(management);
  if (m.management == DagMode::budget && (m.budget < 1 || m.budget > kMaxDagBudget))
    r.fail(ErrorCode::bad_message, "budget", "must be 1..2^32 triangles in BUDGET mode");
  if (m.management == DagMode::free && m.budget != 0)
    r.fail(ErrorCode::bad_message, "budget", "must be 0 in FREE mode");
  return m;
}

}  // namespace pms::protocol
