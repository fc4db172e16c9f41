#include "bench/single_rate_codecs.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <meshoptimizer.h>
#include <zlib.h>
#include <zstd.h>

#include <cstring>
#include <vector>

#include "common/error.h"

namespace pms::bench {
namespace {

// x, y, z and a zero lane: meshoptimizer's vertex codec takes strides that are multiples of 4.
struct GridVertex {
  uint16_t q[4];
};

std::vector<GridVertex> grid_vertices(const Mesh& mesh, const PositionGrid& grid) {
  std::vector<GridVertex> out(mesh.vertex_count());
  for (size_t v = 0; v < out.size(); ++v) {
    uint32_t q[3];
    quantize_position(grid, &mesh.positions[3 * v], q);
    out[v] = {{uint16_t(q[0]), uint16_t(q[1]), uint16_t(q[2]), 0}};
  }
  return out;
}

std::vector<uint8_t> zstd19(const std::vector<uint8_t>& in) {
  std::vector<uint8_t> out(ZSTD_compressBound(in.size()));
  const size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 19);
  if (ZSTD_isError(n)) fail("zstd", ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

// The index codec keeps the triangles' order and orientation but may rotate a triangle's corners.
bool same_triangles(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); i += 3) {
    bool any = false;
    for (int r = 0; r < 3; ++r)
      any |= a[i] == b[i + r] && a[i + 1] == b[i + (r + 1) % 3] && a[i + 2] == b[i + (r + 2) % 3];
    if (!any) return false;
  }
  return true;
}

// meshoptimizer as its documentation prescribes for transmission: vertex cache order, then vertices in
// first-use order, then the two codecs. Returns the two streams, concatenated, after checking both decode.
std::vector<uint8_t> meshopt_streams(const Mesh& mesh, const PositionGrid& grid, SingleRateSizes& sizes) {
  std::vector<GridVertex> vertices = grid_vertices(mesh, grid);
  std::vector<uint32_t> indices(mesh.indices.size());
  meshopt_optimizeVertexCache(indices.data(), mesh.indices.data(), indices.size(), vertices.size());
  const size_t used = meshopt_optimizeVertexFetch(vertices.data(), indices.data(), indices.size(), vertices.data(),
                                                  vertices.size(), sizeof(GridVertex));
  vertices.resize(used);

  std::vector<uint8_t> index_bytes(meshopt_encodeIndexBufferBound(indices.size(), vertices.size()));
  index_bytes.resize(meshopt_encodeIndexBuffer(index_bytes.data(), index_bytes.size(), indices.data(), indices.size()));
  std::vector<uint8_t> vertex_bytes(meshopt_encodeVertexBufferBound(vertices.size(), sizeof(GridVertex)));
  vertex_bytes.resize(meshopt_encodeVertexBuffer(vertex_bytes.data(), vertex_bytes.size(), vertices.data(),
                                                 vertices.size(), sizeof(GridVertex)));

  std::vector<uint32_t> indices_back(indices.size());
  std::vector<GridVertex> vertices_back(vertices.size());
  if (meshopt_decodeIndexBuffer(indices_back.data(), indices_back.size(), sizeof(uint32_t), index_bytes.data(),
                                index_bytes.size()) != 0 ||
      !same_triangles(indices_back, indices))
    fail("meshoptimizer", "the index buffer does not round-trip");
  if (meshopt_decodeVertexBuffer(vertices_back.data(), vertices_back.size(), sizeof(GridVertex), vertex_bytes.data(),
                                 vertex_bytes.size()) != 0 ||
      std::memcmp(vertices_back.data(), vertices.data(), vertices.size() * sizeof(GridVertex)) != 0)
    fail("meshoptimizer", "the vertex buffer does not round-trip");

  sizes.meshopt_index = index_bytes.size();
  sizes.meshopt_vertex = vertex_bytes.size();
  index_bytes.insert(index_bytes.end(), vertex_bytes.begin(), vertex_bytes.end());
  return index_bytes;
}

// Draco's edgebreaker at its densest setting (`draco_encoder -qp BITS -cl 10`), on the grid's snapped positions.
void draco_size(const Mesh& mesh, const PositionGrid& grid, SingleRateSizes& sizes) {
  draco::Mesh d;
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, 3 * sizeof(float), 0);
  const int attribute = d.AddAttribute(position, true, uint32_t(mesh.vertex_count()));
  d.set_num_points(uint32_t(mesh.vertex_count()));
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    float snapped[3];
    snap_position(grid, &mesh.positions[3 * v], snapped);
    d.attribute(attribute)->SetAttributeValue(draco::AttributeValueIndex(uint32_t(v)), snapped);
  }
  for (size_t f = 0; f < mesh.face_count(); ++f)
    d.AddFace({draco::PointIndex(mesh.indices[3 * f]), draco::PointIndex(mesh.indices[3 * f + 1]),
               draco::PointIndex(mesh.indices[3 * f + 2])});

  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, int(grid.bits));
  encoder.SetSpeedOptions(0, 0);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(d, &buffer);
  if (!status.ok()) {
    sizes.draco_error = status.error_msg_string();
    return;
  }
  draco::DecoderBuffer in;
  in.Init(buffer.data(), buffer.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&in);
  if (!decoded.ok() || decoded.value()->num_faces() != mesh.face_count())
    fail("draco", "the mesh does not decode to its own face count");
  sizes.draco = buffer.size();
}

}  // namespace

std::vector<uint8_t> gzip9(const std::vector<uint8_t>& in) {
  z_stream z{};
  if (deflateInit2(&z, 9, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) fail("gzip", "deflateInit2 failed");
  std::vector<uint8_t> out(deflateBound(&z, uLong(in.size())));
  z.next_in = const_cast<Bytef*>(in.data());
  z.avail_in = uInt(in.size());
  z.next_out = out.data();
  z.avail_out = uInt(out.size());
  const int status = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (status != Z_STREAM_END) fail("gzip", "deflate did not finish");
  return out;
}

SingleRateSizes single_rate_codecs(const Mesh& mesh, const PositionGrid& grid) {
  if (grid.bits > 16) fail("single-rate codecs", "positions over 16 bits do not fit meshoptimizer's lanes");
  SingleRateSizes sizes;
  sizes.vertices = mesh.vertex_count();
  sizes.faces = mesh.face_count();
  const std::vector<uint8_t> meshopt = meshopt_streams(mesh, grid, sizes);
  sizes.meshopt_gzip = gzip9(meshopt).size();
  sizes.meshopt_zstd = zstd19(meshopt).size();
  draco_size(mesh, grid, sizes);
  return sizes;
}

}  // namespace pms::bench
