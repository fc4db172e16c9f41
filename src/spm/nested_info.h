// Nested refinement info (docs/internals.md, "Refinement info"): a child's radius, mu, delta and
// cone angle are entries of a lattice below its parent's, rounded up (a parent's bounds hold its children's,
// so the parent's own value is always an entry that holds the child's). The builder stores the entries
// (builder/nested_refine_info.h) and the split records code the entry numbers (spm/split_codec.h), so every
// mode evaluates the same values. Values no entry holds (above the parent's, far below it) stay exact.
// The steps were measured against selectivity (tests/apps/refine_info_nesting_test.cpp): mu carries far
// views' faces, delta close views', the radius and the angle little of either.
#pragma once
#include <cstdint>

#include "spm/refine_info.h"

namespace pms {

// Length codes (a RefineInfo half without its dropped bits: 64 per octave) per lattice step.
constexpr uint32_t kRadiusCodesPerStep = 32;  // half an octave
constexpr uint32_t kMuCodesPerStep = 1;       // the stored precision
constexpr uint32_t kDeltaCodesPerStep = 4;    // a 16th of an octave
constexpr uint32_t kAngleStepsPerOctave = 8;  // cone angle entries: ceil(parent's steps * 2^(-k/8))
constexpr uint32_t kLatticeOctaves = 12;      // how far below the parent's value the entries reach
// A child's own cone axis (when it has a cone) lies on octahedral coordinates that are multiples of this.
constexpr uint32_t kAxisSnapBits = 3;
constexpr uint32_t kNoEntry = UINT32_MAX;

// The lowest entry below the length `parent` (a stored half) that holds the stored length `own`, or
// kNoEntry when none does (own above parent, or below the last entry).
uint32_t length_entry(uint16_t parent, uint16_t own, uint32_t codes_per_step);
// Entry k's length (a stored half), or kNoEntry when there is no such entry.
uint32_t length_at_entry(uint16_t parent, uint32_t k, uint32_t codes_per_step);

// The same for cone angles in RefineInfo::cone_angle steps; `parent` must not be kNoCone.
uint32_t angle_entry(uint16_t parent, uint16_t own);
uint32_t angle_at_entry(uint16_t parent, uint32_t k);

}  // namespace pms
