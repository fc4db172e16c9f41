// Canonical Huffman codes: lengths from counts (a Huffman tree, rebuilt on halved counts until no length
// exceeds kMaxCodeLength, as zlib's and JPEG's writers settle for), code words assigned in canonical order,
// and decoding one bit at a time by code-word ranges per length (Mark Adler's puff.c does the same).
#include "common/prefix_code.h"

#include <algorithm>
#include <bit>
#include <string>

#include "common/error.h"

namespace pms {
namespace {

uint32_t reverse_bits(uint32_t code, unsigned length) {
  uint32_t reversed = 0;
  for (unsigned i = 0; i < length; ++i, code >>= 1) reversed = (reversed << 1) | (code & 1);
  return reversed;
}

// Huffman code lengths of `weights` (all > 0); the tree's depth may exceed the limit. Ties go to the
// lower index, symbols before internal nodes, so the lengths depend on the weights alone.
std::vector<uint32_t> huffman_depths(std::span<const uint64_t> weights) {
  struct Node {
    uint64_t weight;
    uint32_t index;  // < weights.size(): a symbol; else internal node index + weights.size()
  };
  auto heavier = [](const Node& a, const Node& b) {
    return a.weight != b.weight ? a.weight > b.weight : a.index > b.index;
  };
  const auto n = uint32_t(weights.size());
  std::vector<Node> heap;
  heap.reserve(n);
  for (uint32_t i = 0; i < n; ++i) heap.push_back({weights[i], i});
  std::make_heap(heap.begin(), heap.end(), heavier);
  std::vector<uint32_t> parent(n > 0 ? 2 * n - 1 : 0, UINT32_MAX);  // symbols, then internal nodes
  const auto pop = [&] {
    std::pop_heap(heap.begin(), heap.end(), heavier);
    const Node top = heap.back();
    heap.pop_back();
    return top;
  };
  for (uint32_t internal = n; heap.size() > 1; ++internal) {
    const Node a = pop(), b = pop();
    parent[a.index] = parent[b.index] = internal;
    heap.push_back({a.weight + b.weight, internal});
    std::push_heap(heap.begin(), heap.end(), heavier);
  }
  // Internal nodes are created after their children, so a node's depth is its parent's plus one, found
  // from the root down.
  std::vector<uint32_t> depth(parent.size(), 0);
  for (size_t i = parent.size(); i-- > 0;)
    if (parent[i] != UINT32_MAX) depth[i] = depth[parent[i]] + 1;
  depth.resize(n);
  return depth;
}

}  // namespace

PrefixCode::PrefixCode(std::vector<uint8_t> lengths) : lengths_(std::move(lengths)), count_(kMaxCodeLength + 1, 0) {
  uint32_t present = 0;
  for (uint8_t l : lengths_) {
    if (l > kMaxCodeLength)
      fail("prefix code", "code length " + std::to_string(l) + " above " + std::to_string(kMaxCodeLength));
    if (l) ++count_[l], ++present;
  }
  // Kraft: sum of 2^-l <= 1, in units of 2^-kMaxCodeLength.
  uint64_t kraft = 0;
  for (unsigned l = 1; l <= kMaxCodeLength; ++l) kraft += uint64_t(count_[l]) << (kMaxCodeLength - l);
  if (kraft > (uint64_t(1) << kMaxCodeLength)) fail("prefix code", "lengths oversubscribe the code space");
  single_ = present == 1;
  // Canonical code words: by length, then by symbol, in one pass over the symbols (each length's words
  // and places in sorted_ start where the shorter ones end).
  codes_.assign(lengths_.size(), 0);
  uint32_t next[kMaxCodeLength + 2] = {}, place[kMaxCodeLength + 2] = {};
  uint32_t code = 0;
  for (unsigned l = 1; l <= kMaxCodeLength; ++l) {
    code = (code + count_[l - 1]) << 1;
    next[l] = code;
    place[l + 1] = place[l] + count_[l];
  }
  sorted_.assign(present, 0);
  for (uint32_t s = 0; s < lengths_.size(); ++s)
    if (const unsigned l = lengths_[s]; l != 0) {
      // The stream takes a code word's most significant bit first; BitWriter fills from the lowest bit.
      codes_[s] = uint16_t(reverse_bits(next[l]++, l));
      sorted_[place[l]++] = s;
    }
  count_[0] = 0;
  if (single_ || present == 0 || lengths_.size() > 4096) return;
  fast_.assign(size_t(1) << kFastBits, 0);
  for (uint32_t s : sorted_) {
    const unsigned l = lengths_[s];
    if (l > kFastBits) break;  // sorted_ is by length
    for (uint32_t high = 0; high < (1u << (kFastBits - l)); ++high)
      fast_[codes_[s] | (high << l)] = uint16_t(l << 12 | s);
  }
}

PrefixCode PrefixCode::from_counts(std::span<const uint64_t> counts) {
  std::vector<uint32_t> present;
  std::vector<uint64_t> scaled;
  for (uint32_t s = 0; s < counts.size(); ++s)
    if (counts[s] > 0) present.push_back(s), scaled.push_back(counts[s]);
  std::vector<uint8_t> lengths(counts.size(), 0);
  if (present.size() == 1) lengths[present[0]] = 1;
  if (present.size() <= 1) return PrefixCode(std::move(lengths));
  for (;;) {
    const std::vector<uint32_t> depths = huffman_depths(scaled);
    if (*std::max_element(depths.begin(), depths.end()) <= kMaxCodeLength) {
      for (size_t i = 0; i < present.size(); ++i) lengths[present[i]] = uint8_t(depths[i]);
      return PrefixCode(std::move(lengths));
    }
    for (uint64_t& c : scaled) c = std::max<uint64_t>(1, c >> 1);
  }
}

void PrefixCode::write(BitWriter& w, uint32_t symbol) const {
  if (!has(symbol)) fail("prefix code", "symbol " + std::to_string(symbol) + " has no code word");
  if (single_) return;
  w.bits(codes_[symbol], lengths_[symbol]);
}

uint32_t PrefixCode::read(BitReader& r, const char* field) const {
  if (sorted_.empty()) r.fail_field(field, "the code has no symbols");
  if (single_) return sorted_[0];
  if (!fast_.empty()) {
    const uint16_t entry = fast_[r.peek(kFastBits)];
    if (entry != 0 && unsigned(entry >> 12) <= r.bits_left()) {
      r.skip(entry >> 12, field);
      return entry & 0xFFF;
    }
  }
  uint32_t code = 0, first = 0, index = 0;  // first code word of this length, its index in sorted_
  for (unsigned l = 1; l <= kMaxCodeLength; ++l) {
    code |= r.bit(field);
    const uint32_t count = count_[l];
    if (code - first < count) return sorted_[index + (code - first)];
    index += count;
    first = (first + count) << 1;
    code <<= 1;
  }
  r.fail_field(field, "not a code word of the model's code");
}

size_t PrefixCode::serialized_symbols() const {
  size_t m = lengths_.size();
  while (m > 0 && lengths_[m - 1] == 0) --m;
  return m;
}

void PrefixCode::serialize(BitWriter& w) const {
  const size_t m = serialized_symbols();
  if (m > UINT16_MAX) fail("prefix code", "alphabet too large to serialize");
  w.bits(m, 16);
  for (size_t s = 0; s < m; ++s) w.bits(lengths_[s], 4);
}

PrefixCode PrefixCode::deserialize(BitReader& r, size_t alphabet, const char* field) {
  const auto m = size_t(r.bits(16, field));
  if (m > alphabet) r.fail_field(field, std::to_string(m) + " symbols, the alphabet has " + std::to_string(alphabet));
  if (4 * uint64_t(m) > r.bits_left()) r.fail_field(field, "truncated");
  std::vector<uint8_t> lengths(alphabet, 0);
  for (size_t s = 0; s < m; ++s) lengths[s] = uint8_t(r.bits(4, field));
  try {
    return PrefixCode(std::move(lengths));
  } catch (const Error& e) {
    r.fail_field(field, e.what());
  }
}

namespace {

// Steps -15 .. +15 between nonzero lengths as symbols 0 .. 30; symbols without a code word one at a time,
// or in runs as DEFLATE codes them (RFC 1951 §3.2.7): 3-10 with 3 raw bits, 11-138 with 7.
constexpr uint32_t kNoWordSymbol = 2 * kMaxCodeLength + 1;
constexpr uint32_t kShortRunSymbol = kNoWordSymbol + 1, kLongRunSymbol = kNoWordSymbol + 2;
constexpr uint32_t kLengthSymbols = kLongRunSymbol + 1;
constexpr size_t kShortRun = 3, kLongRun = 11, kLongestRun = 138;

// Calls `step(symbol, raw, raw_bits)` for the lengths of `code` up to its last symbol with one.
template <class Step>
void for_each_length_step(const PrefixCode& code, Step step) {
  int previous = 0;
  const size_t m = code.serialized_symbols();
  for (size_t s = 0; s < m;) {
    const int length = code.lengths()[s];
    if (length != 0) {
      step(uint32_t(length - previous + int(kMaxCodeLength)), 0, 0);
      previous = length;
      ++s;
      continue;
    }
    size_t run = 1;
    while (s + run < m && run < kLongestRun && code.lengths()[s + run] == 0) ++run;
    if (run < kShortRun) step(kNoWordSymbol, 0, 0), run = 1;
    else if (run < kLongRun) step(kShortRunSymbol, run - kShortRun, 3);
    else step(kLongRunSymbol, run - kLongRun, 7);
    s += run;
  }
}

constexpr unsigned kMaxGammaZeros = 16;  // m + 1 <= 65536

}  // namespace

void serialize_code_set(std::span<const PrefixCode* const> codes, BitWriter& w) {
  std::vector<uint64_t> counts(kLengthSymbols, 0);
  for (const PrefixCode* code : codes)
    for_each_length_step(*code, [&](uint32_t step, uint64_t, unsigned) { ++counts[step]; });
  const PrefixCode steps = PrefixCode::from_counts(counts);
  steps.serialize(w);
  for (const PrefixCode* code : codes) {
    const uint64_t n = code->serialized_symbols() + 1;
    const auto zeros = unsigned(std::bit_width(n) - 1);
    if (zeros > kMaxGammaZeros) fail("prefix code", "alphabet too large to serialize");
    w.bits(uint64_t(1) << zeros, zeros + 1);
    w.bits(n, zeros);  // the bits below the leading one
    for_each_length_step(*code, [&](uint32_t step, uint64_t raw, unsigned raw_bits) {
      steps.write(w, step);
      w.bits(raw, raw_bits);
    });
  }
}

std::vector<PrefixCode> deserialize_code_set(BitReader& r, std::span<const size_t> alphabets, const char* field) {
  const PrefixCode steps = PrefixCode::deserialize(r, kLengthSymbols, field);
  std::vector<PrefixCode> codes;
  codes.reserve(alphabets.size());
  for (const size_t alphabet : alphabets) {
    unsigned zeros = 0;
    while (r.bits(1, field) == 0)
      if (++zeros > kMaxGammaZeros) r.fail_field(field, "a symbol count above 65535");
    const uint64_t m = ((uint64_t(1) << zeros) | r.bits(zeros, field)) - 1;
    if (m > alphabet) r.fail_field(field, std::to_string(m) + " symbols, the alphabet has " + std::to_string(alphabet));
    std::vector<uint8_t> lengths(alphabet, 0);
    int previous = 0;
    for (size_t s = 0; s < m; ++s) {
      const uint32_t symbol = steps.read(r, field);
      if (symbol == kNoWordSymbol) continue;
      if (symbol == kShortRunSymbol || symbol == kLongRunSymbol) {
        const uint64_t run = symbol == kShortRunSymbol ? kShortRun + r.bits(3, field) : kLongRun + r.bits(7, field);
        if (run > m - s) r.fail_field(field, "a run past the symbol count");
        s += run - 1;
        continue;
      }
      const int length = previous + int(symbol) - int(kMaxCodeLength);
      if (length < 1 || length > int(kMaxCodeLength)) r.fail_field(field, "a code length outside 1..15");
      lengths[s] = uint8_t(length);
      previous = length;
    }
    try {
      codes.emplace_back(std::move(lengths));
    } catch (const Error& e) {
      r.fail_field(field, e.what());
    }
  }
  return codes;
}

}  // namespace pms
