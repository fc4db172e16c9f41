// The container level of a .pms file: header, section table, bounds and checksums. Runs before
// any section is interpreted, so later code may index sections of the announced sizes freely.
#define XXH_STATIC_LINKING_ONLY  // XXH64_state_t on the stack
#include <xxhash.h>

#include <cstring>

#include "common/error.h"
#include "spm/pms_format_internal.h"

namespace pms::format {
namespace {

// Tags of corrupt or foreign sections may hold any byte; keep the error message one clean line.
std::string printable_tag(const char tag[4]) {
  std::string s(tag, 4);
  for (char& c : s)
    if (c < 0x20 || c > 0x7E) c = '?';
  return s;
}

int known_section(const char tag[4]) {
  for (int k = 0; k < kSectionCount; ++k)
    if (std::memcmp(kSections[k].tag, tag, 4) == 0) return k;
  return -1;
}

[[noreturn]] void header_error(const std::string& where, const std::string& what) { fail(where, "header: " + what); }

[[noreturn]] void entry_error(const std::string& where, const SectionEntry& e, const std::string& what) {
  fail(where, "section " + printable_tag(e.tag) + ": " + what);
}

// Magic and version come first: a newer version may lay out everything after them differently.
FileHeader read_header(const std::string& where, const uint8_t* data, uint64_t size) {
  FileHeader h;
  if (size < sizeof h)
    header_error(where, "file is " + str(size) + " bytes, shorter than the " + str(sizeof h) + "-byte header");
  std::memcpy(&h, data, sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) header_error(where, "not a .pms file (bad magic)");
  if (h.version != kVersion)
    header_error(where, "unsupported version " + str(h.version) + " (this build reads " + str(kVersion) +
                            (h.version < kVersion ? "; rebuild the file with this pmstream)" : ")"));
  if (h.header_bytes != sizeof h)
    header_error(where, "header size " + str(h.header_bytes) + ", version " + str(kVersion) + " has " + str(sizeof h));
  if (h.flags != 0) header_error(where, "unknown flags " + str(h.flags));
  const uint64_t table_end = sizeof h + uint64_t(h.section_count) * sizeof(SectionEntry);  // < 2^38: no overflow
  if (table_end > size)
    header_error(where, "section table of " + str(h.section_count) + " entries runs past the end of the " + str(size) +
                            "-byte file (truncated?)");
  if (header_checksum(data, table_end) != h.header_checksum)
    header_error(where, "checksum mismatch (corrupt header or section table)");
  return h;
}

// One table entry: aligned, after the previous section, inside the file, intact.
void check_entry(const std::string& where, const SectionEntry& e, uint64_t previous_end, const uint8_t* data,
                 uint64_t size) {
  const int kind = known_section(e.tag);
  if (e.element_size == 0) entry_error(where, e, "element size 0");
  if (kind >= 0 && e.element_size != kSections[kind].element_size)
    entry_error(where, e, "element size " + str(e.element_size) + ", expected " + str(kSections[kind].element_size));
  if (e.offset % kAlignment != 0) entry_error(where, e, "offset " + str(e.offset) + " is not 64-byte aligned");
  if (e.offset < previous_end)
    entry_error(where, e, "offset " + str(e.offset) + " overlaps the section table or the previous section");
  // Division, not multiplication: an absurd count must not wrap around to a small size.
  if (e.offset > size || e.count > (size - e.offset) / e.element_size)
    entry_error(where, e,
                str(e.count) + " elements of " + str(e.element_size) + " bytes at offset " + str(e.offset) +
                    " run past the end of the " + str(size) + "-byte file (truncated?)");
  if (XXH64(data + e.offset, e.count * e.element_size, 0) != e.checksum)
    entry_error(where, e, "checksum mismatch (corrupt data)");
}

}  // namespace

uint64_t header_checksum(const uint8_t* header_and_table, uint64_t bytes) {
  constexpr size_t field = offsetof(FileHeader, header_checksum);
  constexpr uint8_t zeros[sizeof(uint64_t)] = {};
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, header_and_table, field);
  XXH64_update(&state, zeros, sizeof zeros);
  XXH64_update(&state, header_and_table + field + sizeof zeros, bytes - field - sizeof zeros);
  return XXH64_digest(&state);
}

SectionMap locate_sections(const std::string& where, const uint8_t* data, uint64_t size) {
  const FileHeader header = read_header(where, data, size);
  SectionMap map{};
  uint64_t end = sizeof header + uint64_t(header.section_count) * sizeof(SectionEntry);
  for (uint32_t i = 0; i < header.section_count; ++i) {
    SectionEntry e;
    std::memcpy(&e, data + sizeof header + uint64_t(i) * sizeof e, sizeof e);
    check_entry(where, e, end, data, size);
    end = e.offset + e.count * e.element_size;
    const int kind = known_section(e.tag);
    if (kind < 0) continue;  // a section this version does not know: intact, so skip it
    if (map[kind].present) entry_error(where, e, "appears twice");
    map[kind] = {data + e.offset, e.count, true};
  }
  // After the sections, so that a truncated file names the section it cuts.
  if (header.file_size != size)
    header_error(where, "file is " + str(size) + " bytes but the header says " + str(header.file_size) +
                            " (truncated or appended to?)");
  for (int k = 0; k < kSectionCount; ++k)
    if (kSections[k].required && !map[k].present) section_error(where, Section(k), "missing");
  return map;
}

}  // namespace pms::format
