// PLY importer (Turk, "The PLY Polygon File Format", 1994): ascii, binary_little_endian and
// binary_big_endian. The header declares elements (records) and their typed properties; the body
// holds the records in header order. We keep vertex x y z, optional nx ny nz, red green blue [alpha]
// and texture coordinates (s t, u v, texture_u texture_v or texture_s texture_t), and the face index list
// (vertex_indices or vertex_index), fan-triangulated; every other property and element is skipped by its type. Counts
// in the header are checked against the bytes that follow before anything is allocated from them.
#include <bit>
#include <cstring>
#include <string_view>
#include <vector>

#include "common/bit_cast.h"
#include "common/error.h"
#include "io/import_internal.h"
#include "io/text_internal.h"

namespace pms {

namespace {

enum class Scalar : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

struct ScalarName {
  std::string_view name;
  Scalar type;
};
constexpr ScalarName kScalarNames[] = {
    {"char", Scalar::i8},   {"int8", Scalar::i8},     {"uchar", Scalar::u8},   {"uint8", Scalar::u8},
    {"short", Scalar::i16}, {"int16", Scalar::i16},   {"ushort", Scalar::u16}, {"uint16", Scalar::u16},
    {"int", Scalar::i32},   {"int32", Scalar::i32},   {"uint", Scalar::u32},   {"uint32", Scalar::u32},
    {"float", Scalar::f32}, {"float32", Scalar::f32}, {"double", Scalar::f64}, {"float64", Scalar::f64},
};

size_t scalar_size(Scalar type) {
  static constexpr uint8_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSizes[int(type)];
}
bool is_real(Scalar type) { return type == Scalar::f32 || type == Scalar::f64; }

// Where a property's value goes: vertex attributes, the face corner list, or nowhere.
enum Slot : uint8_t { kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kAlpha, kU, kV, kSlotCount, kCorners, kSkip };

struct Property {
  std::string name;
  Scalar type = Scalar::f32;  // of the items, for a list
  bool is_list = false;
  Scalar count_type = Scalar::u8;
  Slot slot = kSkip;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Format { ascii, binary_le, binary_be };

struct Header {
  Format format = Format::ascii;
  std::vector<Element> elements;
  size_t data_offset = 0;
};

// ---- header ----------------------------------------------------------------------------------

std::vector<std::string_view> split_blanks(std::string_view line) {
  std::vector<std::string_view> tokens;
  const char* p = line.data();
  const char* end = p + line.size();
  while ((p = text::skip_blanks(p, end)) < end) {
    const char* start = p;
    while (p < end && !text::is_blank(*p)) ++p;
    tokens.emplace_back(start, size_t(p - start));
  }
  return tokens;
}

Scalar parse_scalar(const std::string& name, std::string_view token) {
  for (const auto& entry : kScalarNames)
    if (entry.name == token) return entry.type;
  fail(name, "unknown PLY property type '" + std::string(token) + "'");
}

uint64_t parse_count(const std::string& name, std::string_view token) {
  int64_t count = 0;
  const char* end = token.data() + token.size();
  if (text::parse_int(token.data(), end, count) != end || count < 0)
    fail(name, "bad PLY element count '" + std::string(token) + "'");
  return uint64_t(count);
}

// Texture coordinates go by four pairs of names in the wild (Blender writes s t, MeshLab texture_u
// texture_v); the first property of a slot wins.
Slot vertex_slot(std::string_view property) {
  struct Name {
    std::string_view name;
    Slot slot;
  };
  static constexpr Name kNames[] = {
      {"x", kX},     {"y", kY},         {"z", kZ},         {"nx", kNx},       {"ny", kNy},       {"nz", kNz},
      {"red", kRed}, {"green", kGreen}, {"blue", kBlue},   {"alpha", kAlpha}, {"s", kU},         {"t", kV},
      {"u", kU},     {"v", kV},         {"texture_u", kU}, {"texture_v", kV}, {"texture_s", kU}, {"texture_t", kV}};
  for (const Name& entry : kNames)
    if (entry.name == property) return entry.slot;
  return kSkip;
}

// Decides which properties we keep, and rejects files whose vertex/face layout we cannot use.
void assign_slots(const std::string& name, Header& header) {
  int vertex_elements = 0, face_elements = 0;
  for (Element& element : header.elements) {
    if (element.name == "vertex") {
      ++vertex_elements;
      bool seen[kSlotCount] = {};
      for (Property& property : element.properties) {
        const Slot slot = vertex_slot(property.name);
        if (slot == kSkip || property.is_list || seen[slot]) continue;
        seen[slot] = true;
        property.slot = slot;
      }
      if (!seen[kX] || !seen[kY] || !seen[kZ]) fail(name, "PLY vertex element lacks scalar x, y and z");
    } else if (element.name == "face") {
      ++face_elements;
      Property* corners = nullptr;
      for (Property& property : element.properties)
        if (property.is_list && !corners && (property.name == "vertex_indices" || property.name == "vertex_index"))
          corners = &property;
      if (!corners) fail(name, "PLY face element has no vertex_indices list");
      if (is_real(corners->type)) fail(name, "PLY face list '" + corners->name + "' must hold integers");
      corners->slot = kCorners;
    }
  }
  if (vertex_elements != 1) fail(name, "PLY file must have exactly one vertex element");
  if (face_elements > 1) fail(name, "PLY file has more than one face element");
}

Header parse_header(const std::string& name, std::span<const uint8_t> data) {
  const char* begin = reinterpret_cast<const char*>(data.data());
  const char* end = begin + data.size();
  if (data.size() < 4 || std::memcmp(begin, "ply", 3) != 0 || (begin[3] != '\n' && begin[3] != '\r'))
    fail(name, "not a PLY file (missing 'ply' magic line)");

  Header header;
  bool has_format = false;
  size_t line = 0;
  for (const char* p = begin; p < end;) {
    const char* eol = text::line_end(p, end);
    const auto tokens = split_blanks(std::string_view(p, size_t(eol - p)));
    ++line;
    p = eol + (eol < end);
    if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info" || (line == 1 && tokens[0] == "ply"))
      continue;
    const auto bad = [&] { fail(name, "PLY header line " + std::to_string(line) + " is malformed"); };
    if (tokens[0] == "format") {
      if (tokens.size() != 3) bad();
      if (tokens[1] == "ascii") header.format = Format::ascii;
      else if (tokens[1] == "binary_little_endian") header.format = Format::binary_le;
      else if (tokens[1] == "binary_big_endian") header.format = Format::binary_be;
      else fail(name, "unknown PLY format '" + std::string(tokens[1]) + "'");
      has_format = true;
    } else if (tokens[0] == "element") {
      if (tokens.size() != 3) bad();
      header.elements.push_back({std::string(tokens[1]), parse_count(name, tokens[2]), {}});
    } else if (tokens[0] == "property") {
      if (header.elements.empty()) fail(name, "PLY property before any element");
      Property property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        property.is_list = true;
        property.count_type = parse_scalar(name, tokens[2]);
        if (is_real(property.count_type)) fail(name, "PLY list count type must be an integer type");
        property.type = parse_scalar(name, tokens[3]);
        property.name = tokens[4];
      } else if (tokens.size() == 3) {
        property.type = parse_scalar(name, tokens[1]);
        property.name = tokens[2];
      } else {
        bad();
      }
      header.elements.back().properties.push_back(std::move(property));
    } else if (tokens[0] == "end_header") {
      if (!has_format) fail(name, "PLY header has no format line");
      header.data_offset = size_t(p - begin);
      assign_slots(name, header);
      return header;
    } else {
      fail(name,
           "unknown PLY header keyword '" + std::string(tokens[0].substr(0, 24)) + "' on line " + std::to_string(line));
    }
  }
  fail(name, "PLY header has no end_header line");
}

// The fewest bytes one record can take: a token and a separator per ascii value, the scalar
// (or list count) size in binary. A header whose counts cannot fit in the file is lying.
void check_counts_fit(const std::string& name, const Header& header, uint64_t data_bytes) {
  uint64_t left = data_bytes + 1;  // the last ascii token needs no separator
  for (const Element& element : header.elements) {
    uint64_t record = 0;
    for (const Property& property : element.properties) {
      const Scalar stored = property.is_list ? property.count_type : property.type;
      record += header.format == Format::ascii ? 2 : scalar_size(stored);
    }
    if (record == 0) continue;
    if (element.count > left / record)
      fail(name, "PLY header declares " + std::to_string(element.count) + " " + element.name + " records but only " +
                     std::to_string(data_bytes) + " bytes of data follow");
    left -= element.count * record;
  }
}

// ---- body readers ------------------------------------------------------------------------------

// Thrown by readers at the end of the data; turned into a message that names the record.
struct Truncated {};

// Ascii records are whitespace-separated tokens; line breaks carry no meaning.
class AsciiReader {
 public:
  AsciiReader(const std::string& name, const char* begin, const char* data, const char* end)
      : name_(name), begin_(begin), p_(data), end_(end) {}

