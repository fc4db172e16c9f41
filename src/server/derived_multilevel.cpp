// A .pms model's levels (derived_multilevel.h): refine it completely, renumber the result as the cleaned
// input was, and build the multilevel mesh from its hierarchy's collapses.
#include "server/derived_multilevel.h"

#include <string>
#include <vector>

#include "common/error.h"
#include "multilevel/build.h"
#include "spm/stream_order.h"

namespace pms::server {
namespace {

// Replayed in stream order from the roots, the engine's hierarchy puts root t in slot t and the i-th
// split's v_t, v_u in the next two slots (VertexHierarchy::add_split), so a slot names its node.
std::vector<uint32_t> node_of_slot(const ModelData& model) {
  std::vector<uint32_t> nodes(model.root_count + 2 * model.split_order.size());
  for (uint32_t r = 0; r < model.root_count; ++r) nodes[r] = r;
  for (size_t i = 0; i < model.split_order.size(); ++i) {
    const uint32_t t = model.first_child[model.split_order[i]];
    nodes[model.root_count + 2 * i] = t;
    nodes[model.root_count + 2 * i + 1] = t + 1;
  }
  return nodes;
}

}  // namespace

Mesh full_resolution_mesh(const ModelData& model) {
  const MeshArrays arrays = refine_in_stream_order(model, model.split_order.size());
  const std::vector<uint32_t> nodes = node_of_slot(model);
  const size_t vertices = arrays.slots.size();
  const auto bad = [](const std::string& why) { fail("multilevel", "the model's leaves " + why); };
  Mesh mesh;
  mesh.positions.resize(3 * vertices);
  if (!model.normals.empty()) mesh.normals.resize(3 * vertices);
  if (!model.colors.empty()) mesh.colors.resize(4 * vertices);
  std::vector<uint32_t> input(vertices);  // per extracted vertex: its number in the cleaned input
  std::vector<uint8_t> seen(vertices);
  for (size_t i = 0; i < vertices; ++i) {
    const uint32_t slot = arrays.slots[i];
    const uint32_t node = slot < nodes.size() ? nodes[slot] : kNone;
    if (node == kNone || !model.is_leaf(node)) bad("are not what complete refinement extracts");
    const uint32_t v = model.leaf_vertex[node];
    if (v >= vertices || seen[v]) bad("do not number the input vertices once each");
    seen[v] = 1;
    input[i] = v;
    for (int k = 0; k < 3; ++k) mesh.positions[3 * size_t(v) + k] = model.position[3 * size_t(node) + k];
    for (int k = 0; k < 3 && !mesh.normals.empty(); ++k)
      mesh.normals[3 * size_t(v) + k] = model.normals[3 * size_t(node) + k];
    for (int k = 0; k < 4 && !mesh.colors.empty(); ++k)
      mesh.colors[4 * size_t(v) + k] = model.colors[4 * size_t(node) + k];
  }
  mesh.indices.reserve(arrays.indices.size());
  for (uint32_t corner : arrays.indices) mesh.indices.push_back(input[corner]);
  return mesh;
}

std::unique_ptr<ServedMultilevel> derive_multilevel(const std::string& name, const std::string& path,
                                                    const std::string& version, const ModelData& model) {
  const Mesh mesh = full_resolution_mesh(model);
  return serve_multilevel(build_multilevel(mesh, collapses_of(model)), name, path, version);
}

}  // namespace pms::server
