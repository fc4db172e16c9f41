#include "client/held_leaves.h"

#include "common/error.h"

namespace pms::client {

HeldLeaves::HeldLeaves(const ModelData& model) : model_(&model) { hold_roots(); }

void HeldLeaves::hold_roots() {
  bits_.assign((model_->node_count() + 63) / 64, 0);
  for (uint32_t root = 0; root < model_->root_count; ++root) bits_[root / 64] |= uint64_t(1) << (root % 64);
  splits_ = 0;
}

uint32_t HeldLeaves::split(VertexId vs) {
  const uint32_t n = model_->find(vs);
  if (n == kNone || model_->is_leaf(n))
    fail("server", "a split of " + pms::to_string(vs) + ", which the model cannot split");
  if (!holds(n))
    fail("server", "a split of " + pms::to_string(vs) +
                       ", which is not a leaf this client holds (sent before, or its parent never was)");
  bits_[n / 64] &= ~(uint64_t(1) << (n % 64));
  for (uint32_t child : {model_->first_child[n], model_->first_child[n] + 1})
    bits_[child / 64] |= uint64_t(1) << (child % 64);
  ++splits_;
  return n;
}

std::vector<VertexId> HeldLeaves::leaves() const {
  std::vector<VertexId> out;
  for_each_leaf([&](uint32_t node) { out.push_back(model_->id(node)); });
  return out;
}

}  // namespace pms::client
