// libFuzzer target for records format 2's reader (protocol/split_bands.h), the receiver-driven client's
// decoder of every split answer: the input is u8 depth and form (bit 7: the plain form, whose records
// say which children have splits) | u8 id count | a body. A real model's code tables in that form and a
// client holding its base mesh read the hostile body as the answer to the first ids' bands; it
// either attaches splits or throws pms::Error, and the mesh refined by what it attached stays valid or
// refuses a split with pms::Error.
#include <cstddef>
#include <cstdint>
#include <span>

#include "builder/build.h"
#include "common/bit_stream.h"
#include "common/error.h"
#include "io/shapes.h"
#include "protocol/split_bands.h"
#include "spm/refine_info.h"
#include "spm/selective_mesh.h"
#include "spm/split_codec.h"
#include "spm/vertex_hierarchy.h"

namespace {

constexpr uint32_t kPositionBits = 16;
constexpr uint32_t kMaxRecords = 4096;

struct Model {
  pms::Hierarchy hierarchy;
  pms::ModelData model;
  pms::PositionGrid grid;
  pms::SplitCodec codec, plain_codec;
};

pms::SplitCodec codec_of(const pms::ModelData& model, pms::RecordForm form) {
  const pms::EncodedRecords records = pms::encode_records(model, kPositionBits, form);
  pms::BitReader r(records.tables, "tables");
  return pms::SplitCodec::deserialize(r);
}

const Model& model() {
  static const Model m = [] {
    Model built;
    built.hierarchy = pms::build_progressive_mesh(pms::make_terrain(3000, 2), pms::BuildOptions{}).hierarchy;
    built.model = pms::model_of(built.hierarchy);
    built.grid = pms::model_grid(built.model, kPositionBits);
    built.codec = codec_of(built.model, pms::RecordForm::info);
    built.plain_codec = codec_of(built.model, pms::RecordForm::plain);
    return built;
  }();
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const Model& m = model();
  const bool plain = data[0] & 0x80;
  pms::protocol::SplitRequest request{uint32_t((data[0] & 0x7F) % 9), {}};
  for (uint32_t r = 0; r < m.model.root_count && request.ids.size() < size_t(data[1] % 32 + 1); ++r)
    if (!m.model.is_leaf(r)) request.ids.push_back(m.model.id(r));
  pms::VertexHierarchy h;
  for (uint32_t r = 0; r < m.model.root_count; ++r) {
    float p[3];
    pms::snap_position(m.grid, &m.model.position[3 * size_t(r)], p);
    const pms::RefineInfo sent = pms::as_sent(m.model.refine[r]);
    h.add_root(m.model.id(r), p, plain && !pms::never_refines(sent) ? pms::plain_split_info() : sent);
  }
  try {
    pms::protocol::read_split_bands(std::span(data + 2, size - 2), request, plain ? m.plain_codec : m.codec, m.grid, h,
                                    kMaxRecords);
  } catch (const pms::Error&) {
  }
  // Whatever was attached, refining the base mesh by it either keeps a valid mesh or stops with
  // pms::Error at a split whose cut vertices do not fit (a hostile server's records decode to ids the
  // model has, not necessarily to its splits): the client then drops the model, it never corrupts it.
  pms::SelectiveMesh mesh(h, m.model.base_faces);
  try {
    for (uint32_t slot = 0; slot < h.size(); ++slot)
      if (!h.is_leaf(slot)) mesh.vsplit(slot);
  } catch (const pms::Error&) {
    return 0;
  }
  if (!mesh.check_invariants(nullptr)) __builtin_trap();
  return 0;
}