  double number(Scalar type) {
    p_ = text::skip_spaces(p_, end_);
    if (p_ == end_) throw Truncated{};
    const char* next;
    double value = 0;
    if (type == Scalar::f32) {
      float f = 0;  // parse as float so the value is the correctly rounded float, not a double rounded twice
      next = text::parse_real(p_, end_, f);
      value = f;
    } else if (type == Scalar::f64) {
      next = text::parse_real(p_, end_, value);
    } else {
      int64_t i = 0;
      next = text::parse_int(p_, end_, i);
      value = double(i);
    }
    if (!next || (next < end_ && !text::is_space(*next)))
      fail(name_, "line " + std::to_string(text::line_number(begin_, p_)) + ": expected " +
                      (is_real(type) ? "a number" : "an integer") + ", found " + text::quote_token(p_, end_));
    p_ = next;
    return value;
  }

  void skip(Scalar) {
    p_ = text::skip_spaces(p_, end_);
    if (p_ == end_) throw Truncated{};
    p_ = text::skip_token(p_, end_);
  }

  void skip_items(uint64_t count, Scalar type) {
    for (uint64_t k = 0; k < count; ++k) skip(type);
  }

  size_t offset() const { return size_t(p_ - begin_); }

 private:
  const std::string& name_;
  const char* begin_;
  const char* p_;
  const char* end_;
};

template <bool kSwap>
class BinaryReader {
 public:
  BinaryReader(const char* begin, const char* data, const char* end) : begin_(begin), p_(data), end_(end) {}

