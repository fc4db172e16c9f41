// BASE: the base mesh with the roots' refinement info (kim-lee-kobbelt §5.2: "after downloading the entire
// data related to the base mesh, the client creates a base mesh, a vertex hierarchy and a vertex front"),
// and the stream context both ends derive from it. Also the catalogue entry of a model.
#include <cmath>

#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "spm/hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::protocol {
namespace {

constexpr uint8_t kFlagNormals = 1, kFlagColors = 2;

// The smallest a root record can be: bounds the root count by the payload before allocating.
uint64_t root_bits(const StreamContext& c) {
  return 3 * uint64_t(c.grid.bits) + kMinRefineBits + (c.has_normals ? 32 : 0) + (c.has_colors ? 32 : 0);
}

StreamContext context_fields(const Base& m) {
  StreamContext c;
  c.root_count = m.root_count();
  c.tree_id_bits = m.tree_id_bits;
  c.node_id_bits = m.node_id_bits;
  for (int i = 0; i < 3; ++i) {
    c.grid.min[i] = m.bbox_min[i];
    c.grid.max[i] = m.bbox_max[i];
  }
  c.grid.bits = m.position_bits;
  c.has_normals = m.has_normals;
  c.has_colors = m.has_colors;
  return c;
}

void check_sizes(const Base& m) {
  const size_t roots = m.refine.size();
  if (m.positions.size() != 3 * roots || (m.has_normals ? m.normals.size() != 3 * roots : !m.normals.empty()) ||
      (m.has_colors ? m.colors.size() != 4 * roots : !m.colors.empty()) || m.faces.size() % 3 != 0)
    fail("BASE", "array sizes disagree with the root count and flags");
  if (roots > UINT32_MAX || m.faces.size() / 3 > UINT32_MAX) fail("BASE", "too many roots or faces");
  if (!std::isfinite(m.scale) || m.scale < 0) fail("BASE", "scale is not finite or negative");
}

}  // namespace

StreamContext stream_context(const Base& base) {
  StreamContext c = context_fields(base);
  if (const std::string why = check_context(c); !why.empty()) fail("BASE", why);
  return c;
}

bool carries_split_records(StreamMode mode) { return mode == StreamMode::sender_driven; }

std::vector<uint8_t> encode(const Base& m) {
  check_sizes(m);
  const StreamContext c = stream_context(m);
  Writer w(MessageType::base);
  w.string(m.model, kMaxNameBytes, "model");
  for (float v : m.bbox_min) w.f32(v);
  for (float v : m.bbox_max) w.f32(v);
  w.f32(m.scale);
  w.u8(uint8_t(c.tree_id_bits));
  w.u8(uint8_t(c.node_id_bits));
  w.u8(uint8_t(c.grid.bits));
  w.u8(uint8_t((c.has_normals ? kFlagNormals : 0) | (c.has_colors ? kFlagColors : 0)));
  w.u32(c.root_count);
  w.u32(uint32_t(m.faces.size() / 3));
  // Roots: one record each (position, info, normal, color), then the faces, all in one bit stream.
  for (uint32_t i = 0; i < c.root_count; ++i) {
    uint32_t q[3];
    quantize_position(c.grid, &m.positions[3 * size_t(i)], q);
    for (uint32_t v : q) w.bits(v, c.grid.bits);
    write_refine(w, m.refine[i], "BASE");
    if (c.has_normals) {
      uint16_t n[2];
      encode_normal(&m.normals[3 * size_t(i)], n);
      w.u16(n[0]);
      w.u16(n[1]);
    }
    if (c.has_colors)
      for (int k = 0; k < 4; ++k) w.u8(m.colors[4 * size_t(i) + k]);
  }
  for (uint32_t index : m.faces) {
    if (index >= c.root_count) fail("BASE", "face index " + std::to_string(index) + " >= root count");
    w.bits(index, c.tree_id_bits);
  }
  return w.finish();
}

