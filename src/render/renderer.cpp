// The frame pipeline: normals -> vertex stage -> triangle setup and binning -> tiles. Every parallel
// pass splits its work into pieces whose boundaries do not depend on the thread count (vertex blocks,
// face chunks, tiles) and whose results are combined in a fixed order, so the image is bit-identical for
// 1 or N threads. Threads are started per pass: a few tens of microseconds against frames of milliseconds.
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

#include "common/error.h"
#include "render/raster_internal.h"
#include "spm/vertex_id.h"

namespace pms {

using namespace render_detail;

struct Renderer::Scratch {
  VertexData vertices;
  std::vector<std::vector<Tri>> chunk_tris;           // per face chunk, in face order
  std::vector<std::vector<uint32_t>> chunk_tri_tile;  // per triangle: its only tile, or kNone
  std::vector<uint32_t> tile_counts;                  // [chunk][tile], then per-chunk write cursors
  std::vector<uint32_t> bin_start;                    // [tile][chunk] + 1: entries of tile t, chunk c
  std::vector<uint32_t> entries;                      // triangle indices (into their chunk's array)
};

namespace render_detail {

void parallel_for(unsigned threads, size_t count, const std::function<void(size_t)>& fn) {
  if (threads <= 1 || count <= 1) {
    for (size_t i = 0; i < count; ++i) fn(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    try {
      for (size_t i; (i = next.fetch_add(1)) < count;) fn(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = count;
    }
  };
  std::vector<std::thread> pool;
  const size_t extra = std::min<size_t>(threads, count) - 1;
  for (size_t t = 0; t < extra; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace render_detail

namespace {

constexpr size_t kVertexBlock = 16384;
constexpr size_t kMinChunkFaces = 4096;
constexpr size_t kMaxChunks = 256;
constexpr size_t kMaxBinSlots = size_t(1) << 22;  // tiles x chunks: bounds the count arrays for huge images

void check_mesh(const RenderMesh& mesh) {
  if (mesh.positions.size() % 3 != 0) fail("render", "positions must hold 3 floats per vertex");
  if (mesh.indices.size() % 3 != 0) fail("render", "indices must hold 3 per face");
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size() / 3 * 4)
    fail("render", "colors must hold 4 bytes per vertex");
  if (mesh.indices.size() / 3 >= kNone) fail("render", "too many faces for 32-bit face ids");
}

// Chunk boundaries depend on the face and tile counts only, never on the threads.
size_t chunk_faces(size_t face_count, size_t tile_count) {
  size_t size = std::max(kMinChunkFaces, (face_count + kMaxChunks - 1) / kMaxChunks);
  const size_t max_chunks = std::max<size_t>(1, kMaxBinSlots / tile_count);
  return std::max(size, (face_count + max_chunks - 1) / max_chunks);
}

}  // namespace

Renderer::Renderer() : scratch_(std::make_unique<Scratch>()) {}
Renderer::~Renderer() = default;

void Renderer::render(const RenderMesh& mesh, const ViewParams& view, Image& out, const RenderOptions& options) {
  check_mesh(mesh);
  if (view.camera.width == 0 || view.camera.height == 0) fail("render", "empty viewport");
  const Frame frame = make_frame(view);
  const unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  Scratch& s = *scratch_;
  const size_t vertex_count = mesh.positions.size() / 3, face_count = mesh.indices.size() / 3;

  // Each thread owns a vertex range and scans every face: a vertex's normal is summed in face order
  // whatever the ranges are (floating-point addition is not associative).
  VertexData& v = s.vertices;
  if (options.shade) {
    v.normals.resize(3 * vertex_count);
    const size_t normal_ranges = std::min<size_t>(threads, std::max<size_t>(1, vertex_count / kVertexBlock));
    parallel_for(threads, normal_ranges, [&](size_t r) {
      accumulate_normals(mesh, vertex_count * r / normal_ranges, vertex_count * (r + 1) / normal_ranges, v.normals);
    });
  } else {
    check_indices(mesh);
  }
  v.clip.resize(4 * vertex_count);
  v.screen.resize(vertex_count);
  v.color.resize(vertex_count);
  v.outcode.resize(vertex_count);
  parallel_for(threads, (vertex_count + kVertexBlock - 1) / kVertexBlock, [&](size_t block) {
    transform_vertices(mesh, view, frame, options, block * kVertexBlock,
                       std::min(vertex_count, (block + 1) * kVertexBlock), v);
  });

  const size_t tiles = size_t(frame.tiles_x) * frame.tiles_y;
  const size_t chunk = chunk_faces(face_count, tiles);
  const size_t chunks = (face_count + chunk - 1) / chunk;
  s.chunk_tris.resize(std::max(s.chunk_tris.size(), chunks));
  s.chunk_tri_tile.resize(s.chunk_tris.size());
  s.tile_counts.assign(chunks * tiles, 0);
  parallel_for(threads, chunks, [&](size_t c) {
    setup_faces(mesh, v, frame, c * chunk, std::min(face_count, (c + 1) * chunk), s.chunk_tris[c], s.chunk_tri_tile[c],
                &s.tile_counts[c * tiles]);
  });

  // Tile-major prefix sums: tile t's entries are contiguous, chunk after chunk, i.e. in face order.
  s.bin_start.resize(tiles * chunks + 1);
  uint64_t total = 0;
  for (size_t t = 0; t < tiles; ++t)
    for (size_t c = 0; c < chunks; ++c) {
      s.bin_start[t * chunks + c] = uint32_t(total);
      uint32_t& count = s.tile_counts[c * tiles + t];
      total += count;
      if (total >= kNone) fail("render", "too many triangle-tile overlaps for one frame");
      count = s.bin_start[t * chunks + c];  // becomes chunk c's write cursor for tile t
    }
  s.bin_start[tiles * chunks] = uint32_t(total);
  s.entries.resize(total);
  parallel_for(threads, chunks, [&](size_t c) {
    bin_triangles(s.chunk_tris[c], s.chunk_tri_tile[c], frame, &s.tile_counts[c * tiles], s.entries.data());
  });

  out.width = frame.width;
  out.height = frame.height;
  const size_t pixels = size_t(frame.width) * frame.height;
  if (options.shade) out.rgb.resize(3 * pixels);
  else out.rgb.clear();
  out.depth.resize(pixels);
  out.face_id.resize(pixels);
  Target target{options.shade ? out.rgb.data() : nullptr, out.depth.data(), out.face_id.data(), {}};
  for (int k = 0; k < 3; ++k) target.background[k] = options.background[k];
  parallel_for(threads, tiles, [&](size_t t) {
    clear_tile(frame, uint32_t(t), target);
    for (size_t c = 0; c < chunks; ++c)
      raster_tile(frame, uint32_t(t), s.chunk_tris[c].data(), s.entries.data(), s.bin_start[t * chunks + c],
                  s.bin_start[t * chunks + c + 1], target);
  });
}

Image render(const RenderMesh& mesh, const ViewParams& view, const RenderOptions& options) {
  Renderer renderer;
  Image image;
  renderer.render(mesh, view, image, options);
  return image;
}

}  // namespace pms
