// PacketTable: a model's vsplit packets encoded once (packet_table.h), for the server's hot path.
#include <algorithm>
#include <exception>
#include <mutex>

#include "common/bit_stream.h"
#include "common/parallel.h"
#include "protocol/message_types.h"
#include "protocol/packet_table.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"

namespace pms::protocol {
namespace {

// Nodes are encoded in blocks, each into a bit stream of its own on some core; the streams are then laid
// end to end, each from a word boundary.
constexpr size_t kBlockNodes = 4096;

struct Block {
  std::vector<uint8_t> bytes;   // the block's packets back to back, padded to a byte
  std::vector<uint64_t> where;  // per node of the block: bit offset in the block << kLengthBits | count
};

}  // namespace

PacketTable::PacketTable(const ModelData& model, const StreamContext& context, const StoredRecords& records) {
  if (const std::string why = check_context(context); !why.empty()) fail("VSPLITS", "stream context: " + why);
  if (!context.records) fail("VSPLITS", "stream context: no split records");
  if (records.offsets.size() != model.node_count() + 1)
    fail("VSPLITS", "split records: not one offset per node plus one");
  build(model, [&](Writer& w, uint32_t node) {
    write_id(w, model.id(node), context, "v_s");
    BitReader record(records.bits, records.offsets[node], records.offsets[node + 1], "stored record");
    for (uint64_t left = record.bits_left(); left > 0; left = record.bits_left()) {
      const unsigned n = unsigned(std::min<uint64_t>(left, 64));
      w.bits(record.bits(n, "record"), n);
    }
  });
}

void PacketTable::build(const ModelData& model, const std::function<void(Writer& w, uint32_t node)>& write) {
  const size_t n = model.node_count();
  std::vector<Block> blocks((n + kBlockNodes - 1) / kBlockNodes);
  std::exception_ptr failure;
  std::mutex failure_mutex;
  for_each_range(blocks.size(), 2, [&](size_t begin, size_t end) {
    try {
      for (size_t b = begin; b < end; ++b) {
        Writer w(MessageType::vsplits);
        Block& block = blocks[b];
        for (size_t v = b * kBlockNodes; v < std::min(n, (b + 1) * kBlockNodes); ++v) {
          if (model.is_leaf(uint32_t(v))) {
            block.where.push_back(0);
            continue;
          }
          const uint64_t at = w.payload_bits();
          write(w, uint32_t(v));
          const uint64_t length = w.payload_bits() - at;
          if (length >= (uint64_t(1) << kLengthBits))
            fail("VSPLITS", "a packet of " + std::to_string(length) + " bits");
          block.where.push_back(at << kLengthBits | length);
        }
        w.align();
        block.bytes.assign(w.payload().begin(), w.payload().end());
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (!failure) failure = std::current_exception();
    }
  });
  if (failure) std::rethrow_exception(failure);
  size_t words = 1;  // +1: bits_from may read the word after a packet's last one
  for (const Block& block : blocks) words += (block.bytes.size() + 7) / 8;
  bits_.assign(words, 0);
  where_.reserve(n);
  size_t word = 0;
  for (Block& block : blocks) {
    for (size_t i = 0; i < block.bytes.size(); ++i) bits_[word + i / 8] |= uint64_t(block.bytes[i]) << (8 * (i % 8));
    for (uint64_t w : block.where) where_.push_back(w ? w + (uint64_t(64 * word) << kLengthBits) : 0);
    word += (block.bytes.size() + 7) / 8;
    std::vector<uint8_t>().swap(block.bytes);
  }
}

std::vector<uint8_t> PacketTable::encode(uint32_t frame, bool final, std::span<const uint32_t> nodes) const {
  return encode_with(frame, vsplits_flags(final, false), nodes);
}

std::vector<uint8_t> PacketTable::encode_ahead(uint32_t frame, std::span<const uint32_t> nodes) const {
  return encode_with(frame, vsplits_flags(false, true), nodes);
}

std::vector<uint8_t> PacketTable::encode_with(uint32_t frame, uint8_t flags, std::span<const uint32_t> nodes) const {
  Writer w(MessageType::vsplits);
  uint64_t total = 0;
  for (uint32_t node : nodes) {
    if (node >= where_.size() || !where_[node])
      fail("VSPLITS", "node " + std::to_string(node) + " is not an internal node of the model");
    total += where_[node] & ((1u << kLengthBits) - 1);
  }
  w.reserve_payload(9 + (total + 7) / 8);
  write_vsplits_header(w, frame, flags, nodes.size());
  for (uint32_t node : nodes) w.bits_from(bits_, where_[node] >> kLengthBits, where_[node] & ((1u << kLengthBits) - 1));
  return w.finish();
}

}  // namespace pms::protocol
