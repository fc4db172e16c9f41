// The lattices of nested refinement info (spm/nested_info.h). Everything is integer arithmetic on the stored
// codes, so the builder, the server and every client compute the same entries bit for bit.
#include "spm/nested_info.h"

namespace pms {
namespace {

constexpr uint32_t kCodesPerOctave = 1u << (10 - kLengthDroppedBits);
constexpr uint32_t kAngleEntries = kLatticeOctaves * kAngleStepsPerOctave;
static_assert(kAngleStepsPerOctave == 8, "kFraction holds eighths of an octave");
// round(2^32 * 2^(-j/8)): entry k = 8o + j is ceil(parent * kFraction[j] / 2^(32 + o)).
constexpr uint64_t kFraction[8] = {4294967296u, 3938502376u, 3611622603u, 3311872529u,
                                   3037000500u, 2784941738u, 2553802834u, 2341847524u};

uint32_t length_code(uint16_t half) { return half >> kLengthDroppedBits; }
uint32_t length_entries(uint32_t codes_per_step) { return kLatticeOctaves * kCodesPerOctave / codes_per_step; }

// ceil(parent * 2^(-k/8)) for any k (parent <= kConeSteps, so the product fits in 64 bits).
uint32_t angle_fraction(uint16_t parent, uint32_t k) {
  const uint32_t shift = 32 + k / kAngleStepsPerOctave;
  if (shift >= 64) return parent > 0 ? 1 : 0;
  return uint32_t((uint64_t(parent) * kFraction[k % kAngleStepsPerOctave] + (uint64_t(1) << shift) - 1) >> shift);
}

}  // namespace

uint32_t length_entry(uint16_t parent, uint16_t own, uint32_t codes_per_step) {
  const uint32_t p = length_code(parent), o = length_code(own);
  if (o > p) return kNoEntry;
  const uint32_t k = (p - o) / codes_per_step;
  return k <= length_entries(codes_per_step) ? k : kNoEntry;
}

uint32_t length_at_entry(uint16_t parent, uint32_t k, uint32_t codes_per_step) {
  const uint32_t p = length_code(parent);
  if (k > length_entries(codes_per_step) || uint64_t(k) * codes_per_step > p) return kNoEntry;
  return (p - k * codes_per_step) << kLengthDroppedBits;
}

uint32_t angle_at_entry(uint16_t parent, uint32_t k) {
  return parent > kConeSteps || k > kAngleEntries ? kNoEntry : angle_fraction(parent, k);
}

uint32_t angle_entry(uint16_t parent, uint16_t own) {
  if (parent > kConeSteps || own > parent) return kNoEntry;
  uint32_t k = 0;  // entries fall with k: the last one still at or above `own`
  while (k <= kAngleEntries && angle_fraction(parent, k + 1) >= own) ++k;
  return k > kAngleEntries ? kNoEntry : k;  // below the last entry: the exact value
}

}  // namespace pms
