// Kim, Lee, Kobbelt 2005 §5.3 (SelectiveStreaming, SelStreamVSplit) and §6.1 (windowed active tags).
#include "server/selective_streaming.h"

#include <algorithm>
#include <stdexcept>

#include "spm/hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

// A front of the whole forest always holds an ancestor of every node: none means the tags are broken.
uint32_t front_ancestor(const ModelData& model, const ActiveTags& tags, uint32_t node) {
  if (node == kNone) return kNone;
  const uint32_t a = active_ancestor(model, tags, node);
  if (a == kNone) throw std::logic_error("SelStreamVSplit: a cut vertex has no active ancestor");
  return a;
}

// StreamVSplit: the client will have v's children, so the server's front moves below v.
void stream_vsplit(const ModelData& model, ActiveTags& tags, uint32_t node, std::vector<uint32_t>& out) {
  tags.split(node, model.first_child[node]);
  out.push_back(node);
}

// SelStreamVSplit(v) without recursion: v's split waits on the stack while the ancestor shared by
// its cut vertices is split first, and so on down the chain. With `cuts`, every split's active ancestors
// are recorded (the dependency check's, where it ran).
void sel_stream_vsplit(const ModelData& model, const DependencyFilter& dependencies, ActiveTags& tags, uint32_t node,
                       std::vector<uint32_t>& out, std::vector<uint32_t>& stack, std::vector<ActualCuts>* cuts) {
  stack.clear();
  stack.push_back(node);
  while (!stack.empty()) {
    const uint32_t v = stack.back();
    if (!tags.is_active(v)) {  // already split while serving another chain
      stack.pop_back();
      continue;
    }
    // The cut arrays are read only where needed: most splits of a sender-driven answer never look.
    const bool check = dependencies.may_wait(v);
    if (check || cuts) {
      const uint32_t cut_l = model.cut_left[v], cut_r = model.cut_right[v];
      if (check && cut_l != kNone && cut_r != kNone) {
        const uint32_t left = front_ancestor(model, tags, cut_l), right = front_ancestor(model, tags, cut_r);
        if (left == right) {
          stack.push_back(left);
          continue;
        }
        if (cuts) cuts->push_back({left, right});
      } else if (cuts) {
        cuts->push_back({front_ancestor(model, tags, cut_l), front_ancestor(model, tags, cut_r)});
      }
    }
    stream_vsplit(model, tags, v, out);
    stack.pop_back();
  }
}

// Max-heap on importance; ties broken by node index, so the batch is the same on every run. A function
// object, not a function pointer, so the heap algorithms inline it.
struct LessImportant {
  bool operator()(const std::pair<float, uint32_t>& a, const std::pair<float, uint32_t>& b) const {
    return a.first < b.first || (a.first == b.first && a.second > b.second);
  }
};
constexpr LessImportant less_important;

}  // namespace

uint32_t active_ancestor(const ModelData& model, const ActiveTags& tags, uint32_t node) {
  while (node != kNone && !tags.is_active(node)) node = model.parent[node];
  return node;
}

void SelectiveStreamer::start(const ModelData& model, const DependencyFilter& dependencies, ActiveTags& tags,
                              Importance importance, server::PhaseTimes* phases) {
  model_ = &model;
  phases_ = phases;
  dependencies_ = &dependencies;
  tags_ = &tags;
  importance_ = std::move(importance);
  heap_.reserve(kMaxRanked);
  begin_scan();
}

void SelectiveStreamer::begin_scan() {
  heap_.clear();
  overflow_ = false;
  scan_ = tags_->next_active(0);
}

// While scanning, heap_ is a min-heap on importance: its front is the least important of the best so far.
bool SelectiveStreamer::continue_scan(uint64_t budget, uint64_t& work) {
  const auto more_important = [](const std::pair<float, uint32_t>& a, const std::pair<float, uint32_t>& b) {
    return less_important(b, a);
  };
  const ModelData& model = *model_;
  const uint64_t stop = work + budget;
  for (uint32_t v = scan_; v != UINT32_MAX; v = tags_->next_active(v + 1)) {
    if (work >= stop) {
      scan_ = v;
      return false;
    }
    ++work;  // leaves too: a front of a fine mesh is mostly leaves, each a lookup
    if (model.is_leaf(v)) continue;
    const std::pair<float, uint32_t> entry{importance_(v), v};
    if (entry.first <= 0) continue;
    if (heap_.size() < kMaxRanked) {
      heap_.push_back(entry);
      std::push_heap(heap_.begin(), heap_.end(), more_important);
      continue;
    }
    overflow_ = true;
    if (!more_important(entry, heap_.front())) continue;
    std::pop_heap(heap_.begin(), heap_.end(), more_important);
    heap_.back() = entry;
    std::push_heap(heap_.begin(), heap_.end(), more_important);
  }
  scan_ = kNotScanning;
  std::make_heap(heap_.begin(), heap_.end(), less_important);
  return true;
}

void SelectiveStreamer::rank(uint32_t node, float importance) {
  if (heap_.size() >= kMaxRanked) {
    overflow_ = true;
    return;
  }
  heap_.emplace_back(importance, node);
  std::push_heap(heap_.begin(), heap_.end(), less_important);
}

bool SelectiveStreamer::step(size_t max_splits, uint64_t budget, std::vector<uint32_t>& out, uint64_t& work,
                             std::vector<ActualCuts>* cuts) {
  if (!model_) return true;
  const ModelData& model = *model_;
  const size_t start = out.size();
  const uint64_t stop = work + budget;
  for (;;) {
    if (scan_ != kNotScanning) {
      const server::PhaseTimer timer(phases_, server::Phase::determine_visibility);
      if (!continue_scan(stop > work ? stop - work : 0, work)) return false;
    }
    if (heap_.empty()) {
      if (!overflow_) return true;
      begin_scan();
      continue;
    }
    if (out.size() - start >= max_splits || work >= stop) return false;
    std::pop_heap(heap_.begin(), heap_.end(), less_important);
    const uint32_t v = heap_.back().second;
    heap_.pop_back();
    if (!tags_->is_active(v)) continue;  // split earlier as a dependency
    const size_t before = out.size();
    {
      const server::PhaseTimer timer(phases_, server::Phase::update_front);
      sel_stream_vsplit(model, *dependencies_, *tags_, v, out, stack_, cuts);
    }
    work += out.size() - before;
    // Children of every split just made may want refining too; forced splits' children included.
    const server::PhaseTimer timer(phases_, server::Phase::determine_visibility);
    for (size_t i = before; i < out.size(); ++i) {
      const uint32_t child = model.first_child[out[i]];
      for (uint32_t c : {child, child + 1}) {
        if (!tags_->is_active(c) || model.is_leaf(c)) continue;
        ++work;
        const float error = importance_(c);
        if (error > 0) rank(c, error);
      }
    }
  }
}

void SelectiveStreamer::stop() {
  model_ = nullptr;
  phases_ = nullptr;
  dependencies_ = nullptr;
  tags_ = nullptr;
  importance_ = nullptr;
  scan_ = kNotScanning;
  std::vector<std::pair<float, uint32_t>>().swap(heap_);
  std::vector<uint32_t>().swap(stack_);
}

bool selective_streaming(const ModelData& model, const DependencyFilter& dependencies, ActiveTags& tags,
                         const Importance& importance, size_t max_splits, std::vector<uint32_t>& out) {
  SelectiveStreamer streamer;
  streamer.start(model, dependencies, tags, importance);
  uint64_t work = 0;
  return streamer.step(max_splits, UINT64_MAX / 2, out, work);
}

}  // namespace pms
