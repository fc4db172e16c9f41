// Wavefront OBJ, the subset that meshes use: 'v x y z [w]' or 'v x y z r g b' (per-vertex colors
// as MeshLab writes them, in [0, 1]), 'vt u [v [w]]', and 'f' with corners 'a', 'a/t', 'a//n' or
// 'a/t/n' where a negative index counts back from the latest vertex (or texture vertex). Polygons are
// fan-triangulated. Texture coordinates belong to corners in OBJ: they are kept when every corner names
// one, and a vertex used with several of them is split into one copy per texture vertex (a seam), the
// first one keeping the vertex's number, the others appended in the order they are met. Everything else
// (vn, groups, materials, lines) is ignored: OBJ normals belong to corners too, and the shading normals
// of a scan are better recomputed than split for.
#include <algorithm>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/error.h"
#include "io/import_internal.h"
#include "io/text_internal.h"

namespace pms {

namespace {

constexpr size_t kReportBytes = size_t(4) << 20;

constexpr uint32_t kNoTexcoord = UINT32_MAX;

struct ObjParser {
  const std::string& name;
  const char* begin;
  const char* end;
  Mesh mesh;
  bool every_vertex_colored = true;
  std::vector<float> uvs;           // u v per 'vt' line
  std::vector<uint32_t> corner_uv;  // per corner of mesh.indices: its texture vertex, or kNoTexcoord
  bool every_corner_textured = true;

  [[noreturn]] void bad(const char* at, const std::string& problem) const {
    fail(name, "line " + std::to_string(text::line_number(begin, at)) + ": " + problem);
  }

  // Up to `max` numbers from p..eol (the rest of a line) into `value`; returns how many.
  int numbers(const char* p, const char* eol, float* value, int max, const char* what) const {
    int n = 0;
    for (p = text::skip_blanks(p, eol); p < eol && *p != '#' && n < max; p = text::skip_blanks(p, eol)) {
      const char* next = text::parse_real(p, eol, value[n]);
      if (!next || (next < eol && !text::is_blank(*next)))
        bad(p, std::string("expected ") + what + ", found " + text::quote_token(p, eol));
      p = next;
      ++n;
    }
    return n;
  }

  // 'v' already consumed; p..eol is the rest of the line.
  void vertex(const char* p, const char* eol) {
    float value[7];
    const int n = numbers(p, eol, value, 7, "a vertex coordinate");
    if (n < 3) bad(p, "a 'v' line needs x y z");
    mesh.positions.insert(mesh.positions.end(), value, value + 3);
    if (n == 6) {
      for (int c = 0; c < 3; ++c) mesh.colors.push_back(color_channel(value[3 + c], true));
      mesh.colors.push_back(255);
    } else {
      every_vertex_colored = false;
    }
  }

  // 'vt' already consumed: u, optional v (0 when absent), optional w (ignored).
  void texture_vertex(const char* p, const char* eol) {
    float value[3] = {0, 0, 0};
    if (numbers(p, eol, value, 3, "a texture coordinate") < 1) bad(p, "a 'vt' line needs u");
    uvs.insert(uvs.end(), value, value + 2);
  }

  // A 1-based index, or a negative one counting back from the last of `defined` (-1 is the latest).
  uint32_t index_at(const char* p, int64_t index, int64_t defined, const char* what) const {
    const int64_t zero_based = index > 0 ? index - 1 : defined + index;
    if (index == 0 || zero_based < 0 || zero_based > int64_t(UINT32_MAX))
      bad(p, std::string(what) + " index " + std::to_string(index) + " out of range");
    return uint32_t(zero_based);
  }