  double number(Scalar type) {
    if (size_t(end_ - p_) < scalar_size(type)) throw Truncated{};
    double value = 0;
    switch (type) {
      case Scalar::i8:
        value = int8_t(*p_);
        break;
      case Scalar::u8:
        value = uint8_t(*p_);
        break;
      case Scalar::i16:
        value = int16_t(load<uint16_t>());
        break;
      case Scalar::u16:
        value = load<uint16_t>();
        break;
      case Scalar::i32:
        value = int32_t(load<uint32_t>());
        break;
      case Scalar::u32:
        value = load<uint32_t>();
        break;
      case Scalar::f32:
        value = bit_cast<float>(load<uint32_t>());
        break;
      case Scalar::f64:
        value = bit_cast<double>(load<uint64_t>());
        break;
    }
    p_ += scalar_size(type);
    return value;
  }

  void skip(Scalar type) { skip_items(1, type); }

  void skip_items(uint64_t count, Scalar type) {
    if (count > size_t(end_ - p_) / scalar_size(type)) throw Truncated{};
    p_ += count * scalar_size(type);
  }

  size_t offset() const { return size_t(p_ - begin_); }

 private:
  template <class U>
  U load() const {
    U u;
    std::memcpy(&u, p_, sizeof u);
    if constexpr (kSwap) {
      if constexpr (sizeof u == 2) u = __builtin_bswap16(u);
      if constexpr (sizeof u == 4) u = __builtin_bswap32(u);
      if constexpr (sizeof u == 8) u = __builtin_bswap64(u);
    }
    return u;
  }

