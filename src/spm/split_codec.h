// Compressed split records (docs/pms-format.md "Split records"): one vertex split coded against
// what every client that can ask for it already holds about v_s, with static prefix codes per model.
// A record decodes on its own, so a server can hand out any set of them in any order and an HTTP cache
// can keep each one: the same bytes for every client.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/bit_stream.h"
#include "common/prefix_code.h"
#include "spm/hierarchy.h"
#include "spm/position_grid.h"
#include "spm/refine_info.h"
#include "spm/vertex_id.h"

namespace pms {

// How many of v_s's nearest ancestors lend their cut vertices as references for v_s's own.
constexpr int kCutAncestors = 5;

template <size_t N>
constexpr std::array<VertexId, N> no_vertices() {
  std::array<VertexId, N> ids;
  ids.fill(kNoVertex);
  return ids;
}

// What a client holds about v_s once v_s is in its hierarchy: its id, its quantized position, its
// refinement info as sent (`as_sent`), its normal and color as sent (zeros for a model without them),
// and the cut vertices of the splits that made it and its ancestors.
struct SplitContext {
  VertexId vs;
  uint32_t position_s[3] = {0, 0, 0};
  RefineInfo info_s{};
  uint16_t normal_s[2] = {0, 0};  // octahedral (spm/octahedral_normal.h)
  uint8_t color_s[4] = {0, 0, 0, 0};
  // v̂_l, v̂_r of v_s's parent, then of its grandparent, ...; kNoVertex above the root or for a missing side.
  std::array<VertexId, 2 * kCutAncestors> ancestor_cuts = no_vertices<2 * kCutAncestors>();
};

// What a record carries: the split's fundamental cut vertices, v_t's quantized position, normal and color
// (v_u keeps v_s's: half-edge collapse; zeros for attributes the model lacks) and the children's
// refinement info as sent.
struct SplitPayload {
  VertexId cut_l = kNoVertex, cut_r = kNoVertex;
  uint32_t position_t[3] = {0, 0, 0};
  RefineInfo info_t{}, info_u{};
  uint16_t normal_t[2] = {0, 0};
  uint8_t color_t[4] = {0, 0, 0, 0};
  friend bool operator==(const SplitPayload&, const SplitPayload&) = default;
};

// Bits of one record by part (bench: bits per split by part).
struct RecordBits {
  uint64_t topology = 0, geometry = 0, refinement = 0, normal = 0, color = 0;  // normal, color: v_t's
  uint64_t attributes() const { return normal + color; }
  uint64_t total() const { return topology + geometry + refinement + attributes(); }
  RecordBits& operator+=(const RecordBits& o) {
    topology += o.topology, geometry += o.geometry, refinement += o.refinement, normal += o.normal, color += o.color;
    return *this;
  }
};

// Every internal node's record, in node order, as the .pms file stores them (pms-format.md, SRTB, SROF,
// SREC): the serialized tables, n + 1 bit offsets (node i's record is bits [offsets[i], offsets[i + 1]);
// empty for a leaf) and the records' bit stream, padded to a byte.
struct EncodedRecords {
  std::vector<uint8_t> tables;
  std::vector<uint64_t> offsets;
  std::vector<uint8_t> records;
};

// What a record carries of its children (docs/protocol.md, "The plain form"): their refinement info (the
// sender-driven mode's and today's receiver-driven client's), or only whether each has a split of its own
// (cheng-ooi 2008 §3: no spheres or cones on the wire; the area-ranking client decides by screen area).
enum class RecordForm : uint8_t { info, plain };
const char* record_form_name(RecordForm form);

// The info a plain record's child is held with when it has a split: one that always refines (its sphere
// holds the view, no cone, an error far above any tolerance), so adapt() makes every split the client holds
// and lists every leaf with a split in missing(); a child without one is held with never-refining info.
RefineInfo plain_split_info();
// `payload` with its children's info replaced by what the plain form carries: plain_split_info() for a
// child that has a split, never-refining info for one that has none.
SplitPayload plain_payload(SplitPayload payload, bool t_has_split, bool u_has_split);

// A model's static code tables and the record coder over them.
class SplitCodec {
 public:
  SplitCodec() = default;
  // Tables fitted to every split of the model. `positions` holds 3 quantized coordinates per node on a
  // grid of `position_bits` (1..32) per axis.
  static SplitCodec build(const ModelData& model, std::span<const uint32_t> positions, uint32_t position_bits,
                          RecordForm form = RecordForm::info);
  friend EncodedRecords encode_records(const ModelData& model, uint32_t position_bits, RecordForm form);

  // Throws pms::Error for a payload the tables or the model's widths cannot carry, and in the plain form for
  // children's info other than plain_payload()'s (the form has no room for it).
  void encode(const SplitContext& context, const SplitPayload& payload, BitWriter& w, RecordBits* bits = nullptr) const;
  // Throws pms::Error for a record that is not one: truncated, unknown code word, ids outside the model or
  // inside v_s's subtree, values the quantizer never produces.
  SplitPayload decode(const SplitContext& context, BitReader& r) const;

