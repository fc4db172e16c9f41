// The binary multilevel file (docs/multilevel-format.md): a .pms-style header and section table, then HEAD
// and one checksummed LEVL section per level, coarsest first, so that each level can later travel and be
// cached on its own. Little-endian, read by copying (nothing is mapped in place).
#include <xxhash.h>

#include <bit>
#include <cstring>
#include <unordered_set>

#include "common/error.h"
#include "refine/multilevel_file.h"

namespace pms {
namespace {

static_assert(std::endian::native == std::endian::little, "multilevel files are little-endian");

constexpr char kMagic[8] = {'P', 'M', 'S', 'M', 'U', 'L', 'T', 'I'};
constexpr uint32_t kVersion = 1;
constexpr uint64_t kAlignment = 8;
constexpr uint32_t kHasNormals = 1, kHasColors = 2;
constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;

struct FileHeader {
  char magic[8];
  uint32_t version;
  uint32_t header_bytes;
  uint32_t section_count;
  uint32_t flags;
  uint64_t file_size;
  uint64_t header_checksum;  // xxh64 of header + table with this field zero
};
static_assert(sizeof(FileHeader) == 40);

struct SectionEntry {
  char tag[4];
  uint32_t element_size;
  uint64_t offset;
  uint64_t count;
  uint64_t checksum;
};
static_assert(sizeof(SectionEntry) == 32);

struct HeadSection {
  uint32_t level_count, dimension, flags, vertex_count, triangle_count, representative_count, reserved[2];
};
static_assert(sizeof(HeadSection) == 32);

struct LevelHeader {
  uint32_t level, vertices, triangles, representatives;
};

std::string str(uint64_t v) { return std::to_string(v); }

uint64_t checksum_of(const uint8_t* header_and_table, uint64_t bytes) {
  std::vector<uint8_t> copy(header_and_table, header_and_table + bytes);
  std::memset(copy.data() + offsetof(FileHeader, header_checksum), 0, sizeof(uint64_t));
  return XXH64(copy.data(), copy.size(), 0);
}

template <typename T>
void append(std::vector<uint32_t>& words, const T* data, size_t count) {
  static_assert(sizeof(T) == 4);
  if (count == 0) return;  // data() may be null
  const size_t at = words.size();
  words.resize(at + count);
  std::memcpy(words.data() + at, data, count * 4);
}

// One level's section: its header, vertices (positions, normals, colours), triangles, then the
// representatives its triangles state, in the order the ASCII form states them.
std::vector<uint32_t> level_words(const MultilevelMesh& m, uint32_t level, std::vector<uint8_t>& stated) {
  const uint32_t v_end = m.vertex_count[level], t_end = m.triangle_count[level];
  const uint32_t v_begin = v_end - m.level_vertices(level), t_begin = t_end - m.level_triangles(level);
  std::vector<uint32_t> reps;
  for (uint32_t t = t_begin; t < t_end; ++t) representatives_stated_by(m, t, v_end, stated, reps);
  if (level == 0)  // what no triangle states travels with the finest level
    for (uint32_t v = 0; v < m.vertices(); ++v)
      if (m.representative[v] != kNoRep && !stated[v]) reps.insert(reps.end(), {v, m.representative[v]});
  const LevelHeader h{level, v_end - v_begin, t_end - t_begin, uint32_t(reps.size() / 2)};
  std::vector<uint32_t> words;
  append(words, &h.level, 4);
  append(words, m.positions.data() + size_t(v_begin) * m.dimension, size_t(h.vertices) * m.dimension);
  if (!m.normals.empty()) append(words, m.normals.data() + size_t(v_begin) * 3, size_t(h.vertices) * 3);
  if (!m.colors.empty()) {
    const size_t at = words.size();
    words.resize(at + h.vertices);
    std::memcpy(words.data() + at, m.colors.data() + size_t(v_begin) * 4, size_t(h.vertices) * 4);
  }
  append(words, m.triangles.data() + size_t(t_begin) * 3, size_t(h.triangles) * 3);
  append(words, reps.data(), reps.size());
  return words;
}

class SectionReader {
 public:
  SectionReader(const std::string& where, std::span<const uint8_t> bytes) : where_(where), bytes_(bytes) {}

