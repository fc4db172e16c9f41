// libFuzzer target for the compressed levels' decoder (multilevel/codec.h) behind addLevel. Three
// kinds of input, told apart by the first byte:
//   'R' raw: a compressed head (64 bytes, or 80 when its HEAD flags texture coordinates), then levels, each
//       a u32 little-endian length and that many bytes, coarsest first, as a client receives them;
//   'T' patches, as below, on the sphere with texture coordinates (their grid, codes and predictions);
//   else patches: (u32 position, u8 xor) records applied to the compressed form of a small built sphere
//       (head and levels concatenated), which reaches past the head and table checks without a corpus.
// Every prefix of the levels either loads, with every LOD and geomorph of what is loaded takeable, or
// throws pms::Error; crashes, hangs, sanitizer reports and huge allocations are findings.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "builder/build.h"
#include "common/error.h"
#include "io/shapes.h"
#include "multilevel/build.h"
#include "multilevel/codec.h"
#include "multilevel/loader.h"
#include "multilevel/mesh.h"
#include "multilevel_touch.h"

namespace {

using fuzz::kLimits;
using fuzz::touch;
constexpr size_t kHeadBytes = 64, kTexcoordBoxBytes = 16, kHeadFlagsAt = 8, kHasTexcoords = 4;

// The head and the levels with their lengths, as raw input would give them.
struct Pieces {
  std::vector<uint8_t> head;
  std::vector<std::vector<uint8_t>> levels;
};

void load(const Pieces& pieces) {
  try {
    pms::MultilevelLoader loader("fuzz", pieces.head, kLimits, pms::MultilevelForm::compressed);
    for (const auto& level : pieces.levels) {
      if (loader.complete()) break;
      loader.add_level("fuzz", level);
      touch(loader.mesh());
    }
  } catch (const pms::Error&) {
  }
}

Pieces raw_pieces(std::span<const uint8_t> bytes) {
  Pieces out;
  if (bytes.size() < kHeadBytes) return out;
  const size_t head_bytes = kHeadBytes + (bytes[kHeadFlagsAt] & kHasTexcoords ? kTexcoordBoxBytes : 0);
  if (bytes.size() < head_bytes) return out;
  out.head.assign(bytes.begin(), bytes.begin() + long(head_bytes));
  size_t at = head_bytes;
  while (bytes.size() - at >= 4) {
    uint32_t length;
    std::memcpy(&length, bytes.data() + at, 4);
    at += 4;
    if (length > bytes.size() - at) break;
    out.levels.emplace_back(bytes.begin() + long(at), bytes.begin() + long(at + length));
    at += length;
  }
  return out;
}

// The sphere's compressed form; `textured`: with texture coordinates (a planar projection, 10-bit grid).
Pieces compressed_sphere(bool textured) {
  pms::Mesh mesh = pms::make_sphere(12, 16);
  if (textured)
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
      mesh.texcoords.insert(mesh.texcoords.end(), {mesh.positions[3 * v], mesh.positions[3 * v + 2]});
  const pms::BuildResult built = pms::build_progressive_mesh(mesh);
  pms::MultilevelParts parts = pms::multilevel_compressed_parts(
      pms::build_multilevel(mesh, pms::collapses_of(built.hierarchy), 6), 12, nullptr, 10);
  return Pieces{std::move(parts.head), std::move(parts.levels)};
}

const Pieces& sphere(bool textured) {
  static const Pieces plain = compressed_sphere(false), with_texcoords = compressed_sphere(true);
  return textured ? with_texcoords : plain;
}

Pieces patched(std::span<const uint8_t> patches, bool textured) {
  Pieces out = sphere(textured);
  size_t total = out.head.size();
  for (const auto& level : out.levels) total += level.size();
  for (size_t k = 0; k + 5 <= patches.size(); k += 5) {
    uint32_t at;
    std::memcpy(&at, patches.data() + k, 4);
    at %= uint32_t(total);
    std::vector<uint8_t>* piece = &out.head;
    for (size_t i = 0; at >= piece->size(); ++i) {
      at -= uint32_t(piece->size());
      piece = &out.levels[i];
    }
    (*piece)[at] ^= patches[k + 4];
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::span<const uint8_t> bytes(data + 1, size - 1);
  load(data[0] == 'R' ? raw_pieces(bytes) : patched(bytes, data[0] == 'T'));
  return 0;
}