  const char* begin_;
  const char* p_;
  const char* end_;
};

// ---- body ------------------------------------------------------------------------------------

struct Context {
  const std::string& name;
  const ProgressFn& progress;
  size_t file_size;
  uint64_t vertex_count;
};

template <class Reader>
uint64_t read_list_count(const Context& ctx, Reader& reader, const Property& property) {
  const double count = reader.number(property.count_type);
  if (count < 0) fail(ctx.name, "negative length in PLY list '" + property.name + "'");
  return uint64_t(count);
}

template <class Reader>
void skip_property(const Context& ctx, Reader& reader, const Property& property) {
  if (property.is_list) reader.skip_items(read_list_count(ctx, reader, property), property.type);
  else reader.skip(property.type);
}

// Runs fn(i) for each record of the element, reporting progress every 64K records and
// naming the record where the data ends early.
template <class Reader, class Fn>
void for_each_record(const Context& ctx, const Element& element, Reader& reader, Fn&& fn) {
  uint64_t i = 0;
  try {
    for (; i < element.count; ++i) {
      if ((i & 0xFFFF) == 0) report(ctx.progress, "load", double(reader.offset()) / double(ctx.file_size));
      fn(i);
    }
  } catch (const Truncated&) {
    fail(ctx.name, "truncated: the data ends in " + element.name + " " + std::to_string(i) + " of " +
                       std::to_string(element.count));
  }
}

uint8_t color_from(double value, Scalar type) {
  if (type == Scalar::u16 || type == Scalar::i16) return color_channel(value / 257.0, false);
  return color_channel(value, is_real(type));
}

template <class Reader>
void read_vertices(const Context& ctx, const Element& element, Reader& reader, Mesh& mesh) {
  bool present[kSlotCount] = {};
  Scalar color_type[4] = {Scalar::u8, Scalar::u8, Scalar::u8, Scalar::u8};
  for (const Property& property : element.properties) {
    if (property.slot >= kSlotCount) continue;
    present[property.slot] = true;
    if (property.slot >= kRed && property.slot <= kAlpha) color_type[property.slot - kRed] = property.type;
  }
  const bool has_normals = present[kNx] && present[kNy] && present[kNz];
  const bool has_colors = present[kRed] && present[kGreen] && present[kBlue];
  const bool has_texcoords = present[kU] && present[kV];
  const size_t n = size_t(element.count);  // fits: check_counts_fit bounded it by the file size
  mesh.positions.resize(n * 3);
  if (has_normals) mesh.normals.resize(n * 3);
  if (has_colors) mesh.colors.resize(n * 4);
  if (has_texcoords) mesh.texcoords.resize(n * 2);

  double value[kSlotCount] = {};
  value[kAlpha] = is_real(color_type[3]) ? 1.0 : 255.0;  // opaque when the file has no alpha
  for_each_record(ctx, element, reader, [&](uint64_t i) {
    for (const Property& property : element.properties) {
      if (property.slot < kSlotCount) value[property.slot] = reader.number(property.type);
      else skip_property(ctx, reader, property);
    }
    for (int c = 0; c < 3; ++c) mesh.positions[i * 3 + c] = float(value[kX + c]);
    if (has_normals)
      for (int c = 0; c < 3; ++c) mesh.normals[i * 3 + c] = float(value[kNx + c]);
    if (has_colors)
      for (int c = 0; c < 4; ++c) mesh.colors[i * 4 + c] = color_from(value[kRed + c], color_type[c]);
    if (has_texcoords)
      for (int c = 0; c < 2; ++c) mesh.texcoords[i * 2 + c] = float(value[kU + c]);
  });
}

template <class Reader>
void read_faces(const Context& ctx, const Element& element, Reader& reader, Mesh& mesh) {
  // A triangle takes at least 4 bytes in any encoding; never reserve more than the data can hold.
  mesh.indices.reserve(size_t(std::min<uint64_t>(element.count, ctx.file_size / 4)) * 3);
  for_each_record(ctx, element, reader, [&](uint64_t i) {
    for (const Property& property : element.properties) {
      if (property.slot != kCorners) {
        skip_property(ctx, reader, property);
        continue;
      }
      const uint64_t corners = read_list_count(ctx, reader, property);
      Fan fan(mesh.indices);
      for (uint64_t k = 0; k < corners; ++k) {
        const double index = reader.number(property.type);
        if (index < 0 || index >= double(ctx.vertex_count))
          fail(ctx.name, "face " + std::to_string(i) + ": vertex index " + std::to_string(int64_t(index)) +
                             " out of range (" + std::to_string(ctx.vertex_count) + " vertices)");
        fan.add(uint32_t(index));
      }
    }
  });
}

template <class Reader>
Mesh read_body(const Context& ctx, const Header& header, Reader& reader) {
  Mesh mesh;
  for (const Element& element : header.elements) {
    if (element.properties.empty()) continue;  // holds no data however large its count
    if (element.name == "vertex") read_vertices(ctx, element, reader, mesh);
    else if (element.name == "face") read_faces(ctx, element, reader, mesh);
    else
      for_each_record(ctx, element, reader, [&](uint64_t) {
        for (const Property& property : element.properties) skip_property(ctx, reader, property);
      });
  }
  return mesh;
}

}  // namespace

Mesh import_ply(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress) {
  const Header header = parse_header(name, data);
  check_counts_fit(name, header, data.size() - header.data_offset);
  uint64_t vertex_count = 0;
  for (const Element& element : header.elements)
    if (element.name == "vertex") vertex_count = element.count;
  if (vertex_count > UINT32_MAX) fail(name, "more than 2^32 vertices are not supported");

  const Context ctx{name, progress, data.size(), vertex_count};
  const char* begin = reinterpret_cast<const char*>(data.data());
  const char* body = begin + header.data_offset;
  const char* end = begin + data.size();
  constexpr bool kLittle = std::endian::native == std::endian::little;
  switch (header.format) {
    case Format::ascii: {
      AsciiReader reader(name, begin, body, end);
      return read_body(ctx, header, reader);
    }
    case Format::binary_le: {
      BinaryReader<!kLittle> reader(begin, body, end);
      return read_body(ctx, header, reader);
    }
    case Format::binary_be: {
      BinaryReader<kLittle> reader(begin, body, end);
      return read_body(ctx, header, reader);
    }
  }
  return {};
}

}  // namespace pms
