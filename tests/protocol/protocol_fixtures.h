// Shared by the protocol tests: built models (generated and the shared bunny), random messages, and
// helpers that strip frames and check rejections.
#pragma once
#include <gtest/gtest.h>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "builder/build.h"
#include "protocol/message_types.h"
#include "protocol/stream_context.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::test {

// A built model kept in memory; built once per test binary and name.
struct BuiltModel {
  std::string name;
  Hierarchy hierarchy;
  ModelData model() const { return model_of(hierarchy); }
};
const BuiltModel& sphere_model();   // make_sphere, with per-vertex normals and colors added
const BuiltModel& terrain_model();  // make_terrain(20000)
const BuiltModel* bunny_model();    // nullptr when ../shared/models/bunny.ply.xz is absent
const BuiltModel* horse_model();    // with normals; nullptr when ../shared/models/horse.ply.xz is absent

// The payload of one encoded frame (checks the header's length and type on the way).
std::vector<uint8_t> payload_of(const std::vector<uint8_t>& frame, protocol::MessageType type);

// Runs `decode` and expects a ProtocolError with `code` whose text contains `needle`.
void expect_rejected(const std::function<void()>& decode, protocol::ErrorCode code, const std::string& needle);

// Angle between two (nearly) unit vectors, accurate near 0.
double angle_between(const float* a, const float* b);

// Random values for round trips.
using Rng = std::mt19937_64;
float random_float(Rng& rng, float lo, float hi);
std::string random_name(Rng& rng, size_t max_size);
RefineInfo random_refine(Rng& rng);  // any canonical value (spm/refine_info.h, is_canonical)
protocol::StreamContext random_context(Rng& rng);
// A vsplit packet the context can carry: v_s above the deepest level, cut leaves outside its subtree.
SplitRecord random_split(Rng& rng, const protocol::StreamContext& context);
// A complete front over `trees` trees, random depths up to `max_depth`.
std::vector<VertexId> random_front(Rng& rng, uint32_t trees, int max_depth);

}  // namespace pms::test
