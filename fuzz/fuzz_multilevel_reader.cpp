// libFuzzer target for both multilevel readers (docs/architecture.md, "Correctness properties", 5): any
// bytes either parse into a structure that validates and whose every LOD and geomorph can be taken, or
// throw pms::Error; crashes, hangs, sanitizer reports and huge allocations are findings. The binary form
// is tried with its checksums recomputed, so mutated contents reach the structural checks.
// Seed corpus: files written by `pmstream multilevel build` (with and without --ascii).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include "common/error.h"
#include "multilevel/file.h"
#include "multilevel/mesh.h"
#include "multilevel_touch.h"

namespace {

using fuzz::kLimits;
using fuzz::touch;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    touch(
        pms::parse_multilevel_ascii("fuzz.txt", std::string_view(reinterpret_cast<const char*>(data), size), kLimits));
  } catch (const pms::Error&) {
  }
  std::vector<uint8_t> bytes(data, data + size);
  if (size >= 8) std::memcpy(bytes.data(), "PMSMULTI", 8);
  pms::reseal_multilevel_binary(bytes);
  try {
    touch(pms::parse_multilevel_binary("fuzz.pml", bytes, kLimits));
  } catch (const pms::Error&) {
  }
  return 0;
}
