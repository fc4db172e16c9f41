// save_ply: the PLY that load_mesh reads back exactly. Binary is little-endian float32 (so positions,
// normals and texture coordinates survive bit for bit); ascii uses shortest round-trip float formatting
// for the same. Texture coordinates are written as `s t`, the names Blender writes and reads (the
// importer also takes u v, texture_u texture_v and texture_s texture_t).
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "common/bit_cast.h"
#include "common/error.h"
#include "io/mesh.h"

namespace pms {

namespace {

void check_writable(const Mesh& mesh, const std::string& path) {
  const size_t n = mesh.vertex_count();
  if (mesh.positions.size() % 3 != 0 || mesh.indices.size() % 3 != 0)
    fail(path, "cannot save: positions or indices are not whole triples");
  if (mesh.has_normals() && mesh.normals.size() != n * 3) fail(path, "cannot save: normals do not match the vertices");
  if (mesh.has_colors() && mesh.colors.size() != n * 4) fail(path, "cannot save: colors do not match the vertices");
  if (mesh.has_texcoords() && mesh.texcoords.size() != n * 2)
    fail(path, "cannot save: texture coordinates do not match the vertices");
  if (n > size_t(INT32_MAX)) fail(path, "cannot save: PLY 'int' indices hold at most 2^31-1 vertices");
  for (uint32_t index : mesh.indices)
    if (index >= n) fail(path, "cannot save: face index " + std::to_string(index) + " out of range");
}

std::string header(const Mesh& mesh, bool binary) {
  std::string h = "ply\nformat ";
  h += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  h += "comment written by pmstream\n";
  h += "element vertex " + std::to_string(mesh.vertex_count()) + "\n";
  h += "property float x\nproperty float y\nproperty float z\n";
  if (mesh.has_normals()) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (mesh.has_colors()) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  if (mesh.has_texcoords()) h += "property float s\nproperty float t\n";
  h += "element face " + std::to_string(mesh.face_count()) + "\n";
  h += "property list uchar int vertex_indices\nend_header\n";
  return h;
}

// Little-endian bytes of a 32-bit value, whatever the host order.
void put32(std::string& out, uint32_t u) {
  if constexpr (std::endian::native == std::endian::big) u = __builtin_bswap32(u);
  out.append(reinterpret_cast<const char*>(&u), 4);
}

void put_number(std::string& out, auto value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);  // shortest round-trip form
  out.append(buffer, result.ptr);
}

void vertex_record(std::string& out, const Mesh& mesh, size_t v, bool binary) {
  const auto put_float = [&](float x) {
    if (binary) {
      put32(out, bit_cast<uint32_t>(x));
    } else {
      put_number(out, x);
      out += ' ';
    }
  };
  for (int c = 0; c < 3; ++c) put_float(mesh.positions[v * 3 + c]);
  if (mesh.has_normals())
    for (int c = 0; c < 3; ++c) put_float(mesh.normals[v * 3 + c]);
  if (mesh.has_colors())
    for (int c = 0; c < 4; ++c) {
      const uint8_t channel = mesh.colors[v * 4 + c];
      if (binary) {
        out += char(channel);
      } else {
        put_number(out, unsigned(channel));
        out += ' ';
      }
    }
  if (mesh.has_texcoords())
    for (int c = 0; c < 2; ++c) put_float(mesh.texcoords[v * 2 + c]);
  if (!binary) out.back() = '\n';
}

void face_record(std::string& out, const Mesh& mesh, size_t f, bool binary) {
  if (binary) {
    out += char(3);
    for (int c = 0; c < 3; ++c) put32(out, mesh.indices[f * 3 + c]);
    return;
  }
  out += '3';
  for (int c = 0; c < 3; ++c) {
    out += ' ';
    put_number(out, mesh.indices[f * 3 + c]);
  }
  out += '\n';
}

class Writer {
 public:
  explicit Writer(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "wb"), std::fclose) {
    if (!file_) fail(path, std::string("cannot create (") + std::strerror(errno) + ")");
  }

  // Records collect in a buffer written in big chunks; fine-grained fwrite calls dominate otherwise.
  std::string& buffer() { return buffer_; }
  void flush_if_full() {
    if (buffer_.size() >= (size_t(1) << 20)) flush();
  }
  void flush() {
    if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_.get()) != buffer_.size())
      fail(path_, std::string("write error (") + std::strerror(errno) + ")");
    buffer_.clear();
  }
  void close() {
    flush();
    if (std::fclose(file_.release()) != 0) fail(path_, std::string("write error (") + std::strerror(errno) + ")");
  }

 private:
  const std::string& path_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_;
  std::string buffer_;
};

}  // namespace

void save_ply(const Mesh& mesh, const std::string& path, bool binary) {
  check_writable(mesh, path);
  Writer writer(path);
  writer.buffer() = header(mesh, binary);
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    vertex_record(writer.buffer(), mesh, v, binary);
    writer.flush_if_full();
  }
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    face_record(writer.buffer(), mesh, f, binary);
    writer.flush_if_full();
  }
  writer.close();
}

}  // namespace pms
