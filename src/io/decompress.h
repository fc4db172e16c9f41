// In-memory decompression of a mesh file's outer .gz / .xz layer (io layer internal).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/progress.h"

namespace pms {

// A decompression bomb (a few KB inflating to terabytes) must fail instead of exhausting memory;
// 8 GiB is far above any mesh this tool is meant to build.
constexpr uint64_t kMaxDecompressedBytes = uint64_t(8) << 30;

enum class Compression { none, gzip, xz };

// Picks the codec from a trailing ".gz" / ".xz" (case-insensitive).
Compression compression_of(std::string_view name);

// `name` without its compression suffix, so the inner extension picks the mesh format.
std::string_view strip_compression_suffix(std::string_view name);

// Decompresses a whole gzip (concatenated members allowed) or xz stream. Reports `progress`
// fractions of the input consumed. Throws pms::Error "NAME: problem" on corrupt or truncated
// data and when the output would exceed `max_output` bytes.
std::vector<uint8_t> decompress(const std::string& name, Compression codec, std::span<const uint8_t> bytes,
                                const ProgressFn& progress = {}, uint64_t max_output = kMaxDecompressedBytes);

}  // namespace pms
