// OFF (Geomview "Object File Format", ascii): a keyword line [C][N]OFF, the counts "nv nf [ne]",
// nv vertex lines "x y z [nx ny nz] [r g b [a]]" and nf face lines "k i_0 ... i_k-1 [face color]".
// '#' starts a comment. Faces are fan-triangulated; face colors are ignored. Vertex colors written
// as integers are 0..255 (MeshLab), with a decimal point 0..1 (Geomview).
#include <algorithm>
#include <cstring>
#include <string>

#include "common/error.h"
#include "io/import_internal.h"
#include "io/text_internal.h"

namespace pms {

namespace {

class OffParser {
 public:
  OffParser(const std::string& name, std::span<const uint8_t> data)
      : name_(name), begin_(reinterpret_cast<const char*>(data.data())), end_(begin_ + data.size()), p_(begin_) {}

  Mesh parse(const ProgressFn& progress) {
    parse_keyword();
    int64_t counts[3] = {0, 0, 0};
    for (int k = 0; k < 2; ++k) counts[k] = integer("an OFF count");
    if (first_ < last_) counts[2] = integer("an OFF count");
    if (counts[0] < 0 || counts[1] < 0 || counts[2] < 0) bad("negative OFF count");
    check_counts_fit(uint64_t(counts[0]), uint64_t(counts[1]));

    Mesh mesh;
    const size_t vertex_count = size_t(counts[0]);
    mesh.positions.resize(vertex_count * 3);
    if (has_normals_) mesh.normals.resize(vertex_count * 3);
    if (has_colors_) mesh.colors.resize(vertex_count * 4);
    for (size_t v = 0; v < vertex_count; ++v) {
      record("vertex", v, vertex_count, progress);
      vertex(mesh, v);
    }
    const size_t face_count = size_t(counts[1]);
    mesh.indices.reserve(face_count * 3);
    for (size_t f = 0; f < face_count; ++f) {
      record("face", f, face_count, progress);
      face(mesh, vertex_count);
    }
    return mesh;
  }

 private:
  [[noreturn]] void bad(const std::string& problem) const {
    fail(name_, "line " + std::to_string(text::line_number(begin_, first_)) + ": " + problem);
  }

  // Moves [first_, last_) to the next line with content, comment stripped; false at the end.
  bool next_line() {
    while (p_ < end_) {
      const char* eol = text::line_end(p_, end_);
      first_ = text::skip_blanks(p_, eol);
      const void* hash = std::memchr(first_, '#', size_t(eol - first_));
      last_ = hash ? static_cast<const char*>(hash) : eol;
      p_ = eol + (eol < end_);
      if (text::skip_blanks(first_, last_) < last_) return true;
    }
    first_ = last_ = end_;
    return false;
  }

  void parse_keyword() {
    if (!next_line()) fail(name_, "not an OFF file (empty)");
    const char* word_end = first_;
    while (word_end < last_ && !text::is_blank(*word_end)) ++word_end;
    const std::string_view word(first_, size_t(word_end - first_));
    if (word.size() < 3 || word.substr(word.size() - 3) != "OFF") fail(name_, "not an OFF file (missing OFF keyword)");
    const std::string_view prefix = word.substr(0, word.size() - 3);
    has_colors_ = prefix == "C" || prefix == "CN";
    has_normals_ = prefix == "N" || prefix == "CN";
    if (!prefix.empty() && !has_colors_ && !has_normals_)
      fail(name_, "unsupported OFF variant '" + std::string(word.substr(0, 24)) + "'");
    first_ = text::skip_blanks(word_end, last_);
    if (std::string_view(first_, size_t(text::skip_token(first_, last_) - first_)) == "BINARY")
      fail(name_, "binary OFF is not supported");
    if (first_ == last_) next_line();  // the counts may share the keyword's line
  }

  // A header of counts that the rest of the file cannot hold is lying; check before allocating.
  void check_counts_fit(uint64_t vertices, uint64_t faces) const {
    const uint64_t left = uint64_t(end_ - p_) + 1;    // the last line needs no newline
    const uint64_t kVertexBytes = 6, kFaceBytes = 2;  // "0 0 0\n", and "0\n" for an empty face
    if (vertices > left / kVertexBytes || faces > (left - vertices * kVertexBytes) / kFaceBytes)
      fail(name_, "OFF header declares " + std::to_string(vertices) + " vertices and " + std::to_string(faces) +
                      " faces but only " + std::to_string(end_ - p_) + " bytes follow");
  }

  void record(const char* what, size_t i, size_t count, const ProgressFn& progress) {
    if (!next_line())
      fail(name_, std::string("truncated: the file ends at ") + what + " " + std::to_string(i) + " of " +
                      std::to_string(count));
    if ((i & 0xFFFF) == 0) report(progress, "load", double(p_ - begin_) / double(end_ - begin_));
  }

  template <class T>
  T real() {
    first_ = text::skip_blanks(first_, last_);
    T value{};
    const char* next = text::parse_real(first_, last_, value);
    if (!next || (next < last_ && !text::is_blank(*next)))
      bad("expected a number, found " + text::quote_token(first_, last_));
    first_ = text::skip_blanks(next, last_);
    return value;
  }

  int64_t integer(const char* what) {
    first_ = text::skip_blanks(first_, last_);
    int64_t value = 0;
    const char* next = text::parse_int(first_, last_, value);
    if (!next || (next < last_ && !text::is_blank(*next)))
      bad(std::string("expected ") + what + ", found " + text::quote_token(first_, last_));
    first_ = text::skip_blanks(next, last_);
    return value;
  }

  void vertex(Mesh& mesh, size_t v) {
    for (int c = 0; c < 3; ++c) mesh.positions[v * 3 + c] = real<float>();
    if (has_normals_)
      for (int c = 0; c < 3; ++c) mesh.normals[v * 3 + c] = real<float>();
    if (!has_colors_) return;
    const char* color_begin = first_;
    double rgba[4] = {0, 0, 0, 255};
    int channels = 0;
    for (; channels < 4 && first_ < last_; ++channels) rgba[channels] = real<double>();
    if (channels < 3) bad("a COFF vertex needs r g b");
    const bool unit_range = std::any_of(color_begin, first_, [](char c) { return c == '.' || c == 'e' || c == 'E'; });
    if (unit_range && channels == 3) rgba[3] = 1.0;
    for (int c = 0; c < 4; ++c) mesh.colors[v * 4 + c] = color_channel(rgba[c], unit_range);
  }

  void face(Mesh& mesh, size_t vertex_count) {
    const int64_t corners = integer("a face corner count");
    Fan fan(mesh.indices);
    for (int64_t k = 0; k < corners; ++k) {
      const int64_t index = integer("a vertex index");
      if (index < 0 || uint64_t(index) >= vertex_count)
        bad("vertex index " + std::to_string(index) + " out of range (" + std::to_string(vertex_count) + " vertices)");
      fan.add(uint32_t(index));
    }
  }

  const std::string& name_;
  const char* begin_;
  const char* end_;
  const char* p_;                // start of the next line
  const char* first_ = nullptr;  // the current line's unread content...
  const char* last_ = nullptr;   // ...up to its end or comment
  bool has_colors_ = false;
  bool has_normals_ = false;
};

}  // namespace

Mesh import_off(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress) {
  return OffParser(name, data).parse(progress);
}

}  // namespace pms
