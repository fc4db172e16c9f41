#include "protocol_fixtures.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "io/mesh.h"
#include "io/shapes.h"
#include "protocol/message_types.h"
#include "protocol/stream_context.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms::test {
namespace {

BuiltModel build(const std::string& name, const Mesh& mesh) {
  BuiltModel model;
  model.name = name;
  model.hierarchy = build_progressive_mesh(mesh).hierarchy;
  return model;
}

}  // namespace

const BuiltModel& sphere_model() {
  static const BuiltModel model = [] {
    Mesh mesh = make_sphere(24, 32);
    // Attributes so the normal / color fields of BASE and VSPLITS travel too.
    mesh.normals.resize(mesh.positions.size());
    mesh.colors.resize(4 * mesh.vertex_count());
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      const float* p = &mesh.positions[3 * v];
      const float length = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int k = 0; k < 3; ++k) {
        mesh.normals[3 * v + k] = p[k] / length;
        mesh.colors[4 * v + k] = uint8_t(127.5f + 127.5f * p[k] / length);
      }
      mesh.colors[4 * v + 3] = uint8_t(v);
    }
    return build("sphere", mesh);
  }();
  return model;
}

const BuiltModel& terrain_model() {
  static const BuiltModel model = build("terrain", make_terrain(20000, 3));
  return model;
}

namespace {

std::unique_ptr<BuiltModel> build_shared(const std::string& name) {
  const auto path = shared_model(name + ".ply.xz");
  if (path.empty()) return nullptr;
  Mesh mesh = load_mesh(path.string());
  clean_mesh(mesh);
  return std::make_unique<BuiltModel>(build(name, mesh));
}

}  // namespace

const BuiltModel* bunny_model() {
  static const std::unique_ptr<BuiltModel> model = build_shared("bunny");
  return model.get();
}

const BuiltModel* horse_model() {
  static const std::unique_ptr<BuiltModel> model = build_shared("horse");
  return model.get();
}

std::vector<uint8_t> payload_of(const std::vector<uint8_t>& frame, protocol::MessageType type) {
  EXPECT_GE(frame.size(), protocol::kFrameHeaderBytes);
  if (frame.size() < protocol::kFrameHeaderBytes) return {};
  const uint32_t size =
      uint32_t(frame[0]) | uint32_t(frame[1]) << 8 | uint32_t(frame[2]) << 16 | uint32_t(frame[3]) << 24;
  EXPECT_EQ(size, frame.size() - protocol::kFrameHeaderBytes);
  EXPECT_EQ(frame[4], uint8_t(type));
  return {frame.begin() + protocol::kFrameHeaderBytes, frame.end()};
}

void expect_rejected(const std::function<void()>& decode, protocol::ErrorCode code, const std::string& needle) {
  try {
    decode();
    ADD_FAILURE() << "accepted; expected " << protocol::to_string(code) << " mentioning '" << needle << "'";
  } catch (const protocol::ProtocolError& e) {
    EXPECT_EQ(e.code, code) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << "'" << e.what() << "' lacks '" << needle << "'";
  }
}

// atan2 form: acos of a dot product near 1 loses half its digits (and inputs are unit only to ~1e-7).
double angle_between(const float* a, const float* b) {
  const double dot = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
  const double cx = double(a[1]) * b[2] - double(a[2]) * b[1], cy = double(a[2]) * b[0] - double(a[0]) * b[2],
               cz = double(a[0]) * b[1] - double(a[1]) * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot);
}

float random_float(Rng& rng, float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); }

std::string random_name(Rng& rng, size_t max_size) {
  std::string s(std::uniform_int_distribution<size_t>(0, max_size)(rng), '\0');
  for (char& c : s) c = char(std::uniform_int_distribution<int>(0, 255)(rng));  // any bytes, NUL included
  return s;
}

RefineInfo random_refine(Rng& rng) {
  // Lengths 0 .. +inf at the stored precision; a cone with any in-range axis, or none (spm/refine_info.h).
  std::uniform_int_distribution<int> length(0, 0x7C00 >> kLengthDroppedBits), axis(-kAxisSteps, kAxisSteps),
      angle(0, kConeSteps + 1);
  RefineInfo info{};
  for (uint16_t* half : {&info.radius, &info.mu, &info.delta}) *half = uint16_t(length(rng) << kLengthDroppedBits);
  const int a = angle(rng);
  if (a > kConeSteps) {
    info.cone_angle = kNoCone;
    return info;
  }
  info.cone_angle = uint16_t(a);
  info.cone_x = uint16_t(int16_t(axis(rng)));
  info.cone_y = uint16_t(int16_t(axis(rng)));
  return info;
}