  // Header and table checks; returns the entries.
  std::vector<SectionEntry> table() const {
    if (bytes_.size() < sizeof(FileHeader)) error(0, "header: " + str(bytes_.size()) + " bytes, too short for a header");
    FileHeader h;
    std::memcpy(&h, bytes_.data(), sizeof h);
    if (std::memcmp(h.magic, kMagic, 8) != 0) error(0, "header: not a binary multilevel file (magic)");
    if (h.version != kVersion)
      error(8, "header: unsupported version " + str(h.version) + " (this build reads " + str(kVersion) + ")");
    if (h.header_bytes != sizeof h) error(12, "header: header size " + str(h.header_bytes));
    if (h.flags != 0) error(20, "header: unknown flags " + str(h.flags));
    if (h.section_count > (bytes_.size() - sizeof h) / sizeof(SectionEntry))
      error(16, "header: " + str(h.section_count) + " sections do not fit in the file");
    const uint64_t table_end = sizeof h + uint64_t(h.section_count) * sizeof(SectionEntry);
    if (checksum_of(bytes_.data(), table_end) != h.header_checksum) error(32, "header: checksum mismatch");
    if (h.file_size != bytes_.size())
      error(24, "header: file size " + str(h.file_size) + " but " + str(bytes_.size()) + " bytes read (truncated?)");
    std::vector<SectionEntry> entries(h.section_count);
    uint64_t end = table_end;
    for (uint32_t i = 0; i < h.section_count; ++i) {
      const uint64_t at = sizeof h + uint64_t(i) * sizeof(SectionEntry);
      SectionEntry& e = entries[i];
      std::memcpy(&e, bytes_.data() + at, sizeof e);
      const std::string name = "section " + str(i) + " (" + std::string(e.tag, 4) + ")";
      if (e.element_size == 0) error(at, name + ": element size 0");
      if (e.offset % kAlignment || e.offset < end) error(at, name + ": offset " + str(e.offset) + " misaligned or overlapping");
      if (e.offset > bytes_.size() || e.count > (bytes_.size() - e.offset) / e.element_size)
        error(at, name + ": " + str(e.count) + " elements past the end of the file");
      if (XXH64(bytes_.data() + e.offset, e.count * e.element_size, 0) != e.checksum) error(e.offset, name + ": checksum mismatch");
      end = e.offset + e.count * e.element_size;
    }
    return entries;
  }

  [[noreturn]] void error(uint64_t offset, const std::string& what) const {
    fail(where_, "offset " + str(offset) + ": " + what);
  }

