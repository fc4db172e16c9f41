// Wavefront OBJ, the subset that meshes use: 'v x y z [w]' or 'v x y z r g b' (per-vertex colors
// as MeshLab writes them, in [0, 1]), and 'f' with corners 'a', 'a/t', 'a//n' or 'a/t/n' where a
// negative index counts back from the latest vertex. Polygons are fan-triangulated. Everything else
// (vn, vt, groups, materials, lines) is ignored: OBJ normals belong to corners, not vertices.
#include <string>

#include "common/error.h"
#include "io/import_internal.h"
#include "io/text_internal.h"

namespace pms {

namespace {

constexpr size_t kReportBytes = size_t(4) << 20;

struct ObjParser {
  const std::string& name;
  const char* begin;
  const char* end;
  Mesh mesh;
  bool every_vertex_colored = true;

  [[noreturn]] void bad(const char* at, const std::string& problem) const {
    fail(name, "line " + std::to_string(text::line_number(begin, at)) + ": " + problem);
  }

  // 'v' already consumed; p..eol is the rest of the line.
  void vertex(const char* p, const char* eol) {
    float value[7];
    int n = 0;
    for (p = text::skip_blanks(p, eol); p < eol && *p != '#' && n < 7; p = text::skip_blanks(p, eol)) {
      const char* next = text::parse_real(p, eol, value[n]);
      if (!next || (next < eol && !text::is_blank(*next)))
        bad(p, "expected a vertex coordinate, found " + text::quote_token(p, eol));
      p = next;
      ++n;
    }
    if (n < 3) bad(p, "a 'v' line needs x y z");
    mesh.positions.insert(mesh.positions.end(), value, value + 3);
    if (n == 6) {
      for (int c = 0; c < 3; ++c) mesh.colors.push_back(color_channel(value[3 + c], true));
      mesh.colors.push_back(255);
    } else {
      every_vertex_colored = false;
    }
  }

  // 'f' already consumed. Only the position index of each corner matters.
  void face(const char* p, const char* eol) {
    const int64_t defined = int64_t(mesh.vertex_count());
    Fan fan(mesh.indices);
    for (p = text::skip_blanks(p, eol); p < eol && *p != '#'; p = text::skip_blanks(p, eol)) {
      int64_t index = 0;
      const char* next = text::parse_int(p, eol, index);
      if (!next || (next < eol && !text::is_blank(*next) && *next != '/'))
        bad(p, "expected a face corner, found " + text::quote_token(p, eol));
      // 1-based; negative counts back from the last vertex defined so far (-1 is the latest).
      const int64_t corner = index > 0 ? index - 1 : defined + index;
      if (index == 0 || corner < 0 || corner > int64_t(UINT32_MAX))
        bad(p, "face corner index " + std::to_string(index) + " out of range");
      while (next < eol && !text::is_blank(*next)) ++next;  // the /t/n part
      p = next;
      fan.add(uint32_t(corner));
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
      }
      p = eol + (eol < end);
      if (size_t(p - begin) >= next_report) {
        report(progress, "load", double(p - begin) / double(end - begin));
        next_report += kReportBytes;
      }
    }
    if (!every_vertex_colored) mesh.colors.clear();
    mesh.colors.shrink_to_fit();
  }
};

}  // namespace

Mesh import_obj(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress) {
  const char* begin = reinterpret_cast<const char*>(data.data());
  ObjParser parser{name, begin, begin + data.size(), {}, true};
  parser.parse(progress);
  return std::move(parser.mesh);
}

}  // namespace pms
