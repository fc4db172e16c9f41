// load_mesh: read the file, peel a .gz/.xz layer, pick the importer by the inner extension, then
// check what every importer's output must satisfy before the rest of the pipeline trusts it.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "common/error.h"
#include "io/decompress.h"
#include "io/import_internal.h"
#include "io/mesh.h"

namespace pms {

namespace {

std::vector<uint8_t> read_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not a mesh file");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), std::fclose);
  if (!file) fail(path, std::string("cannot open (") + std::strerror(errno) + ")");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) fail(path, "cannot read its size (" + ec.message() + ")");
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  if (std::fread(bytes.data(), 1, bytes.size(), file.get()) != bytes.size())
    fail(path, std::ferror(file.get()) ? std::string("read error (") + std::strerror(errno) + ")"
                                       : std::string("the file shrank while being read"));
  return bytes;
}

std::string lower_extension(std::string_view name) {
  const std::string extension = std::filesystem::path(name).extension().string();
  std::string lower;
  for (char c : extension.empty() ? extension : extension.substr(1)) lower += char(std::tolower(uint8_t(c)));
  return lower;
}

// Vertex of the first NaN or infinite value in an array of `width` floats per vertex, or -1.
ptrdiff_t first_non_finite_vertex(const std::vector<float>& values, ptrdiff_t width = 3) {
  const auto bad = std::find_if(values.begin(), values.end(), [](float x) { return !std::isfinite(x); });
  return bad == values.end() ? -1 : (bad - values.begin()) / width;
}

// The invariants the builder relies on, whatever format the mesh came from.
void validate(const std::string& name, const Mesh& mesh) {
  if (mesh.face_count() == 0) fail(name, "no faces (not a surface mesh)");
  if (const ptrdiff_t v = first_non_finite_vertex(mesh.positions); v >= 0)
    fail(name, "vertex " + std::to_string(v) + " has a NaN or infinite coordinate");
  if (const ptrdiff_t v = first_non_finite_vertex(mesh.normals); v >= 0)
    fail(name, "vertex " + std::to_string(v) + " has a NaN or infinite normal");
  if (const ptrdiff_t v = first_non_finite_vertex(mesh.texcoords, 2); v >= 0)
    fail(name, "vertex " + std::to_string(v) + " has a NaN or infinite texture coordinate");
  const size_t vertex_count = mesh.vertex_count();
  const auto out_of_range =
      std::find_if(mesh.indices.begin(), mesh.indices.end(), [&](uint32_t i) { return i >= vertex_count; });
  if (out_of_range != mesh.indices.end())
    fail(name, "face " + std::to_string((out_of_range - mesh.indices.begin()) / 3) + " uses vertex " +
                   std::to_string(*out_of_range) + " but there are only " + std::to_string(vertex_count) + " vertices");
}

// Maps an importer's [0, 1] onto [lo, 1] of the "load" phase, after the decompression share.
ProgressFn sub_progress(const ProgressFn& progress, double lo, double hi) {
  if (!progress) return {};
  return [&progress, lo, hi](std::string_view phase, double fraction) { progress(phase, lo + (hi - lo) * fraction); };
}

Mesh import_bytes(const std::string& name, std::span<const uint8_t> bytes, const ProgressFn& progress) {
  const Compression codec = compression_of(name);
  std::vector<uint8_t> inflated;
  double parse_start = 0.0;
  if (codec != Compression::none) {
    // Decompression takes most of a compressed input's load (xz more than parsing the text it holds).
    parse_start = 0.8;
    inflated = decompress(name, codec, bytes, sub_progress(progress, 0.0, parse_start));
    bytes = inflated;
  }
  const std::string extension = lower_extension(strip_compression_suffix(name));
  const ProgressFn parse_progress = sub_progress(progress, parse_start, 1.0);
  Mesh mesh;
  if (extension == "ply") mesh = import_ply(name, bytes, parse_progress);
  else if (extension == "obj") mesh = import_obj(name, bytes, parse_progress);
  else if (extension == "off") mesh = import_off(name, bytes, parse_progress);
  else mesh = import_assimp(name, bytes, extension);
  validate(name, mesh);
  report(progress, "load", 1.0);
  return mesh;
}

}  // namespace

Mesh load_mesh(const std::string& path, const ProgressFn& progress) {
  report(progress, "load", 0.0);
  return import_bytes(path, read_file(path), progress);
}

Mesh load_mesh_from_memory(const std::string& name, const std::vector<uint8_t>& bytes) {
  return import_bytes(name, bytes, {});
}

}  // namespace pms