protocol::StreamContext random_context(Rng& rng) {
  protocol::StreamContext c;
  c.tree_id_bits = std::uniform_int_distribution<uint32_t>(1, 32)(rng);
  const uint64_t max_roots = std::min<uint64_t>(uint64_t(1) << c.tree_id_bits, 1u << 20);
  c.root_count = uint32_t(std::uniform_int_distribution<uint64_t>(1, max_roots)(rng));
  // One tree needs a level below the root, or no leaf lies outside a split node's subtree.
  c.node_id_bits = std::uniform_int_distribution<uint32_t>(c.root_count == 1 ? 2 : 1, 63)(rng);
  static const uint32_t kBits[] = {1, 4, 8, 11, 12, 16, 20, 32};
  c.grid.bits = kBits[std::uniform_int_distribution<size_t>(0, std::size(kBits) - 1)(rng)];
  for (int i = 0; i < 3; ++i) {
    const float center = random_float(rng, -1, 1), extent = random_float(rng, 0.5f, 4);
    c.grid.min[i] = center - extent / 2;
    c.grid.max[i] = center + extent / 2;
  }
  c.has_normals = rng() & 1;
  c.has_colors = rng() & 1;
  return c;
}

namespace {

VertexId random_id(Rng& rng, const protocol::StreamContext& c, uint32_t max_depth) {
  VertexId v;
  v.tree = std::uniform_int_distribution<uint32_t>(0, c.root_count - 1)(rng);
  const uint32_t depth = std::uniform_int_distribution<uint32_t>(0, max_depth)(rng);
  v.node = (uint64_t(1) << depth) | (depth == 0 ? 0 : rng() >> (64 - depth));
  return v;
}

}  // namespace

SplitRecord random_split(Rng& rng, const protocol::StreamContext& c) {
  SplitRecord s;
  do s.vs = random_id(rng, c, c.node_id_bits - 1);
  while (c.root_count == 1 && s.vs.is_root());
  const int sides = std::uniform_int_distribution<int>(1, 3)(rng);
  for (auto [bit, cut] : {std::pair{1, &s.cut_l}, std::pair{2, &s.cut_r}}) {
    if (!(sides & bit)) continue;
    do *cut = random_id(rng, c, c.node_id_bits);
    while (is_ancestor_or_self(s.vs, *cut));
  }
  for (int i = 0; i < 3; ++i) s.position_t[i] = random_float(rng, c.grid.min[i], c.grid.max[i]);
  s.info_t = random_refine(rng);
  s.info_u = random_refine(rng);
  s.has_normal = c.has_normals;
  if (s.has_normal) {
    float length = 0;
    for (float& v : s.normal_t) {
      v = random_float(rng, -1, 1);
      length += v * v;
    }
    for (float& v : s.normal_t) v /= std::sqrt(std::max(length, 1e-12f));
  }
  s.has_color = c.has_colors;
  if (s.has_color)
    for (uint8_t& v : s.color_t) v = uint8_t(rng());
  return s;
}

namespace {

void random_subtree(Rng& rng, VertexId node, int max_depth, std::vector<VertexId>& out) {
  const bool split = node.depth() < max_depth && std::uniform_int_distribution<int>(0, 99)(rng) < 70 - 4 * node.depth();
  if (!split) {
    out.push_back(node);
    return;
  }
  random_subtree(rng, node.child(0), max_depth, out);
  random_subtree(rng, node.child(1), max_depth, out);
}

}  // namespace

std::vector<VertexId> random_front(Rng& rng, uint32_t trees, int max_depth) {
  std::vector<VertexId> front;
  for (uint32_t t = 0; t < trees; ++t) random_subtree(rng, {t, 1}, max_depth, front);
  std::shuffle(front.begin(), front.end(), rng);  // the encoder must not rely on the caller's order
  return front;
}

}  // namespace pms::test