  // u32 root count, u8 max depth, u8 position bits, u16 grid step ratios x, y, z, f32 largest grid step
  // over the model's scale, u8 attributes (bit 0 normals, bit 1 colors, bit 2 the plain form), then every
  // table (PrefixCode::serialize): the attribute tables only for the attributes the model has, the
  // refinement info's only in the info form. Unknown attribute bits are refused.
  void serialize(BitWriter& w) const;
  static SplitCodec deserialize(BitReader& r);

  uint32_t root_count() const { return root_count_; }
  uint32_t max_depth() const { return max_depth_; }
  uint32_t position_bits() const { return position_bits_; }
  // Whether records carry v_t's normal / color: the model has them.
  bool has_normals() const { return has_normals_; }
  bool has_colors() const { return has_colors_; }
  RecordForm form() const { return form_; }

 private:
  struct Counts;
  struct SymbolLog;
  struct Fitting;
  // build(); with `logs`, also each range of nodes' symbols, so encode_records() writes them without
  // working them out again.
  static SplitCodec fit(const ModelData& model, std::span<const uint32_t> positions, uint32_t position_bits,
                        RecordForm form, std::vector<SymbolLog>* logs);
  // What the record of `node` carries in this codec's form.
  SplitPayload form_payload(const ModelData& model, std::span<const uint32_t> positions, uint32_t node) const;
  // The context the coding reads: the plain form's ignores v_s's info, which its clients do not hold.
  SplitContext coding_context(const SplitContext& context) const;
  template <class Out>
  void emit_children(const SplitContext& context, const SplitPayload& payload, Out& out) const;
  void decode_children(const SplitContext& context, BitReader& r, SplitPayload& payload) const;
  // Every slot's code words in one array, at kFirstSymbol[slot] + symbol (split_codec.cpp): the word in
  // stream order from the lowest bit, its length from bit 16.
  std::vector<uint32_t> code_words() const;
  template <class Out>
  void emit(const SplitContext& context, const SplitPayload& payload, Out& out) const;
  // The cut vertices (topology).
  template <class Out>
  void emit_cuts(const SplitContext& context, const SplitPayload& payload, Out& out) const;

  // Whether the tables of `slot` are serialized: every core slot, an attribute's only when the model has it.
  bool carried(uint32_t slot) const;
  template <class Out>
  void emit_attributes(const SplitContext& context, const SplitPayload& payload, uint32_t edge, Out& out) const;
  void decode_attributes(const SplitContext& context, uint32_t edge, BitReader& r, SplitPayload& payload) const;

  uint32_t root_count_ = 0, max_depth_ = 0, position_bits_ = 0;
  bool has_normals_ = false, has_colors_ = false;
  RecordForm form_ = RecordForm::info;
  std::array<uint16_t, 3> steps_{};  // each axis's grid step over the largest, in 1/65535
  float grid_step_ = 0;              // the largest grid step over the model's scale; 0 without a grid (serialized,
                                     // read by no field since nested info: docs/protocol.md)
  std::vector<PrefixCode> codes_;    // one per slot (split_codec.cpp)
};

// The grid of `position_bits` per axis over the model's box, and the 3 quantized coordinates per node on
// it that records carry.
PositionGrid model_grid(const ModelData& model, uint32_t position_bits);
// Each axis's grid step over the largest one (the box's extents), in 1/65535: what makes a direction on
// the grid a direction in space.
std::array<uint16_t, 3> grid_step_ratios(const ModelData& model);
// The largest axis's grid step in the refinement info's length unit (the model's scale); 0 for float positions.
float largest_grid_step(const ModelData& model, uint32_t position_bits);
std::vector<uint32_t> grid_positions(const ModelData& model, uint32_t position_bits);

// The tables fitted to the model and every record coded with them, in `form`.
EncodedRecords encode_records(const ModelData& model, uint32_t position_bits, RecordForm form = RecordForm::info);

// The codec of stored records, after checking them against the model: the tables parse, fit its ids and
// carry the attributes it has, are of the info form, the offsets are ordered and end with the stream, leaves have none
// and every internal node's record decodes on its own to that node's split. Throws pms::Error naming `where` and the
// node.
SplitCodec check_records(const std::string& where, const ModelData& model, std::span<const uint8_t> tables,
                         std::span<const uint64_t> offsets, std::span<const uint8_t> records);

// The context and payload of internal node `node` of a complete model (the builder's and the tests'
// view; a client builds the context from its own hierarchy).
SplitContext split_context(const ModelData& model, std::span<const uint32_t> positions, uint32_t node);
SplitPayload split_payload(const ModelData& model, std::span<const uint32_t> positions, uint32_t node);

}  // namespace pms