 private:
  const std::string& where_;
  std::span<const uint8_t> bytes_;
};

bool tag_is(const SectionEntry& e, const char* tag) { return std::memcmp(e.tag, tag, 4) == 0; }

// Reads one LEVL section into `m` (levels arrive coarsest first); representatives go to `reps`.
void read_level(const SectionReader& in, const SectionEntry& e, const uint8_t* base, uint32_t expected_level,
                uint32_t flags, MultilevelMesh& m, std::vector<uint32_t>& reps) {
  const bool normals = flags & kHasNormals, colors = flags & kHasColors;
  const std::string name = "section LEVL of level " + str(expected_level);
  if (e.element_size != 4) in.error(e.offset, name + ": element size " + str(e.element_size) + " (4 expected)");
  if (e.count < 4) in.error(e.offset, name + ": " + str(e.count) + " words, too short for its header");
  LevelHeader h;
  std::memcpy(&h, base + e.offset, sizeof h);
  if (h.level != expected_level) in.error(e.offset, name + ": says it is level " + str(h.level));
  const uint64_t per_vertex = m.dimension + (normals ? 3 : 0) + (colors ? 1 : 0);
  const uint64_t words = 4 + per_vertex * h.vertices + 3 * uint64_t(h.triangles) + 2 * uint64_t(h.representatives);
  if (words != e.count)
    in.error(e.offset, name + ": " + str(e.count) + " words but its counts need " + str(words));
  const uint8_t* p = base + e.offset + sizeof h;
  auto take = [&](auto& out, uint64_t count, size_t elem) {
    if (count == 0) return;  // data() may be null
    const size_t at = out.size();
    out.resize(at + count);
    std::memcpy(out.data() + at, p, count * elem);
    p += count * elem;
  };
  take(m.positions, uint64_t(h.vertices) * m.dimension, 4);
  if (normals) take(m.normals, uint64_t(h.vertices) * 3, 4);
  if (colors) take(m.colors, uint64_t(h.vertices) * 4, 1);
  take(m.triangles, uint64_t(h.triangles) * 3, 4);
  take(reps, uint64_t(h.representatives) * 2, 4);
}

}  // namespace

void reseal_multilevel_binary(std::span<uint8_t> bytes) {
  if (bytes.size() < sizeof(FileHeader)) return;
  FileHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  if (h.section_count > (bytes.size() - sizeof h) / sizeof(SectionEntry)) return;
  for (uint32_t i = 0; i < h.section_count; ++i) {
    uint8_t* at = bytes.data() + sizeof h + uint64_t(i) * sizeof(SectionEntry);
    SectionEntry e;
    std::memcpy(&e, at, sizeof e);
    if (e.element_size == 0 || e.offset > bytes.size() || e.count > (bytes.size() - e.offset) / e.element_size) continue;
    e.checksum = XXH64(bytes.data() + e.offset, e.count * e.element_size, 0);
    std::memcpy(at, &e, sizeof e);
  }
  h.header_checksum = checksum_of(bytes.data(), sizeof h + uint64_t(h.section_count) * sizeof(SectionEntry));
  std::memcpy(bytes.data(), &h, sizeof h);
}

bool is_multilevel_binary(std::span<const uint8_t> bytes) {
  return bytes.size() >= 8 && std::memcmp(bytes.data(), kMagic, 8) == 0;
}

std::vector<uint8_t> format_multilevel_binary(const MultilevelMesh& m) {
  validate_multilevel("", m);
  const uint32_t levels = m.level_count();
  std::vector<std::vector<uint32_t>> sections;
  std::vector<uint8_t> stated(m.vertices(), 0);
  for (uint32_t level = levels; level-- > 0;) sections.push_back(level_words(m, level, stated));
  const HeadSection head{levels,      m.dimension, (m.normals.empty() ? 0 : kHasNormals) | (m.colors.empty() ? 0 : kHasColors),
                         m.vertices(), m.faces(),  uint32_t(m.stored_representatives()), {0, 0}};

  const uint32_t section_count = levels + 1;
  auto align = [](uint64_t x) { return (x + kAlignment - 1) / kAlignment * kAlignment; };
  std::vector<SectionEntry> table(section_count);
  uint64_t at = align(sizeof(FileHeader) + uint64_t(section_count) * sizeof(SectionEntry));
  table[0] = {{'H', 'E', 'A', 'D'}, sizeof head, at, 1, XXH64(&head, sizeof head, 0)};
  at = align(at + sizeof head);
  for (uint32_t i = 0; i < levels; ++i) {
    const auto& w = sections[i];
    table[i + 1] = {{'L', 'E', 'V', 'L'}, 4, at, w.size(), XXH64(w.data(), w.size() * 4, 0)};
    at = align(at + w.size() * 4);
  }
  const uint64_t file_size = table.back().offset + table.back().count * table.back().element_size;
  std::vector<uint8_t> out(file_size, 0);
  FileHeader h{};
  std::memcpy(h.magic, kMagic, 8);
  h.version = kVersion;
  h.header_bytes = sizeof h;
  h.section_count = section_count;
  h.file_size = file_size;
  std::memcpy(out.data(), &h, sizeof h);
  std::memcpy(out.data() + sizeof h, table.data(), table.size() * sizeof(SectionEntry));
  std::memcpy(out.data() + table[0].offset, &head, sizeof head);
  for (uint32_t i = 0; i < levels; ++i)
    std::memcpy(out.data() + table[i + 1].offset, sections[i].data(), sections[i].size() * 4);
  h.header_checksum = checksum_of(out.data(), sizeof h + table.size() * sizeof(SectionEntry));
  std::memcpy(out.data(), &h, sizeof h);
  return out;
}

MultilevelMesh parse_multilevel_binary(const std::string& where, std::span<const uint8_t> bytes,
                                       const MultilevelLimits& limits) {
  if (bytes.size() > limits.max_file_bytes) fail(where, "larger than " + str(limits.max_file_bytes) + " bytes");
  const SectionReader in(where, bytes);
  const std::vector<SectionEntry> table = in.table();
  size_t i = 0;
  while (i < table.size() && !tag_is(table[i], "HEAD")) ++i;  // unknown sections before it are skipped
  if (i == table.size()) in.error(0, "no HEAD section");
  const SectionEntry& he = table[i];
  if (he.element_size != sizeof(HeadSection) || he.count != 1) in.error(he.offset, "section HEAD: wrong size");
  HeadSection head;
  std::memcpy(&head, bytes.data() + he.offset, sizeof head);
  if (head.level_count == 0 || head.level_count > limits.max_levels)
    in.error(he.offset, "section HEAD: " + str(head.level_count) + " levels (1 to " + str(limits.max_levels) + ")");
  if (head.dimension < 2 || head.dimension > 3) in.error(he.offset + 4, "section HEAD: dimension " + str(head.dimension));
  if (head.flags & ~(kHasNormals | kHasColors)) in.error(he.offset + 8, "section HEAD: unknown flags");

  MultilevelMesh m;
  m.dimension = head.dimension;
  m.vertex_count.assign(head.level_count, 0);
  m.triangle_count.assign(head.level_count, 0);
  std::vector<uint32_t> reps;
  uint32_t level = head.level_count;
  for (++i; i < table.size(); ++i) {
    if (!tag_is(table[i], "LEVL")) continue;
    if (level == 0) in.error(table[i].offset, "more LEVL sections than HEAD's " + str(head.level_count) + " levels");
    --level;
    read_level(in, table[i], bytes.data(), level, head.flags, m, reps);
    if (m.positions.size() / m.dimension > 0x7FFFFFFFu || m.triangles.size() / 3 > 0x7FFFFFFFu)
      in.error(table[i].offset, "more than 2^31 vertices or triangles");
    m.vertex_count[level] = uint32_t(m.positions.size() / m.dimension);
    m.triangle_count[level] = uint32_t(m.triangles.size() / 3);
  }
  if (level != 0) in.error(bytes.size(), str(level) + " of HEAD's " + str(head.level_count) + " LEVL sections are missing");
  if (m.vertices() != head.vertex_count || m.faces() != head.triangle_count || reps.size() / 2 != head.representative_count)
    in.error(he.offset, "section HEAD: its totals disagree with the LEVL sections");
  m.representative.assign(m.vertices(), kNoRep);
  for (size_t k = 0; k < reps.size(); k += 2) {
    const uint32_t v = reps[k];
    if (v >= m.vertices()) fail(where, "a representative of vertex " + str(v) + ", beyond the file's " + str(m.vertices()));
    if (m.representative[v] != kNoRep) fail(where, "vertex " + str(v) + " has two representatives");
    m.representative[v] = reps[k + 1];
  }
  validate_multilevel(where, m);
  return m;
}

}  // namespace pms
