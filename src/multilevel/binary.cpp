// The binary multilevel file (docs/multilevel-format.md): a .pms-style header and section table, then HEAD
// and one checksummed LEVL section per level, coarsest first, so that each level can later travel and be
// cached on its own. Little-endian, read by copying (nothing is mapped in place).
#include <xxhash.h>

#include <bit>
#include <cstring>

#include "common/error.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"

namespace pms {
namespace {

static_assert(std::endian::native == std::endian::little, "multilevel files are little-endian");

constexpr char kMagic[8] = {'P', 'M', 'S', 'M', 'U', 'L', 'T', 'I'};
constexpr uint32_t kVersion = 1;
constexpr uint64_t kAlignment = 8;

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

std::string str(uint64_t v) { return std::to_string(v); }

uint64_t checksum_of(const uint8_t* header_and_table, uint64_t bytes) {
  std::vector<uint8_t> copy(header_and_table, header_and_table + bytes);
  std::memset(copy.data() + offsetof(FileHeader, header_checksum), 0, sizeof(uint64_t));
  return XXH64(copy.data(), copy.size(), 0);
}

class SectionReader {
 public:
  SectionReader(const std::string& where, std::span<const uint8_t> bytes) : where_(where), bytes_(bytes) {}

  // Header and table checks; returns the entries.
  std::vector<SectionEntry> table() const {
    if (bytes_.size() < sizeof(FileHeader))
      error(0, "header: " + str(bytes_.size()) + " bytes, too short for a header");
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
      if (e.offset % kAlignment || e.offset < end)
        error(at, name + ": offset " + str(e.offset) + " misaligned or overlapping");
      if (e.offset > bytes_.size() || e.count > (bytes_.size() - e.offset) / e.element_size)
        error(at, name + ": " + str(e.count) + " elements past the end of the file");
      if (XXH64(bytes_.data() + e.offset, e.count * e.element_size, 0) != e.checksum)
        error(e.offset, name + ": checksum mismatch");
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
    if (e.element_size == 0 || e.offset > bytes.size() || e.count > (bytes.size() - e.offset) / e.element_size)
      continue;
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
  const MultilevelParts parts = multilevel_parts(m);
  const uint32_t section_count = uint32_t(parts.levels.size()) + 1;
  auto align = [](uint64_t x) { return (x + kAlignment - 1) / kAlignment * kAlignment; };
  std::vector<SectionEntry> table(section_count);
  uint64_t at = align(sizeof(FileHeader) + uint64_t(section_count) * sizeof(SectionEntry));
  table[0] = {{'H', 'E', 'A', 'D'}, uint32_t(parts.head.size()), at, 1, XXH64(parts.head.data(), parts.head.size(), 0)};
  at = align(at + parts.head.size());
  for (size_t i = 0; i < parts.levels.size(); ++i) {
    const auto& bytes = parts.levels[i];
    table[i + 1] = {{'L', 'E', 'V', 'L'}, 4, at, bytes.size() / 4, XXH64(bytes.data(), bytes.size(), 0)};
    at = align(at + bytes.size());
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
  std::memcpy(out.data() + table[0].offset, parts.head.data(), parts.head.size());
  for (size_t i = 0; i < parts.levels.size(); ++i)
    std::memcpy(out.data() + table[i + 1].offset, parts.levels[i].data(), parts.levels[i].size());
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
  if (he.count != 1) in.error(he.offset, "section HEAD: wrong size");
  MultilevelLoader loader(where + ": offset " + str(he.offset), bytes.subspan(he.offset, he.element_size), limits);
  for (++i; i < table.size(); ++i) {
    const SectionEntry& e = table[i];
    if (!tag_is(e, "LEVL")) continue;
    if (e.element_size != 4) in.error(e.offset, "section LEVL: element size " + str(e.element_size) + " (4 expected)");
    loader.add_level(where, bytes.subspan(e.offset, e.count * 4), e.offset);
  }
  if (!loader.complete())
    in.error(bytes.size(), str(loader.level_count() - loader.levels_loaded()) + " of HEAD's " +
                               str(loader.level_count()) + " LEVL sections are missing");
  return loader.release();
}

}  // namespace pms
