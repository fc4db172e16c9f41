// libFuzzer target for the .pms reader (docs/architecture.md, "Correctness properties", 5): any bytes
// either open or throw pms::Error; crashes, hangs, sanitizer reports and huge allocations are findings.
// Seed corpus: files written by `pmstream build` or by the pm tests.
#include <xxhash.h>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/pms_format_internal.h"

namespace {

using namespace pms::format;

// A random mutation almost never keeps its section's checksum valid, so on its own the fuzzer
// would stop at the checksum checks. Recomputing them (where the table allows) lets mutated
// contents reach the structural validation too.
void fix_checksums(std::vector<uint8_t>& bytes) {
  if (bytes.size() < sizeof(FileHeader)) return;
  FileHeader header;
  std::memcpy(&header, bytes.data(), sizeof header);
  const uint64_t table_end = sizeof header + uint64_t(header.section_count) * sizeof(SectionEntry);
  if (table_end > bytes.size()) return;
  for (uint32_t i = 0; i < header.section_count; ++i) {
    SectionEntry e;
    uint8_t* at = bytes.data() + sizeof header + uint64_t(i) * sizeof e;
    std::memcpy(&e, at, sizeof e);
    if (e.element_size == 0 || e.offset > bytes.size() || e.count > (bytes.size() - e.offset) / e.element_size)
      continue;
    e.checksum = XXH64(bytes.data() + e.offset, e.count * e.element_size, 0);
    std::memcpy(at, &e, sizeof e);
  }
  header.header_checksum = header_checksum(bytes.data(), table_end);
  std::memcpy(bytes.data(), &header, sizeof header);
}

void open_and_touch(const uint8_t* data, size_t size) {
  try {
    const auto file = pms::PmsFile::from_bytes("fuzz.pms", data, size);
    // What a consumer does first: ids must resolve to their own nodes.
    const pms::ModelData& m = file->model();
    for (uint32_t n = 0; n < m.node_count(); ++n)
      if (m.find(m.id(n)) != n) __builtin_trap();
  } catch (const pms::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  open_and_touch(data, size);
  std::vector<uint8_t> fixed(data, data + size);
  fix_checksums(fixed);
  open_and_touch(fixed.data(), fixed.size());
  return 0;
}
