// The ASCII multilevel file of gueziec et al. 1999, Fig. 6 and Fig. 13, read and written
// (docs/multilevel-format.md, "ASCII"). The reader makes two passes: the first checks the braces and counts
// the numbers of each vertex batch, which fixes the dimension; the second reads them.
#include <fast_float/fast_float.h>

#include <charconv>
#include <cmath>

#include "common/error.h"
#include "multilevel/file.h"

namespace pms {
namespace {

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;
constexpr uint32_t kMaxIndex = 0x7FFFFFFFu;

std::string str(uint64_t v) { return std::to_string(v); }

enum class Token { open, close, number, end };

class Lexer {
 public:
  Lexer(const std::string& where, std::string_view text) : where_(where), text_(text) {}

  Token next() {
    for (;;) {
      if (pos_ == text_.size()) return Token::end;
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (c == ' ' || c == '\t' || c == '\r' || c == ',') {
        ++pos_;
      } else if (c == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else if (c == '{' || c == '}') {
        ++pos_;
        return c == '{' ? Token::open : Token::close;
      } else {
        const size_t begin = pos_;
        while (pos_ < text_.size() && !is_separator(text_[pos_])) ++pos_;
        number_ = text_.substr(begin, pos_ - begin);
        return Token::number;
      }
    }
  }

  std::string_view number() const { return number_; }
  uint64_t line() const { return line_; }
  [[noreturn]] void error(const std::string& what) const { fail(where_, "line " + str(line_) + ": " + what); }

  float coordinate() const {
    float value = 0;
    const auto r = fast_float::from_chars(number_.data(), number_.data() + number_.size(), value);
    if (r.ec != std::errc() || r.ptr != number_.data() + number_.size() || !std::isfinite(value))
      error(quoted("is not a finite number"));
    return value;
  }

  uint32_t index() const {
    uint32_t value = 0;
    const auto r = std::from_chars(number_.data(), number_.data() + number_.size(), value);
    if (r.ec != std::errc() || r.ptr != number_.data() + number_.size() || value > kMaxIndex)
      error(quoted("is not a vertex index"));
    return value;
  }

 private:
  static bool is_separator(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == ',' || c == '#' || c == '{' || c == '}';
  }
  // "'TOKEN' WHAT", built by appending (GCC 12 misreports -Wrestrict on "'" + std::string).
  std::string quoted(const char* what) const {
    std::string s(1, '\'');
    s.append(number_.substr(0, 40));
    s.append("' ");
    s.append(what);
    return s;
  }

  const std::string& where_;
  std::string_view text_;
  size_t pos_ = 0;
  uint64_t line_ = 1;
  std::string_view number_;
};

struct Shape {
  uint32_t dimension = 3, level_count = 0;
  uint64_t vertex_count = 0;  // in the whole file, so indices are checked as they are read
};

// Pass 1: batches well formed, in vertex/triangle pairs; how many numbers each vertex batch holds.
Shape shape_of(const std::string& where, std::string_view text, const MultilevelLimits& limits) {
  Lexer lex(where, text);
  std::vector<std::pair<uint64_t, uint64_t>> vertex_batches;  // (numbers, line)
  uint64_t batches = 0;
  for (Token t = lex.next(); t != Token::end; t = lex.next()) {
    if (t != Token::open) lex.error(t == Token::close ? "'}' without '{'" : "a number outside { }");
    const uint64_t line = lex.line();
    uint64_t numbers = 0;
    for (t = lex.next(); t == Token::number; t = lex.next()) ++numbers;
    if (t == Token::open) lex.error("'{' inside a batch (the batch opened on line " + str(line) + ")");
    if (t == Token::end) fail(where, "line " + str(line) + ": '{' is never closed");
    if (batches % 2 == 0) vertex_batches.push_back({numbers, line});
    if (++batches > 2 * uint64_t(limits.max_levels)) lex.error("more than " + str(limits.max_levels) + " levels");
  }
  if (batches == 0) fail(where, "no levels: the file holds no { } batch");
  if (batches % 2) fail(where, "the last level has vertices but no triangle batch (an empty one is {})");
  for (uint32_t d : {3u, 2u}) {
    bool whole = true;
    for (const auto& batch : vertex_batches) whole = whole && batch.first % d == 0;
    uint64_t numbers = 0;
    for (const auto& batch : vertex_batches) numbers += batch.first;
    if (whole) return {d, uint32_t(batches / 2), numbers / d};
  }
  for (const auto& [numbers, line] : vertex_batches)
    if (numbers % 3 && numbers % 2)
      fail(where,
           "line " + str(line) + ": a vertex batch of " + str(numbers) + " numbers is not whole 2D or 3D vertices");
  fail(where, "vertex batches mix 2D and 3D coordinates");
}

// Pass 2, one triangle batch of level l with n vertices known: corners, then the representatives they state.
// `stated` holds the representatives stated so far (kNoRep where none), one entry per vertex of the file.
void read_triangles(Lexer& lex, uint32_t level, uint32_t n, MultilevelMesh& m, std::vector<uint32_t>& stated) {
  const uint64_t total = stated.size();
  auto vertex = [&](const char* what) {
    const uint32_t v = lex.index();
    if (v >= total) lex.error(std::string(what) + " " + str(v) + " is beyond the file's " + str(total) + " vertices");
    return v;
  };
  Token t = lex.next();
  while (t == Token::number) {
    uint32_t corner[3];
    for (int k = 0; k < 3; ++k) {
      if (t != Token::number) lex.error("a triangle of level " + str(level) + " has " + str(k) + " corners, not 3");
      corner[k] = vertex("vertex");
      t = lex.next();
    }
    for (uint32_t v : corner) {
      m.triangles.push_back(v);
      while (v >= n && stated[v] == kNoRep) {
        if (t != Token::number)
          lex.error("vertex " + str(v) + " is not in level " + str(level) +
                    " or above: its representative must follow the triangle");
        const uint32_t r = vertex("representative");
        if (r >= v) lex.error("representative " + str(r) + " of vertex " + str(v) + " is not below it");
        stated[v] = r;
        v = r;
        t = lex.next();
      }
    }
  }
  if (t != Token::close) lex.error("expected '}' to close the triangles of level " + str(level));
}

// Pass 1 checked the batch's count and its closing brace.
void read_vertices(Lexer& lex, MultilevelMesh& m) {
  for (Token t = lex.next(); t == Token::number; t = lex.next()) m.positions.push_back(lex.coordinate());
}

std::string format_float(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace

MultilevelMesh parse_multilevel_ascii(const std::string& where, std::string_view text, const MultilevelLimits& limits) {
  if (text.size() > limits.max_file_bytes) fail(where, "larger than " + str(limits.max_file_bytes) + " bytes");
  const Shape shape = shape_of(where, text, limits);
  MultilevelMesh m;
  m.dimension = shape.dimension;
  m.vertex_count.resize(shape.level_count);
  m.triangle_count.resize(shape.level_count);
  if (shape.vertex_count > kMaxIndex) fail(where, "more than " + str(kMaxIndex) + " vertices");
  Lexer lex(where, text);
  std::vector<uint32_t> stated(shape.vertex_count, kNoRep);
  for (uint32_t level = shape.level_count; level-- > 0;) {
    lex.next();  // '{'
    read_vertices(lex, m);
    m.vertex_count[level] = uint32_t(m.positions.size() / m.dimension);
    lex.next();  // '{'
    read_triangles(lex, level, m.vertex_count[level], m, stated);
    if (m.triangles.size() / 3 > kMaxIndex) lex.error("more than " + str(kMaxIndex) + " triangles");
    m.triangle_count[level] = uint32_t(m.triangles.size() / 3);
  }
  m.representative = RepresentativeArray(stated);
  validate_multilevel(where, m);
  return m;
}

std::string format_multilevel_ascii(const MultilevelMesh& m) {
  validate_multilevel("", m);
  bool reads_as_3d = m.dimension == 2;
  for (uint32_t l = 0; l < m.level_count(); ++l) reads_as_3d = reads_as_3d && m.level_vertices(l) % 3 == 0;
  if (reads_as_3d)
    fail("", "a 2D mesh whose every level has a multiple of 3 vertices would read back as 3D from the ASCII form");
  std::string out(1, '#');
  out += str(m.level_count());
  out += "-level progressive mesh\n";
  // The paper's form states a representative only after a triangle that needs it: the ones no triangle
  // states (only geomorphs use them, multilevel/mesh.h) have no place in it.
  const uint64_t left_out = geomorph_representative_count(m);
  if (left_out) out += "#(without the " + str(left_out) + " representatives only geomorphs use)\n";
  std::vector<uint8_t> stated(m.vertices(), 0);
  std::vector<uint32_t> reps;
  const uint32_t d = m.dimension;
  for (uint32_t level = m.level_count(); level-- > 0;) {
    const uint32_t v_end = m.vertex_count[level], t_end = m.triangle_count[level];
    const uint32_t v_begin = v_end - m.level_vertices(level), t_begin = t_end - m.level_triangles(level);
    out += "{#level " + str(level) + " vertices (" + str(v_end - v_begin) + ")\n";
    for (uint32_t v = v_begin; v < v_end; ++v) {
      for (uint32_t k = 0; k < d; ++k) {
        out += format_float(m.positions[size_t(v) * d + k]);
        if (k + 1 < d) out += ", ";
      }
      if (v + 1 < v_end) out += ",\n";
    }
    out += "}\n{#level " + str(level) + " triangles (" + str(t_end - t_begin) +
           "), each followed by the representatives it states\n";
    for (uint32_t t = t_begin; t < t_end; ++t) {
      reps.clear();
      representatives_stated_by(m, t, v_end, stated, reps);
      for (int k = 0; k < 3; ++k) out += str(m.triangles[3 * size_t(t) + k]) + (k < 2 || !reps.empty() ? ", " : "");
      for (size_t i = 1; i < reps.size(); i += 2) out += str(reps[i]) + (i + 2 < reps.size() ? ", " : "");
      if (t + 1 < t_end) out += ",\n";
    }
    out += "}\n";
  }
  return out;
}

}  // namespace pms