  // 'f' already consumed. Each corner's position index and texture vertex matter; its normal does not.
  void face(const char* p, const char* eol) {
    const int64_t defined = int64_t(mesh.vertex_count()), defined_uvs = int64_t(uvs.size() / 2);
    Fan fan(mesh.indices), uv_fan(corner_uv);
    for (p = text::skip_blanks(p, eol); p < eol && *p != '#'; p = text::skip_blanks(p, eol)) {
      int64_t index = 0;
      const char* next = text::parse_int(p, eol, index);
      if (!next || (next < eol && !text::is_blank(*next) && *next != '/'))
        bad(p, "expected a face corner, found " + text::quote_token(p, eol));
      const uint32_t corner = index_at(p, index, defined, "face corner");
      uint32_t uv = kNoTexcoord;
      if (next + 1 < eol && *next == '/' && next[1] != '/' && !text::is_blank(next[1])) {
        const char* at = next + 1;
        next = text::parse_int(at, eol, index);
        if (!next || (next < eol && !text::is_blank(*next) && *next != '/'))
          bad(at, "expected a texture vertex index, found " + text::quote_token(at, eol));
        uv = index_at(at, index, defined_uvs, "texture vertex");
        if (uv >= defined_uvs) bad(at, "texture vertex index " + std::to_string(index) + " out of range");
      }
      every_corner_textured &= uv != kNoTexcoord;
      while (next < eol && !text::is_blank(*next)) ++next;  // the /n part
      p = next;
      fan.add(corner);
      if (every_corner_textured) uv_fan.add(uv);
    }
    if (!every_corner_textured) std::vector<uint32_t>().swap(corner_uv);  // never read: free it at once
  }

  // Per-vertex texture coordinates from the corners' texture vertices, splitting seams.
  void split_by_texcoords() {
    const size_t n = mesh.vertex_count();
    std::vector<uint32_t> first(n, kNoTexcoord);     // the texture vertex that keeps vertex v
    std::unordered_map<uint64_t, uint32_t> copy_of;  // (vertex, other texture vertex) -> its copy
    std::vector<uint32_t> source, source_uv;         // per copy: its vertex and texture vertex
    for (size_t c = 0; c < mesh.indices.size(); ++c) {
      uint32_t& v = mesh.indices[c];
      const uint32_t uv = corner_uv[c];
      if (v >= n) continue;  // load_mesh reports it, naming the face
      if (first[v] == kNoTexcoord) first[v] = uv;
      if (first[v] == uv) continue;
      const auto [it, fresh] = copy_of.emplace(uint64_t(v) << 32 | uv, uint32_t(n + source.size()));
      if (fresh) {
        if (n + source.size() >= UINT32_MAX) fail(name, "more than 2^32 - 1 vertices after splitting texture seams");
        source.push_back(v);
        source_uv.push_back(uv);
      }
      v = it->second;
    }
    mesh.texcoords.resize(2 * (n + source.size()), 0.0f);  // a vertex no face uses gets (0, 0)
    for (size_t v = 0; v < n; ++v)
      if (first[v] != kNoTexcoord) std::copy_n(&uvs[2 * size_t(first[v])], 2, &mesh.texcoords[2 * v]);
    for (size_t i = 0; i < source.size(); ++i) {
      const size_t v = source[i];
      std::copy_n(&uvs[2 * size_t(source_uv[i])], 2, &mesh.texcoords[2 * (n + i)]);
      // By value: a range of the vector itself must not be inserted into it.
      mesh.positions.insert(mesh.positions.end(),
                            {mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]});
      if (mesh.has_colors())
        mesh.colors.insert(mesh.colors.end(), {mesh.colors[4 * v], mesh.colors[4 * v + 1], mesh.colors[4 * v + 2],
                                               mesh.colors[4 * v + 3]});
    }
  }

  void parse(const ProgressFn& progress) {
    size_t next_report = kReportBytes;
    for (const char* p = begin; p < end;) {
      const char* eol = text::line_end(p, end);
      p = text::skip_blanks(p, eol);
      if (eol - p >= 2 && text::is_blank(p[1])) {
        if (p[0] == 'v') vertex(p + 1, eol);
        else if (p[0] == 'f') face(p + 1, eol);
      } else if (eol - p >= 3 && p[0] == 'v' && p[1] == 't' && text::is_blank(p[2])) {
        texture_vertex(p + 2, eol);
      }
      p = eol + (eol < end);
      if (size_t(p - begin) >= next_report) {
        report(progress, "load", double(p - begin) / double(end - begin));
        next_report += kReportBytes;
      }
    }
    if (!every_vertex_colored) mesh.colors.clear();
    mesh.colors.shrink_to_fit();
    if (every_corner_textured && !mesh.indices.empty()) split_by_texcoords();
  }
};

}  // namespace

Mesh import_obj(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress) {
  const char* begin = reinterpret_cast<const char*>(data.data());
  ObjParser parser{name, begin, begin + data.size(), {}, true, {}, {}, true};
  parser.parse(progress);
  return std::move(parser.mesh);
}

}  // namespace pms