Base decode_base(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::base);
  Base m;
  m.model = r.string(kMaxNameBytes, "model");
  for (float& v : m.bbox_min) v = r.finite_f32("bbox min");
  for (float& v : m.bbox_max) v = r.finite_f32("bbox max");
  m.scale = r.finite_f32("scale");
  if (m.scale < 0) r.fail(ErrorCode::bad_message, "scale", "is negative");
  m.tree_id_bits = r.u8("tree_id_bits");
  m.node_id_bits = r.u8("node_id_bits");
  m.position_bits = r.u8("position bits");
  const uint8_t flags = r.u8("flags");
  if (flags & ~(kFlagNormals | kFlagColors)) r.fail(ErrorCode::bad_message, "flags", "unknown bits set");
  m.has_normals = flags & kFlagNormals;
  m.has_colors = flags & kFlagColors;
  const uint32_t roots = r.u32("root count");
  const uint32_t faces = r.u32("face count");

  StreamContext c = context_fields(m);
  c.root_count = roots;
  if (const std::string why = check_context(c); !why.empty()) r.fail(ErrorCode::bad_message, "header", why);
  // Both counts against the bytes left before anything is allocated (each alone, then together).
  r.check_count(roots, root_bits(c), "root count");
  r.check_count(faces, 3 * uint64_t(c.tree_id_bits), "face count");
  if (roots * root_bits(c) + faces * 3 * uint64_t(c.tree_id_bits) > r.bits_left())
    r.fail(ErrorCode::bad_message, "face count", "roots and faces do not fit in the payload");

  m.positions.resize(3 * size_t(roots));
  m.refine.resize(roots);
  if (c.has_normals) m.normals.resize(3 * size_t(roots));
  if (c.has_colors) m.colors.resize(4 * size_t(roots));
  for (uint32_t i = 0; i < roots; ++i) {
    r.set_item("root", i);
    uint32_t q[3];
    for (uint32_t& v : q) v = uint32_t(r.bits(c.grid.bits, "position"));
    dequantize_position(c.grid, q, &m.positions[3 * size_t(i)]);
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(m.positions[3 * size_t(i) + k])) r.fail(ErrorCode::bad_message, "position", "is not finite");
    m.refine[i] = read_refine(r, "refine info");
    if (c.has_normals) {
      const uint16_t n[2] = {r.u16("normal"), r.u16("normal")};
      decode_normal(n, &m.normals[3 * size_t(i)]);
    }
    if (c.has_colors)
      for (int k = 0; k < 4; ++k) m.colors[4 * size_t(i) + k] = r.u8("color");
  }
  m.faces.resize(3 * size_t(faces));
  for (size_t k = 0; k < m.faces.size(); ++k) {
    r.set_item("face", k / 3);
    m.faces[k] = uint32_t(r.bits(c.tree_id_bits, "corner"));
    if (m.faces[k] >= roots)
      r.fail(ErrorCode::bad_id, "corner", std::to_string(m.faces[k]) + " >= root count " + std::to_string(roots));
  }
  r.clear_item();
  r.expect_end();
  return m;
}

Base make_base(const ModelData& model, const std::string& name, uint32_t position_bits) {
  Base m;
  m.model = name;
  const uint32_t roots = model.root_count;
  for (int i = 0; i < 3; ++i) {
    m.bbox_min[i] = model.bbox_min[i];
    m.bbox_max[i] = model.bbox_max[i];
  }
  m.scale = model.scale;
  m.tree_id_bits = tree_id_bits(roots);
  // Nodes are breadth-first by depth: the last one is among the deepest.
  m.node_id_bits = model.node_count() == 0 ? 0 : uint32_t(model.id(uint32_t(model.node_count() - 1)).depth());
  m.position_bits = position_bits;
  m.has_normals = !model.normals.empty();
  m.has_colors = !model.colors.empty();
  m.positions.assign(model.position.begin(), model.position.begin() + 3 * size_t(roots));
  m.refine.assign(model.refine.begin(), model.refine.begin() + roots);
  if (m.has_normals) m.normals.assign(model.normals.begin(), model.normals.begin() + 3 * size_t(roots));
  if (m.has_colors) m.colors.assign(model.colors.begin(), model.colors.begin() + 4 * size_t(roots));
  m.faces.assign(model.base_faces.begin(), model.base_faces.end());
  return m;
}

ModelInfo model_info(const ModelData& model, const std::string& name) {
  ModelInfo info;
  info.name = name;
  info.base_vertices = model.root_count;
  info.vsplits = (model.node_count() - model.root_count) / 2;
  // Full refinement = the input: every split adds f_l and/or f_r (one side is missing on a boundary).
  info.input_faces = model.base_faces.size() / 3;
  for (uint32_t n = 0; n < model.node_count(); ++n)
    if (!model.is_leaf(n)) info.input_faces += (model.cut_left[n] != kNone) + (model.cut_right[n] != kNone);
  info.tree_id_bits = tree_id_bits(model.root_count);
  info.node_id_bits = model.node_count() == 0 ? 0 : uint32_t(model.id(uint32_t(model.node_count() - 1)).depth());
  info.has_normals = !model.normals.empty();
  info.has_colors = !model.colors.empty();
  return info;
}

}  // namespace pms::protocol
