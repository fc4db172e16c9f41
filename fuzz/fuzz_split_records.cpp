// libFuzzer target for the split-record decoders (spm/split_codec.h, common/prefix_code.h): the input is
// u16 table bytes T | T bytes of code tables | a record. Hostile tables and records either decode or throw
// pms::Error; a record that decodes re-encodes (where the tables allow) to one that decodes the same. The
// tables' attribute flags come from the input, so v_t's normal and color fields are decoded too, against a
// v_s whose normal lies near the octahedral square's edge (where steps fold over it), and so is the form
// (bit 2: the plain records, which carry the children's presence instead of their info).
#include <cstddef>
#include <cstdint>
#include <span>

#include "common/bit_stream.h"
#include "common/error.h"
#include "spm/octahedral_normal.h"
#include "spm/refine_info.h"
#include "spm/split_codec.h"
#include "spm/vertex_id.h"

namespace {

pms::SplitContext fixed_context() {
  pms::SplitContext c;
  c.vs = {3, 0b1011};
  c.position_s[0] = 100, c.position_s[1] = 20000, c.position_s[2] = 65000;
  c.info_s = {0x2C00, 0x2400, 0x2000, 12, uint16_t(int16_t(-40)), 300};
  c.ancestor_cuts[0] = {3, 0b11011};
  c.ancestor_cuts[1] = {4, 0b10010};
  c.ancestor_cuts[3] = {3, 0b100111};
  c.normal_s[0] = uint16_t(int16_t(32700)), c.normal_s[1] = uint16_t(int16_t(-5000));
  c.color_s[0] = 200, c.color_s[1] = 13, c.color_s[2] = 255, c.color_s[3] = 128;
  return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const size_t table_bytes = size_t(data[0]) | size_t(data[1]) << 8;
  if (table_bytes > size - 2) return 0;
  const std::span<const uint8_t> tables(data + 2, table_bytes), record(data + 2 + table_bytes, size - 2 - table_bytes);
  try {
    pms::BitReader table_reader(tables, "tables");
    const pms::SplitCodec codec = pms::SplitCodec::deserialize(table_reader);
    const pms::SplitContext context = fixed_context();
    pms::BitReader r(record, "record");
    const pms::SplitPayload payload = codec.decode(context, r);
    if (codec.has_normals() && !pms::is_canonical_normal(payload.normal_t)) __builtin_trap();
    pms::BitWriter w;
    try {
      codec.encode(context, payload, w);
    } catch (const pms::Error&) {
      return 0;  // hostile tables may lack the code words the encoder's own choice needs
    }
    pms::BitReader again(w.bytes(), 0, w.size(), "re-encoded");
    if (!(codec.decode(context, again) == payload)) __builtin_trap();
  } catch (const pms::Error&) {
  }
  return 0;
}
