#include "bench/openmesh_pm.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <vector>

#include "common/error.h"
#include "spm/hierarchy.h"

namespace pms::bench {
namespace {

constexpr char kMagic[8] = {'P', 'r', 'o', 'g', 'M', 'e', 's', 'h'};
constexpr uint32_t kAbsent = 0xffffffff;  // OpenMesh's invalid vertex handle: no vl (or vr) at a boundary
constexpr uint64_t kHeaderBytes = sizeof kMagic + 3 * 4;
constexpr uint64_t kPositionBytes = 3 * 4;
constexpr uint64_t kFaceBytes = 3 * 4;
constexpr uint64_t kDetailBytes = kPositionBytes + 3 * 4;

uint32_t load_u32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

std::string n(uint64_t value) { return std::to_string(value); }

// Base faces may only use base vertices; returns which base vertices they use.
std::vector<uint8_t> check_base_faces(const uint8_t* faces, const OpenMeshPmStats& s, const std::string& name) {
  std::vector<uint8_t> used(s.base_vertices, 0);
  for (uint32_t f = 0; f < s.base_faces; ++f) {
    for (int corner = 0; corner < 3; ++corner) {
      const uint32_t v = load_u32(faces + f * kFaceBytes + corner * 4);
      if (v >= s.base_vertices)
        fail(name,
             "base face " + n(f) + " uses vertex " + n(v) + " but there are " + n(s.base_vertices) + " base vertices");
      used[v] = 1;
    }
  }
  return used;
}

}  // namespace

OpenMeshPmStats parse_openmesh_pm(std::span<const uint8_t> bytes, const std::string& name) {
  if (bytes.size() < kHeaderBytes)
    fail(name, "truncated: " + n(bytes.size()) + " bytes, shorter than the " + n(kHeaderBytes) + "-byte header");
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    fail(name, "not an OpenMesh progressive mesh (does not start with \"ProgMesh\")");
  OpenMeshPmStats s;
  s.base_vertices = load_u32(bytes.data() + 8);
  s.base_faces = load_u32(bytes.data() + 12);
  s.details = load_u32(bytes.data() + 16);

  // The counts must describe exactly this many bytes, checked before anything is allocated.
  const uint64_t expected =
      kHeaderBytes + s.base_vertices * kPositionBytes + s.base_faces * kFaceBytes + s.details * kDetailBytes;
  if (expected != bytes.size())
    fail(name, "header says " + n(s.base_vertices) + " base vertices, " + n(s.base_faces) + " base faces and " +
                   n(s.details) + " details (" + n(expected) + " bytes) but the file has " + n(bytes.size()) +
                   " bytes");
  const uint64_t vertex_count = uint64_t(s.base_vertices) + s.details;
  if (vertex_count >= kAbsent) fail(name, n(vertex_count) + " vertices do not fit 32-bit vertex indices");

  const uint8_t* faces = bytes.data() + kHeaderBytes + s.base_vertices * kPositionBytes;
  std::vector<uint8_t> used = check_base_faces(faces, s, name);

  // A split of v1 puts both v1 and the new vertex one level below v1's old node, so the height of
  // the hierarchy is the deepest any vertex gets.
  std::vector<uint32_t> depth(vertex_count, 0);
  const uint8_t* detail = faces + s.base_faces * kFaceBytes;
  for (uint32_t i = 0; i < s.details; ++i, detail += kDetailBytes) {
    const uint32_t existing = s.base_vertices + i;  // the new vertex's index; all below it exist
    const uint32_t v1 = load_u32(detail + kPositionBytes);
    const uint32_t vl = load_u32(detail + kPositionBytes + 4);
    const uint32_t vr = load_u32(detail + kPositionBytes + 8);
    if (v1 >= existing)
      fail(name, "detail " + n(i) + " splits vertex " + n(v1) + " but only " + n(existing) + " vertices exist yet");
    for (const uint32_t v : {vl, vr})
      if (v != kAbsent && v >= existing)
        fail(name,
             "detail " + n(i) + " names neighbour vertex " + n(v) + " but only " + n(existing) + " vertices exist yet");
    depth[existing] = depth[v1] = depth[v1] + 1;
    s.max_depth = std::max(s.max_depth, depth[v1]);
    if (v1 < s.base_vertices) used[v1] = 1;
  }
  s.isolated_base_vertices = uint32_t(std::count(used.begin(), used.end(), uint8_t(0)));
  s.tree_id_bits = tree_id_bits(s.base_vertices);
  return s;
}

OpenMeshPmStats read_openmesh_pm(const std::string& path) {
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) fail(path, "cannot open");
  const std::streamoff size = file.tellg();
  if (size < 0) fail(path, "cannot read its size");
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  file.seekg(0);
  if (!file.read(reinterpret_cast<char*>(bytes.data()), size)) fail(path, "read error");
  return parse_openmesh_pm(bytes, path);
}

}  // namespace pms::bench
