// Reading E6's curves (quality_curve.h): the bytes a client needed to reach a PSNR, and where one mode's
// curve lies against another's. Between samples a curve is a step: the client shows the mesh of its last
// sample until the next one, and after its last it keeps its final mesh.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "bench/quality_curve.h"

namespace pms::bench {

// The bytes of the first sample at or above `psnr`; nothing when the curve never gets there.
std::optional<uint64_t> bytes_to_reach(const std::vector<CurveSample>& samples, double psnr);

// The PSNR a client shows once it has received `bytes`, capped at `cap`; nothing before its first sample.
std::optional<double> psnr_at(const std::vector<CurveSample>& samples, uint64_t bytes, double cap);

struct CurveOrder {
  uint64_t compared = 0;  // byte counts compared: every sample of either curve from where both hold a mesh
  uint64_t above = 0, equal = 0, below = 0;  // `upper` against `lower` there, both capped at the cap
  uint64_t first_below_bytes = 0;            // the first byte count where `upper` is below (when below > 0)
  double worst_deficit = 0;                  // the largest amount `upper` is below by, in dB
  bool not_below() const { return compared > 0 && below == 0; }
};

// Whether `upper` lies at or above `lower` at every byte count where both clients hold a mesh. PSNRs
// are capped at `cap` first (cheng-ooi's curves stop there), so two curves that both passed it are equal.
CurveOrder compare_curves(const std::vector<CurveSample>& upper, const std::vector<CurveSample>& lower, double cap);

}  // namespace pms::bench
