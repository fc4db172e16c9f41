// E10's transmission sizes (multilevel_sizes.h). The ASCII form is cut at its batches ('{' outside a
// comment), two per level; meshoptimizer gets each level's own vertices (4 x u16 lanes on the grid) and
// its triangles as an index sequence (its triangle codec may rotate corners, which the structure keeps).
#include "bench/multilevel_sizes.h"

#include <meshoptimizer.h>

#include <nlohmann/json.hpp>
#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "bench/single_rate_codecs.h"
#include "common/error.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"

namespace pms::bench {
namespace {

// Each level's text, coarsest first; the file's leading comment goes with the first.
std::vector<std::vector<uint8_t>> ascii_levels(const MultilevelMesh& m) {
  const std::string text = format_multilevel_ascii(m);
  std::vector<size_t> batches;
  bool comment = false;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '#') comment = true;
    else if (text[i] == '\n') comment = false;
    else if (text[i] == '{' && !comment) batches.push_back(i);
  }
  if (batches.size() != 2 * size_t(m.level_count()))
    fail("bench", "the ASCII form does not have two batches per level");
  std::vector<std::vector<uint8_t>> out;
  for (size_t l = 0; l < m.level_count(); ++l) {
    const size_t begin = l == 0 ? 0 : batches[2 * l], end = l + 1 < m.level_count() ? batches[2 * l + 2] : text.size();
    out.emplace_back(text.begin() + long(begin), text.begin() + long(end));
  }
  return out;
}

struct MeshoptLevel {
  uint64_t vertex = 0, index = 0;
};

MeshoptLevel meshopt_level(const MultilevelMesh& m, const PositionGrid& grid, uint32_t level) {
  const uint32_t d = m.dimension, v_end = m.vertex_count[level], v_begin = v_end - m.level_vertices(level);
  const uint32_t t_end = m.triangle_count[level], t_begin = t_end - m.level_triangles(level);
  std::vector<uint16_t> lanes;
  for (uint32_t v = v_begin; v < v_end; ++v) {
    float p[3] = {0, 0, 0};
    uint32_t q[3];
    for (uint32_t k = 0; k < d; ++k) p[k] = m.positions[size_t(v) * d + k];
    quantize_position(grid, p, q);
    lanes.insert(lanes.end(), {uint16_t(q[0]), uint16_t(q[1]), uint16_t(q[2]), 0});
  }
  const std::vector<uint32_t> indices(m.triangles.begin() + 3 * size_t(t_begin),
                                      m.triangles.begin() + 3 * size_t(t_end));
  MeshoptLevel out;
  std::vector<uint8_t> bytes(meshopt_encodeVertexBufferBound(lanes.size() / 4, 8));
  out.vertex = meshopt_encodeVertexBuffer(bytes.data(), bytes.size(), lanes.data(), lanes.size() / 4, 8);
  bytes.assign(meshopt_encodeIndexSequenceBound(indices.size(), m.vertices()), 0);
  out.index = meshopt_encodeIndexSequence(bytes.data(), bytes.size(), indices.data(), indices.size());
  std::vector<uint32_t> back(indices.size());
  if (meshopt_decodeIndexSequence(back.data(), back.size(), sizeof(uint32_t), bytes.data(), out.index) != 0 ||
      back != indices)
    fail("meshoptimizer", "a level's index sequence does not round-trip");
  return out;
}

// A client's decoding time for the compressed form, head and every level: each level's fastest of a few
// loads, summed (the machine's other work then shows in none of them).
double compressed_decode_ms(const MultilevelParts& compressed) {
  std::vector<double> fastest(compressed.levels.size(), 0);
  for (int run = 0; run < 5; ++run) {
    MultilevelLoader loader("bench", compressed.head, {}, MultilevelForm::compressed);
    for (size_t i = 0; i < compressed.levels.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      loader.add_level("bench", compressed.levels[i]);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      fastest[i] = run == 0 ? ms : std::min(fastest[i], ms);
    }
  }
  double sum = 0;
  for (double ms : fastest) sum += ms;
  return sum;
}

}  // namespace

MultilevelSizes multilevel_sizes(const MultilevelMesh& m, uint32_t position_bits, nlohmann::json& per_level) {
  std::vector<CompressedLevelBits> bits;
  const MultilevelParts compressed = multilevel_compressed_parts(m, position_bits, &bits);
  const MultilevelParts binary = multilevel_parts(m);
  const std::vector<std::vector<uint8_t>> ascii = ascii_levels(m);
  const PositionGrid grid = multilevel_grid(m, position_bits);
  MultilevelSizes total;
  per_level = nlohmann::json::array();
  for (size_t i = 0; i < compressed.levels.size(); ++i) {
    const uint32_t level = m.level_count() - 1 - uint32_t(i);
    const uint32_t vertices = m.level_vertices(level), triangles = m.level_triangles(level);
    const CompressedLevelBits& b = bits[i];
    // The header and tables are shared out by the part's share of the level.
    const uint64_t body = b.vertices + b.triangles + b.representatives;
    const uint64_t vertex_bits = b.vertices + (body ? b.header * b.vertices / body : 0);
    const uint64_t triangle_bits = b.total() - vertex_bits;
    const MeshoptLevel mo = position_bits <= 16 ? meshopt_level(m, grid, level) : MeshoptLevel{};
    const uint64_t binary_gzip = gzip9(binary.levels[i]).size(), ascii_gzip = gzip9(ascii[i]).size();
    per_level.push_back({{"level", level},
                         {"vertices", vertices},
                         {"triangles", triangles},
                         {"compressed_bytes", compressed.levels[i].size()},
                         {"compressed_bits",
                          {{"header", b.header},
                           {"representatives", b.representatives},
                           {"vertices", b.vertices},
                           {"triangles", b.triangles}}},
                         {"bits_per_vertex", vertices ? double(vertex_bits) / vertices : 0.0},
                         {"bits_per_triangle", triangles ? double(triangle_bits) / triangles : 0.0},
                         {"binary_bytes", binary.levels[i].size()},
                         {"binary_gzip_bytes", binary_gzip},
                         {"ascii_bytes", ascii[i].size()},
                         {"ascii_gzip_bytes", ascii_gzip},
                         {"meshopt_vertex_bytes", mo.vertex},
                         {"meshopt_index_bytes", mo.index}});
    total.compressed += compressed.levels[i].size();
    total.binary += binary.levels[i].size();
    total.binary_gzip += binary_gzip;
    total.ascii += ascii[i].size();
    total.ascii_gzip += ascii_gzip;
    total.vertex_bits += vertex_bits;
    total.triangle_bits += triangle_bits;
    total.meshopt_vertex += mo.vertex;
    total.meshopt_index += mo.index;
    total.parts.header += b.header;
    total.parts.representatives += b.representatives;
    total.parts.vertices += b.vertices;
    total.parts.triangles += b.triangles;
    total.parts.changed += b.changed;
  }
  total.decode_ms = compressed_decode_ms(compressed);
  return total;
}

}  // namespace pms::bench
