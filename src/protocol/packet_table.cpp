// PacketTable: a model's vsplit packets encoded once (protocol.h), for the server's hot path.
#include <exception>
#include <mutex>

#include "common/parallel.h"
#include "protocol/wire_internal.h"

namespace pms::protocol {
namespace {

// Nodes are encoded in blocks, each starting on a word of its own, so blocks fill the pool in parallel.
constexpr size_t kBlockNodes = 4096;

// Runs fn(block) over all blocks on every core; the first exception is rethrown here.
template <class Fn>
void for_each_block(size_t blocks, Fn&& fn) {
  std::exception_ptr failure;
  std::mutex failure_mutex;
  for_each_range(blocks, 2, [&](size_t begin, size_t end) {
    try {
      for (size_t b = begin; b < end; ++b) fn(b);
    } catch (...) {
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (!failure) failure = std::current_exception();
    }
  });
  if (failure) std::rethrow_exception(failure);
}

}  // namespace

PacketTable::PacketTable(const ModelView& model, const StreamContext& context) {
  if (const std::string why = check_context(context); !why.empty()) fail("VSPLITS", "stream context: " + why);
  const size_t n = model.node_count(), blocks = (n + kBlockNodes - 1) / kBlockNodes;
  // Pass 1: every packet's length, from the same accounting the encoder is tested against.
  where_.assign(n, 0);
  for_each_block(blocks, [&](size_t b) {
    for (size_t v = b * kBlockNodes; v < std::min(n, (b + 1) * kBlockNodes); ++v)
      if (!model.is_leaf(uint32_t(v))) where_[v] = packet_bits(split_record(model, uint32_t(v)), context).total();
  });
  // Offsets: packets back to back within a block, blocks word-aligned.
  uint64_t at = 0;
  for (size_t b = 0; b < blocks; ++b) {
    at = (at + 63) / 64 * 64;
    for (size_t v = b * kBlockNodes; v < std::min(n, (b + 1) * kBlockNodes); ++v) {
      const uint64_t length = where_[v];
      if (length >= (uint64_t(1) << kLengthBits)) fail("VSPLITS", "a packet of " + std::to_string(length) + " bits");
      if (length) where_[v] = at << kLengthBits | length;
      at += length;
    }
  }
  bits_.assign((at + 63) / 64 + 1, 0);  // +1: bits_from may read the word after a packet's last one
  // Pass 2: each packet through the encoder, its bits copied into place.
  for_each_block(blocks, [&](size_t b) {
    for (size_t v = b * kBlockNodes; v < std::min(n, (b + 1) * kBlockNodes); ++v) {
      if (!where_[v]) continue;
      Writer w(MessageType::vsplits);
      write_packet(w, split_record(model, uint32_t(v)), context);
      w.align();
      const std::span<const uint8_t> bytes = w.payload();
      uint64_t bit = where_[v] >> kLengthBits;
      const uint64_t end = bit + (where_[v] & ((1u << kLengthBits) - 1));
      for (size_t i = 0; bit < end; ++i) {
        const unsigned take = unsigned(std::min<uint64_t>(8, end - bit));
        const uint64_t value = bytes[i] & ((1u << take) - 1);
        bits_[bit / 64] |= value << (bit % 64);
        if (bit % 64 + take > 64) bits_[bit / 64 + 1] |= value >> (64 - bit % 64);
        bit += take;
      }
    }
  });
}

std::vector<uint8_t> PacketTable::encode(uint32_t frame, bool final, std::span<const uint32_t> nodes) const {
  Writer w(MessageType::vsplits);
  uint64_t total = 0;
  for (uint32_t node : nodes) {
    if (node >= where_.size() || !where_[node])
      fail("VSPLITS", "node " + std::to_string(node) + " is not an internal node of the model");
    total += where_[node] & ((1u << kLengthBits) - 1);
  }
  w.reserve_payload(9 + (total + 7) / 8);
  write_vsplits_header(w, frame, final, nodes.size());
  for (uint32_t node : nodes) w.bits_from(bits_, where_[node] >> kLengthBits, where_[node] & ((1u << kLengthBits) - 1));
  return w.finish();
}

}  // namespace pms::protocol
