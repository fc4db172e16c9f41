// Kim, Lee, Kobbelt 2005 §5.3 (SelectiveStreaming, SelStreamVSplit) and §6.1 (windowed active tags).
#include "server/selective_streaming.h"

#include <algorithm>

#include "common/parallel.h"

namespace pms {
namespace {

// StreamVSplit: the client will have v's children, so the server's front moves below v.
void stream_vsplit(const ModelView& model, ActiveTags& tags, uint32_t node, std::vector<uint32_t>& out) {
  tags.deactivate(node);
  tags.activate(model.first_child[node]);
  tags.activate(model.first_child[node] + 1);
  out.push_back(node);
}

// SelStreamVSplit(v) without recursion: v's split waits on the stack while the ancestor shared by
// its cut vertices is split first, and so on down the chain.
void sel_stream_vsplit(const ModelView& model, const ClimbStarts& starts, ActiveTags& tags, uint32_t node,
                       std::vector<uint32_t>& out, std::vector<uint32_t>& stack) {
  stack.clear();
  stack.push_back(node);
  while (!stack.empty()) {
    const uint32_t v = stack.back();
    if (!tags.is_active(v)) {  // already split while serving another chain
      stack.pop_back();
      continue;
    }
    const uint32_t cut_l = model.cut_left[v], cut_r = model.cut_right[v];
    if (cut_l != kNone && cut_r != kNone) {
      const uint32_t left = active_ancestor(model, tags, cut_l, starts.of(model, v, 0));
      if (left == active_ancestor(model, tags, cut_r, starts.of(model, v, 1))) {
        stack.push_back(left);
        continue;
      }
    }
    stream_vsplit(model, tags, v, out);
    stack.pop_back();
  }
}

// Max-heap on importance; ties broken by node index, so the batch is the same on every run.
bool less_important(const std::pair<float, uint32_t>& a, const std::pair<float, uint32_t>& b) {
  return a.first < b.first || (a.first == b.first && a.second > b.second);
}

}  // namespace

ClimbStarts::ClimbStarts(const ModelView& model) {
  const size_t internal = (model.node_count() - model.root_count) / 2;
  starts_.assign(2 * kLevels * internal, kNone);
  const auto depth = [&](uint32_t n) { return VertexId{0, model.node_id[n]}.depth(); };
  for_each_range(model.node_count(), 1 << 16, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) {
      if (model.is_leaf(uint32_t(v))) continue;
      const int below = depth(uint32_t(v)) + 1;
      uint32_t* out = &starts_[(size_t(model.first_child[v]) - model.root_count) * kLevels];
      for (int side = 0; side < 2; ++side, out += kLevels) {
        uint32_t n = side == 0 ? model.cut_left[v] : model.cut_right[v];
        if (n == kNone) continue;
        for (int d = depth(n); d > below; --d) n = model.parent[n];
        for (int level = 0; level < kLevels && n != kNone; ++level, n = model.parent[n]) out[level] = n;
      }
    }
  });
}

uint32_t active_ancestor(const ModelView& model, const ActiveTags& tags, uint32_t leaf, const uint32_t* starts) {
  uint32_t up = kNone;  // the next ancestor above the starts
  if (starts) {
    for (int level = 0; level < ClimbStarts::kLevels && starts[level] != kNone; ++level) {
      if (tags.is_active(starts[level])) return starts[level];
      up = starts[level];
    }
    if (up != kNone) up = model.parent[up];
  }
  // Two independent chains of loads, so the misses of one overlap the other's.
  for (uint32_t low = leaf;;) {
    if (up != kNone) {
      if (tags.is_active(up)) return up;
      up = model.parent[up];
    }
    if (low == kNone || tags.is_active(low)) return low;
    low = model.parent[low];
  }
}

void SelectiveStreamer::start(const ModelView& model, const ClimbStarts& starts, ActiveTags& tags,
                              Importance importance) {
  model_ = &model;
  starts_ = &starts;
  tags_ = &tags;
  importance_ = std::move(importance);
  heap_.clear();
  for (uint32_t v = tags.next_active(0); v != UINT32_MAX; v = tags.next_active(v + 1)) {
    if (model.is_leaf(v)) continue;
    const float error = importance_(v);
    if (error > 0) heap_.emplace_back(error, v);
  }
  std::make_heap(heap_.begin(), heap_.end(), less_important);
}

bool SelectiveStreamer::step(size_t max_splits, std::vector<uint32_t>& out) {
  if (!model_) return true;
  const ModelView& model = *model_;
  const size_t start = out.size();
  while (!heap_.empty()) {
    if (out.size() - start >= max_splits) return false;
    std::pop_heap(heap_.begin(), heap_.end(), less_important);
    const uint32_t v = heap_.back().second;
    heap_.pop_back();
    if (!tags_->is_active(v)) continue;  // split earlier as a dependency
    const size_t before = out.size();
    sel_stream_vsplit(model, *starts_, *tags_, v, out, stack_);
    // Children of every split just made may want refining too; forced splits' children included.
    for (size_t i = before; i < out.size(); ++i) {
      const uint32_t child = model.first_child[out[i]];
      for (uint32_t c : {child, child + 1}) {
        if (!tags_->is_active(c) || model.is_leaf(c)) continue;
        const float error = importance_(c);
        if (error <= 0) continue;
        heap_.emplace_back(error, c);
        std::push_heap(heap_.begin(), heap_.end(), less_important);
      }
    }
  }
  return true;
}

void SelectiveStreamer::stop() {
  model_ = nullptr;
  starts_ = nullptr;
  tags_ = nullptr;
  importance_ = nullptr;
  std::vector<std::pair<float, uint32_t>>().swap(heap_);
  std::vector<uint32_t>().swap(stack_);
}

bool selective_streaming(const ModelView& model, const ClimbStarts& starts, ActiveTags& tags,
                         const Importance& importance, size_t max_splits, std::vector<uint32_t>& out) {
  SelectiveStreamer streamer;
  streamer.start(model, starts, tags, importance);
  return streamer.step(max_splits, out);
}

}  // namespace pms
