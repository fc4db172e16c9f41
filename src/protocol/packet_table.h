// A model's vsplit packets, encoded once and shared by every session that streams them.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "protocol/split_bands.h"
#include "protocol/stream_context.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"

namespace pms::protocol {

class Writer;  // wire_internal.h

// Every vsplit packet of a model as a sender-driven session sends it, encoded once and shared by all
// sessions: a VSPLITS batch is then its packets' bits copied back to back, with none of the per-packet
// reads of ids, positions and refinement info scattered over the model (the cache misses that dominated a
// server answering hundreds of first views). ~25 bytes per internal node and 8 per node on the real models.
class PacketTable {
 public:
  PacketTable() = default;
  // The packets of a context with split records (StreamContext::records): v_s's id and the record the
  // model stores (coded against what the client holds about v_s, which a session's client does), copied.
  // Throws pms::Error for a model the context cannot carry (as encode(VSplits) would).
  PacketTable(const ModelData& model, const StreamContext& context, const StoredRecords& records);
  bool empty() const { return where_.empty(); }
  size_t memory_bytes() const { return (bits_.capacity() + where_.capacity()) * sizeof(uint64_t); }

  // The same frame encode(VSplits{frame, final, splits of `nodes`}, context) gives; pms::Error for a node
  // that is not an internal node of the table's model.
  std::vector<uint8_t> encode(uint32_t frame, bool final, std::span<const uint32_t> nodes) const;
  // The same as a batch sent ahead (VSplits::ahead).
  std::vector<uint8_t> encode_ahead(uint32_t frame, std::span<const uint32_t> nodes) const;

 private:
  std::vector<uint8_t> encode_with(uint32_t frame, uint8_t flags, std::span<const uint32_t> nodes) const;
  // Every internal node's packet, as `write` puts it into a batch's bit stream.
  void build(const ModelData& model, const std::function<void(Writer& w, uint32_t node)>& write);
  static constexpr unsigned kLengthBits = 10;  // a packet is < 1024 bits (3 ids of <= 101 bits, info, attributes)
  std::vector<uint64_t> bits_;                 // the packets back to back
  std::vector<uint64_t> where_;                // per node: bit offset << kLengthBits | bit count; 0 for a leaf
};

}  // namespace pms::protocol
