// Split records coded against the client's own hierarchy (cheng-ooi 2008 §4.3 codes dx, dy, dz
// against v_s with Huffman codes and the cut neighbours after Kim et al. 2006; docs/pms-format.md has the
// record format field by field and the measured bits).
//
// - Cut vertices: a fundamental cut vertex is a leaf next to v_s's leaves, so its id shares a long prefix
//   with an id the client already holds (the id-prefix property behind ActiveAncestor, kim-lee-kobbelt §4):
//   v_s itself (the sibling's subtree and nearby), the cut vertices of v_s's nearest ancestors, and for
//   v̂_r the v̂_l just decoded. A record names the reference (the first the id follows furthest down, so
//   each id has one coding), how far above it the two ids part, and the rest of the path below the
//   parting bit (which is implied: the other child). Ids in no reference's tree escape to tree-id, depth
//   and path.
// - Position: v_t − v_s on the grid, the two differences in v_s's tangent plane larger first, then the
//   third against the plane, each as a magnitude step (prefix coded, the first in a table per class of
//   v_s's radius: the radius bounds |p_t − p_s|) and the step's low bits raw.
// - Refinement info: each child's radius, mu, delta and cone angle as the entry of the lattice below v_s's
//   that the builder rounded it up to (spm/nested_info.h), its own cone axis in coarse steps from v_s's.
//   Values no entry holds travel exact, so any canonical info can be coded.
// - Normal and color of v_t (v_u keeps v_s's): the normal as the wire's octahedral integers, in steps from
//   a cone axis the client holds (v_t's, else v_s's) or v_s's normal, folding over the square's edges
//   (spm/octahedral_normal.h); each color channel as its difference from v_s's, modulo 256.
#include "spm/split_codec.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>
#include <string>

#include "common/bit_cast.h"
#include "common/error.h"
#include "common/huge_pages.h"
#include "common/parallel.h"
#include "spm/nested_info.h"
#include "spm/octahedral_normal.h"
#include "spm/position_grid.h"

namespace pms {
namespace {

// Signed integers as a magnitude class k = bit_width(|v|) with the sign in the symbol: 0, then +k, -k for
// k = 1 .. kMaxClass; the k - 1 bits below the leading one follow raw.
constexpr uint32_t kMaxClass = 40;
constexpr uint32_t kIntSymbols = 1 + 2 * kMaxClass;
// Nested values (spm/nested_info.h): 0, the exact value (kExactLengthBits or kConeAngleBits raw), or lattice
// entry k: k itself below kDirectEntries, else its magnitude class with the bits below the leading one raw.
constexpr uint32_t kZeroSymbol = 0, kExactSymbol = 1, kDirectEntries = 16;
constexpr uint32_t kFirstClassSymbol = 2 + kDirectEntries;
constexpr uint32_t kFirstClass = 5, kLastClass = 10;  // bit_width of kDirectEntries and of the deepest entry
constexpr uint32_t kEntrySymbols = kFirstClassSymbol + kLastClass - kFirstClass + 1;
static_assert(kLatticeOctaves * 64 / kMuCodesPerStep < (1u << kLastClass), "the finest lattice's entries have a class");
constexpr uint32_t kNoConeSymbol = kEntrySymbols;  // after the entries, in the angle codes
// An axis's two steps from its origin like the position's in-plane pair: the larger by quarter octaves
// (the flag for which one folded in), then the smaller in a table by the larger's step.
constexpr uint32_t kAxisLargerSteps = 16;
constexpr unsigned kExactLengthBits = 15 - kLengthDroppedBits;  // a length code up to infinity's

constexpr uint32_t kMaxDepthSymbols = 64;
constexpr uint32_t kEqualSymbol = 0;                     // "the reference itself", in the parting codes; up u is 1 + u
constexpr uint32_t kReferences = 2 + 2 * kCutAncestors;  // v_s, ancestor cuts, v̂_l (for v̂_r)
// Reference symbols: escape, 1 + reference index, or "no cut vertex on this side".
constexpr uint32_t kEscapeSymbol = 0;
constexpr uint32_t kAbsentSymbol = kReferences + 1;
constexpr uint32_t kRefSymbols = kReferences + 2;
constexpr uint32_t kRadiusClasses = 64;  // v_s's radius by half octaves (half-float exponent and top mantissa bit)
constexpr size_t kParallelNodes = size_t(1) << 14;  // whole-model passes (fit, encode, check) below this run inline
constexpr uint32_t kGridBits = 24;                  // finer than this, positions are float bits (position_grid.h)
constexpr uint32_t kSizeClasses = 26;               // magnitude classes of a coordinate difference, clamped
// v_t − v_s in v_s's tangent plane is an edge of about the local edge length in any direction: the larger
// of the two in-plane differences goes first, by quarter octaves (the flag saying which it is folded into
// its symbol), in a table by v_s's radius; the smaller one by quarter octaves in a table by the larger's
// step; the third, predicted on the plane, by half octaves in a table by the class of the offset the
// plane allows (plane_context), or without a plane by the larger's class.
constexpr uint32_t kInPlanePrecision = 2, kOffPlanePrecision = 1;
constexpr uint32_t kLargerSteps = 64;  // quarter-octave steps of the larger difference, clamped
constexpr uint32_t kPositionContexts = kRadiusClasses + kLargerSteps + 2 * kSizeClasses;
constexpr uint32_t kFlagContexts = 10;   // v_s never refines, or the class of its radius over its mu
constexpr uint32_t kChainContexts = 12;  // the previous field's symbol, clamped
constexpr uint32_t kAxisContexts = 13;   // no parent cone, or the class of the angle the child leaves inside it

// Code slots, in serialization order; [..] are the contexts.
constexpr uint32_t kCutHeights = 12;  // v_s's height above the deepest level, clamped
constexpr uint32_t kOwnLevels = 8;    // levels of a reference's path no earlier reference shares, clamped
constexpr uint32_t kUpContexts = 4;   // up, clamped, for the depth step's tables
constexpr uint32_t kLeftReferenceCounts = kReferences - 1;  // v̂_l's list: v_s and the ancestors' cuts
constexpr uint32_t kSlotCutRef = 0;  // [v̂_l: its list's length; v̂_r: after each v̂_l symbol]
constexpr uint32_t kSlotCutRight = kSlotCutRef + kLeftReferenceCounts;
constexpr uint32_t kSlotCutUp =
    kSlotCutRight + kRefSymbols;  // [side][reference is v_s: 0, a leaf: 1][height][own levels]
constexpr uint32_t kSlotCutRest = kSlotCutUp + 4 * kCutHeights * kOwnLevels;      // [side][same][height][up]
constexpr uint32_t kSlotCutDepth = kSlotCutRest + 4 * kCutHeights * kUpContexts;  // escaped ids
constexpr uint32_t kSlotPosition = kSlotCutDepth + 1;  // [radius class]: the larger in-plane difference
constexpr uint32_t kSlotPositionSmaller = kSlotPosition + kRadiusClasses;     // [the larger's step]
constexpr uint32_t kSlotPositionThird = kSlotPositionSmaller + kLargerSteps;  // [larger's class; plane context]
constexpr uint32_t kSlotInfoFlags = kSlotPosition + kPositionContexts;        // [flag context]
constexpr uint32_t kSlotRadius = kSlotInfoFlags + kFlagContexts;  // [t, or u without t: height; u: t's radius symbol]
constexpr uint32_t kSlotMu = kSlotRadius + 2 * kFlagContexts + kChainContexts;  // [child][radius symbol]
constexpr uint32_t kSlotDelta = kSlotMu + 2 * kChainContexts;                   // [child][mu symbol]
constexpr uint32_t kSlotAngle = kSlotDelta + 2 * kChainContexts;                // [child][parent has a cone]
constexpr uint32_t kSlotAxis = kSlotAngle + 4;                            // [child][axis context]: the larger step
constexpr uint32_t kSlotAxisSmaller = kSlotAxis + 2 * kAxisContexts;      // [child][the larger's step]
constexpr uint32_t kCoreSlots = kSlotAxisSmaller + 2 * kAxisLargerSteps;  // serialized for every model
static_assert(kCoreSlots == 934, "docs/protocol.md, \"Split records\", gives the count");
// Attributes of v_t against an origin the client holds; the first value's table by the size of the step
// (the edge's magnitude class, or the cone angle class of the origin), each later one's by the class of the
// one before.
constexpr uint32_t kConeClasses = 11;         // bit_width of a cone angle, 0 .. 1022
constexpr uint32_t kNormalClasses = 18;       // bit_width of an octahedral difference up to 2 kOctahedralMax
constexpr uint32_t kColorClasses = 9;         // bit_width of a channel difference in -128 .. 127
constexpr uint32_t kSlotNormal = kCoreSlots;  // [edge class; v_t's cone angle class; v_s's cone angle class]
constexpr uint32_t kSlotNormalSecond = kSlotNormal + kSizeClasses + 2 * kConeClasses;  // [class of the first]
constexpr uint32_t kSlotColor = kSlotNormalSecond + kNormalClasses;                    // [red: edge class]
constexpr uint32_t kSlotColorNext = kSlotColor + kSizeClasses;  // [channel 1..3][class of the one before]
constexpr uint32_t kSlotCount = kSlotColorNext + 3 * kColorClasses;
static_assert(kSlotCount - kSlotNormal == 66 + 53, "docs/protocol.md, \"Split records\", gives the counts");
constexpr uint8_t kHasNormals = 1, kHasColors = 2, kPlainForm = 4;

// Integers by magnitude steps of `precision` bits: magnitudes below 2^precision each a step, larger ones
// by their bit_width and the `precision` bits below the leading one, the bits below those raw. A symbol is
// 0 for 0, else 2 step − 1 plus 1 when negative. Precision 0 is one class per octave.
constexpr uint32_t int_symbols(uint32_t precision) { return 2 * ((kMaxClass - precision + 1) << precision) - 1; }
static_assert(int_symbols(0) == kIntSymbols);
constexpr uint32_t kFineAxisSymbol = 0;  // first in the axis codes (then 1 + the larger's symbol): both coordinates raw

constexpr uint32_t alphabet(uint32_t slot) {
  if (slot < kSlotCutUp) return kRefSymbols;
  if (slot < kSlotCutRest) return kMaxDepthSymbols + 1;
  if (slot == kSlotCutDepth) return kMaxDepthSymbols;
  if (slot >= kSlotPosition && slot < kSlotPositionSmaller) return 2 * int_symbols(kInPlanePrecision);
  if (slot >= kSlotPositionSmaller && slot < kSlotPositionThird) return int_symbols(kInPlanePrecision);
  if (slot >= kSlotPositionThird && slot < kSlotInfoFlags) return int_symbols(kOffPlanePrecision);
  if (slot >= kSlotInfoFlags && slot < kSlotRadius) return 4;
  if (slot >= kSlotRadius && slot < kSlotAngle) return kEntrySymbols;
  if (slot >= kSlotAngle && slot < kSlotAxis) return kEntrySymbols + 1;
  if (slot >= kSlotAxis && slot < kSlotAxisSmaller) return 2 * int_symbols(kInPlanePrecision) + 1;
  if (slot >= kSlotAxisSmaller && slot < kCoreSlots) return int_symbols(kInPlanePrecision);
  return kIntSymbols;
}

enum Part { topology, geometry, refinement, normal, color };

uint32_t tree_bits(uint32_t root_count) { return root_count <= 1 ? 1 : uint32_t(std::bit_width(root_count - 1)); }

uint64_t magnitude(int64_t v) { return v < 0 ? uint64_t(0) - uint64_t(v) : uint64_t(v); }

// An integer as coded: its symbol, its magnitude step, and the raw bits after the symbol.
struct IntCode {
  uint32_t symbol = 0, step = 0;
  uint64_t raw = 0;
  unsigned raw_bits = 0;
};
[[noreturn, gnu::cold, gnu::noinline]] void fail_too_large(int64_t v) {
  fail("split record", "value " + std::to_string(v) + " too large to code");
}
IntCode int_code(int64_t v, uint32_t precision) {
  const uint64_t m = magnitude(v);
  const auto k = uint32_t(std::bit_width(m));
  if (k > kMaxClass) fail_too_large(v);
  if (k <= precision) return {m == 0 ? 0 : 2 * uint32_t(m) - 1 + (v < 0), uint32_t(m)};
  const unsigned low = k - 1 - precision;
  const uint32_t step = ((k - precision) << precision) | uint32_t((m >> low) & ((1u << precision) - 1));
  return {2 * step - 1 + (v < 0), step, m & ((uint64_t(1) << low) - 1), low};
}

// The depth of the deepest common ancestor of two ids, -1 in different trees.
int common_depth(VertexId a, VertexId b) {
  if (a.tree != b.tree) return -1;
  const int da = a.depth(), db = b.depth(), shallower = std::min(da, db);
  // Both ids cut to the shallower depth agree above their highest differing bit.
  const uint64_t x = a.node >> (da - shallower), y = b.node >> (db - shallower);
  return shallower - int(std::bit_width(x ^ y));
}

}  // namespace

// Where each slot's symbols start in one array over every slot's alphabet (symbol counts, code words).
constexpr std::array<uint32_t, kSlotCount + 1> kFirstSymbol = [] {
  std::array<uint32_t, kSlotCount + 1> first{};
  for (uint32_t s = 0; s < kSlotCount; ++s) first[s + 1] = first[s] + alphabet(s);
  return first;
}();
constexpr uint32_t kAllSymbols = kFirstSymbol[kSlotCount];

// Slot ranges holding about as many symbols each, one per core: the tables are fitted and turned into
// code words a range at a time (the position slots hold most symbols, so equal slot counts would not do).
const std::vector<size_t>& slot_bounds() {
  static const std::vector<size_t> bounds = [] {
    const size_t ranges = range_count(kAllSymbols, 1);
    std::vector<size_t> b{0};
    for (size_t k = 1, s = 0; k < ranges; ++k) {
      while (s < kSlotCount && kFirstSymbol[s] * ranges < kAllSymbols * k) ++s;
      b.push_back(s);
    }
    b.push_back(kSlotCount);
    return b;
  }();
  return bounds;
}

// Symbol counts, for fitting the tables; sized by the fit that fills them (results start empty).
struct SplitCodec::Counts {
  std::vector<uint64_t> counts;
  void symbol(uint32_t slot, uint32_t sym, Part) { ++counts[kFirstSymbol[slot] + sym]; }
  void raw(uint64_t, unsigned, Part) {}
  void add(const Counts& other) {
    for (size_t i = 0; i < counts.size(); ++i) counts[i] += other.counts[i];
  }
  std::span<const uint64_t> of(uint32_t slot) const {
    return std::span(counts).subspan(kFirstSymbol[slot], alphabet(slot));
  }
};

// A range of nodes' symbols and raw bits, in order, as the fit met them: writing the records then needs
// only the tables. A word per symbol, its index in kFirstSymbol's array; raw bits as a word with kRawFlag
// and their count, holding up to kInlineRawBits of them, else followed by the 64-bit value in two words;
// each node's record ends with kEndOfRecord (a leaf's is only that). The words go in chunks, each as large
// as the log before it up to one 2 MiB page: a log grows without copies, and what it reserves beyond what
// it holds is never more than what it holds, nor than a page.
struct SplitCodec::SymbolLog {
  static constexpr unsigned kCountShift = 24, kInlineRawBits = kCountShift;
  static constexpr uint32_t kRawFlag = 1u << 31, kEndOfRecord = kRawFlag - 1;
  static constexpr size_t kFirstChunkWords = size_t(1) << 14, kLargestChunkWords = kHugePage / sizeof(uint32_t);
  static_assert(kAllSymbols < kEndOfRecord);
  static_assert(64 < 1u << (31 - kCountShift));  // a raw count up to 64 fits
  struct Chunk {
    std::unique_ptr<uint32_t[]> words;  // uninitialised: every word is written before it is read
    size_t size = 0;                    // words written; the last chunk's is next_'s offset
  };
  std::vector<Chunk> chunks;
  size_t records = 0;  // nodes logged

  // The fit logs a few words per node: one test and one store each, the chunk's end the only branch.
  void symbol(uint32_t index) { put(index); }
  void raw(uint64_t value, unsigned n) {
    if (n < 64) value &= (uint64_t(1) << n) - 1;
    if (n <= kInlineRawBits) return put(kRawFlag | n << kCountShift | uint32_t(value));
    if (end_ - next_ < 3) grow(3);  // a raw's words stay in one chunk
    next_[0] = kRawFlag | n << kCountShift, next_[1] = uint32_t(value), next_[2] = uint32_t(value >> 32);
    next_ += 3;
  }
  void end_record() {
    put(kEndOfRecord);
    ++records;
  }

  // The records into `w`, each one's start into `offsets`; `code_words` as SplitCodec::code_words().
  // Fields of up to 32 bits (code words, inline raws) gather in a 64-bit word that goes out 32 bits at a
  // time: one BitWriter call per 32 bits rather than per field.
  void write(std::span<const uint32_t> code_words, BitWriter& w, std::vector<uint64_t>& offsets) const {
    static_assert(kInlineRawBits <= 32);
    offsets.reserve(offsets.size() + records);
    uint64_t pending = 0;
    unsigned pending_bits = 0;                          // below 32 between fields
    const auto put = [&](uint64_t value, unsigned n) {  // n <= 32, value below 2^n
      pending |= value << pending_bits;
      pending_bits += n;
      if (pending_bits >= 32) {
        w.bits(pending, 32);
        pending >>= 32;
        pending_bits -= 32;
      }
    };
    bool record_start = true;
    for (const Chunk& chunk : chunks) {
      const uint32_t* words = chunk.words.get();
      const size_t size = &chunk == &chunks.back() ? size_t(next_ - words) : chunk.size;
      for (size_t i = 0; i < size;) {
        if (record_start) offsets.push_back(w.size() + pending_bits);
        const uint32_t word = words[i++];
        record_start = word == kEndOfRecord;
        if (record_start) continue;
        if (!(word & kRawFlag)) {
          const uint32_t code = code_words[word];
          put(code & 0xffff, code >> 16);
          continue;
        }
        const unsigned n = (word & ~kRawFlag) >> kCountShift;
        if (n <= kInlineRawBits) {
          put(word & ((uint32_t(1) << n) - 1), n);
        } else {
          w.bits(pending, pending_bits);  // a long raw goes straight out, after what is pending
          pending = 0, pending_bits = 0;
          w.bits(words[i] | uint64_t(words[i + 1]) << 32, n);
          i += 2;
        }
      }
    }
    w.bits(pending, pending_bits);
  }

 private:
  void put(uint32_t word) {
    if (next_ == end_) grow(1);
    *next_++ = word;
  }
  // A new chunk as large as the log so far, within [kFirstChunkWords, kLargestChunkWords]: a log grows
  // without copies, and what it holds unused is never more than what it holds, nor than a page.
  void grow(size_t words) {
    if (!chunks.empty()) {
      chunks.back().size = size_t(next_ - chunks.back().words.get());
      logged_ += chunks.back().size;
    }
    const size_t size = std::max(words, std::clamp(logged_, kFirstChunkWords, kLargestChunkWords));
    chunks.push_back({std::unique_ptr<uint32_t[]>(new uint32_t[size]), 0});
    next_ = chunks.back().words.get();
    end_ = next_ + size;
  }
  // Into the last chunk's words (moving the log moves the chunks, not their words).
  uint32_t* next_ = nullptr;
  uint32_t* end_ = nullptr;
  size_t logged_ = 0;  // words in the chunks before the last
};

// The fit's output: symbol counts, and with a log every symbol and raw bits in order.
struct SplitCodec::Fitting {
  Counts& counts;
  SymbolLog* log;
  void symbol(uint32_t slot, uint32_t sym, Part) {
    const uint32_t index = kFirstSymbol[slot] + sym;
    ++counts.counts[index];
    if (log) log->symbol(index);
  }
  void raw(uint64_t value, unsigned n, Part) {
    if (log) log->raw(value, n);
  }
};

namespace {

struct Writing {
  const std::vector<PrefixCode>& codes;
  BitWriter& w;
  RecordBits bits;
  void symbol(uint32_t slot, uint32_t sym, Part part) {
    const uint64_t before = w.size();
    codes[slot].write(w, sym);
    add(part, w.size() - before);
  }
  void raw(uint64_t value, unsigned n, Part part) {
    w.bits(value, n);
    add(part, n);
  }
  void add(Part part, uint64_t n) {
    uint64_t* parts[] = {&bits.topology, &bits.geometry, &bits.refinement, &bits.normal, &bits.color};
    *parts[part] += n;
  }
};

template <class Out>
void put_raw(Out& out, const IntCode& code, Part part) {
  if (code.raw_bits > 0) out.raw(code.raw, code.raw_bits, part);
}
// Returns the symbol (whose step, (symbol + 1) / 2, is the class at precision 0).
template <class Out>
uint32_t put_int(Out& out, uint32_t slot, int64_t v, Part part, uint32_t precision = 0) {
  const IntCode code = int_code(v, precision);
  out.symbol(slot, code.symbol, part);
  put_raw(out, code, part);
  return code.symbol;
}

int64_t get_int(uint32_t sym, BitReader& r, const char* field, uint32_t precision = 0) {
  if (sym == 0) return 0;
  if (sym >= int_symbols(precision)) r.fail_field(field, "not an integer symbol");
  const uint32_t step = (sym + 1) / 2;
  uint64_t m = step;
  if (step >= (1u << precision)) {
    const uint32_t k = (step >> precision) + precision;
    const unsigned low = k - 1 - precision;
    m = (uint64_t(1) << (k - 1)) | (uint64_t(step & ((1u << precision) - 1)) << low) | r.bits(low, field);
  }
  return sym % 2 == 0 ? -int64_t(m) : int64_t(m);
}

// Two differences that make one short vector in any direction (the position's in-plane pair, a cone axis's
// steps): the larger first by quarter octaves, its symbol times 2 plus 1 when it is b (a on ties) after
// `offset` symbols of the first table; then the smaller by quarter octaves in the table `smaller_base` +
// the larger's step, clamped below `smaller_tables`.
struct PairTables {
  uint32_t first, offset, smaller_base, smaller_tables;
};
template <class Out>
void put_pair(Out& out, const PairTables& t, int64_t a, int64_t b, Part part) {
  const bool swapped = magnitude(b) > magnitude(a);
  const IntCode larger = int_code(swapped ? b : a, kInPlanePrecision);
  out.symbol(t.first, t.offset + 2 * larger.symbol + (swapped ? 1 : 0), part);
  put_raw(out, larger, part);
  put_int(out, t.smaller_base + std::min(larger.step, t.smaller_tables - 1), swapped ? a : b, part, kInPlanePrecision);
}
// The pair after its first symbol, less the offset, was read.
void get_pair(const std::vector<PrefixCode>& codes, const PairTables& t, uint32_t first, BitReader& r,
              const char* field, int64_t pair[2]) {
  const bool swapped = first & 1;
  const int64_t larger = get_int(first >> 1, r, field, kInPlanePrecision);
  const uint32_t larger_step = ((first >> 1) + 1) / 2;
  const int64_t smaller = get_int(codes[t.smaller_base + std::min(larger_step, t.smaller_tables - 1)].read(r, field), r,
                                  field, kInPlanePrecision);
  if (magnitude(smaller) > magnitude(larger) || (swapped && magnitude(smaller) == magnitude(larger)))
    r.fail_field(field, "a pair of differences not larger first");
  pair[0] = swapped ? smaller : larger;
  pair[1] = swapped ? larger : smaller;
}

// The ids a cut vertex of `side` is coded against, each once, in symbol order: v_s, the ancestors' cut
// vertices, and for v̂_r the v̂_l just decoded. A cut vertex parts from the first of them whose path it
// follows furthest down, so a reference only ever serves for its `own` lowest levels: the part of its path
// that no earlier reference shares. That makes the coding canonical, and how many levels a reference
// owns is the context of how far above it the target parts.
struct References {
  uint32_t count = 0;
  VertexId id[kReferences];

  void add(VertexId v) {
    if (!is_vertex(v)) return;
    for (uint32_t i = 0; i < count; ++i)
      if (id[i] == v) return;
    id[count++] = v;
  }
  // The levels of reference i's path that no earlier reference shares. Asked of the one reference a cut
  // vertex is coded against, so computed then rather than for every reference listed.
  uint32_t own(uint32_t i) const {
    int shared = -1;
    for (uint32_t j = 0; j < i; ++j) shared = std::max(shared, common_depth(id[j], id[i]));
    return uint32_t(std::max(0, id[i].depth() - 1 - shared));
  }
};
// v̂_l's references; v̂_r's add v̂_l.
References references(const SplitContext& c) {
  References refs;
  refs.add(c.vs);
  for (VertexId cut : c.ancestor_cuts) refs.add(cut);
  return refs;
}

// How a cut vertex is coded: against the reference it follows furthest down (the first on ties), with
// the depth of their deepest common ancestor; or escaped (`ref` = refs.count) when no reference is in its
// tree or one of the two ids lies above the other (no parting bit).
struct CutCoding {
  uint32_t ref = 0;
  int common = -1;
  bool equal = false;
};
CutCoding cut_coding(const References& refs, VertexId cut) {
  CutCoding coding{refs.count};
  for (uint32_t i = 0; i < refs.count; ++i)
    if (const int common = common_depth(refs.id[i], cut); common > coding.common) coding = {i, common};
  if (coding.ref == refs.count) return coding;
  const VertexId ref = refs.id[coding.ref];
  coding.equal = ref == cut;
  if (!coding.equal && (coding.common == ref.depth() || coding.common == cut.depth())) coding.ref = refs.count;
  return coding;
}

// A half float's exponent and top mantissa bit.
uint32_t half_octave(uint16_t half) { return (half >> 9) & (kRadiusClasses - 1); }
uint32_t position_class(const SplitContext& c) { return half_octave(c.info_s.radius); }

// v_t - v_s is an edge of the surface under v_s, so it lies near the plane normal to v_s's cone axis:
// the axis where that normal is largest is predicted from the other two, the others coded first. The
// normal is the octahedral axis decoded in integers (L1 norm kAxisSteps), scaled by each axis's grid step.
struct PositionFrame {
  uint32_t order[3] = {0, 1, 2};
  bool plane = false;
  int64_t normal[3] = {0, 0, 0};
  int64_t angle = 0;
};
PositionFrame position_frame(const RefineInfo& s, const std::array<uint16_t, 3>& steps, uint32_t position_bits) {
  PositionFrame f;
  if (s.cone_angle == kNoCone || position_bits > kGridBits) return f;
  int64_t x = int16_t(s.cone_x), y = int16_t(s.cone_y);
  const int64_t z = kAxisSteps - std::abs(x) - std::abs(y);
  if (z < 0) {  // the lower hemisphere, folded over the diagonals
    const int64_t fx = (x >= 0 ? 1 : -1) * (kAxisSteps - std::abs(y)),
                  fy = (y >= 0 ? 1 : -1) * (kAxisSteps - std::abs(x));
    x = fx, y = fy;
  }
  const int64_t n[3] = {x * steps[0], y * steps[1], z * steps[2]};
  uint32_t major = 0;
  for (uint32_t a = 1; a < 3; ++a)
    if (std::abs(n[a]) > std::abs(n[major])) major = a;
  if (n[major] == 0) return f;
  f.plane = true;
  f.order[0] = major == 0 ? 1 : 0;
  f.order[1] = major == 2 ? 1 : 2;
  f.order[2] = major;
  std::copy_n(n, 3, f.normal);
  f.angle = s.cone_angle;
  return f;
}
// The major axis's difference on the plane through v_s, rounded to the grid.
int64_t plane_prediction(const PositionFrame& f, const int64_t d[3]) {
  const int64_t num = -(f.normal[f.order[0]] * d[f.order[0]] + f.normal[f.order[1]] * d[f.order[1]]);
  const int64_t den = f.normal[f.order[2]];
  const int64_t q = (2 * std::abs(num) + std::abs(den)) / (2 * std::abs(den));  // |num / den| rounded
  return (num < 0) != (den < 0) ? -q : q;
}
// How far off the plane v_t may lie grows with the in-plane offset and the cone's width.
uint32_t plane_context(const PositionFrame& f, const int64_t d[3]) {
  const uint64_t offset = uint64_t(std::max(std::abs(d[f.order[0]]), std::abs(d[f.order[1]])));
  return std::min<uint32_t>(uint32_t(std::bit_width((offset * uint64_t(f.angle + 1)) >> 8)), kSizeClasses - 1);
}
PairTables in_plane_tables(const SplitContext& c) {
  return {kSlotPosition + position_class(c), 0, kSlotPositionSmaller, kLargerSteps};
}
// A child's axis steps; symbol 0 of the first table is kFineAxisSymbol.
PairTables axis_tables(uint32_t first, uint32_t child) {
  return {first, 1, kSlotAxisSmaller + child * kAxisLargerSteps, kAxisLargerSteps};
}

// The table of the third difference: on the plane, by the offset the plane allows; else by the larger
// in-plane difference's class.
uint32_t third_position_slot(const PositionFrame& f, const int64_t d[3]) {
  if (f.plane) return kSlotPositionThird + kSizeClasses + plane_context(f, d);
  const uint64_t larger = std::max(magnitude(d[f.order[0]]), magnitude(d[f.order[1]]));
  return kSlotPositionThird + std::min<uint32_t>(uint32_t(std::bit_width(larger)), kSizeClasses - 1);
}

// Whether v_s's children never refine, and how far below v_s their bounds are, depend on how far v_s is
// from the deepest level.
uint32_t height_context(const SplitContext& c, uint32_t max_depth) {
  return std::min<uint32_t>(uint32_t(std::max(0, int(max_depth) - c.vs.depth())), kFlagContexts - 1);
}
// How far a cut vertex parts from its reference, and how deep it goes, depends on how far v_s is from the
// deepest level (the cut vertices are leaves).
uint32_t cut_height(const SplitContext& c, uint32_t max_depth) {
  return std::min<uint32_t>(uint32_t(std::max(0, int(max_depth) - c.vs.depth())), kCutHeights - 1);
}
uint32_t up_slot(const SplitContext& c, uint32_t max_depth, int side, uint32_t ref, uint32_t own) {
  const uint32_t kind = 2 * uint32_t(side) + (ref > 0 ? 1 : 0);  // reference 0 is v_s, the others leaves
  return kSlotCutUp + (kind * kCutHeights + cut_height(c, max_depth)) * kOwnLevels + std::min(own, kOwnLevels - 1);
}
// v̂_l's reference in a table by how many references there are to choose from (1 .. 11).
uint32_t left_reference_slot(const References& refs) { return kSlotCutRef + std::max<uint32_t>(refs.count, 1) - 1; }
uint32_t depth_step_slot(const SplitContext& c, uint32_t max_depth, int side, uint32_t ref, uint32_t up) {
  const uint32_t kind = 2 * uint32_t(side) + (ref > 0 ? 1 : 0);
  return kSlotCutRest + (kind * kCutHeights + cut_height(c, max_depth)) * kUpContexts + std::min(up, kUpContexts - 1);
}
uint32_t chain_context(uint32_t previous_symbol) { return std::min(previous_symbol, kChainContexts - 1); }
// v_s's sphere is v_t's moved or v_u's, so how close v_t's radius came to its bound says about v_u's.
constexpr uint32_t kNoRadiusSymbol = UINT32_MAX;
uint32_t radius_slot(const SplitContext& c, uint32_t max_depth, uint32_t child, uint32_t t_radius_symbol) {
  if (child == 0 || t_radius_symbol == kNoRadiusSymbol)
    return kSlotRadius + child * kFlagContexts + height_context(c, max_depth);
  return kSlotRadius + 2 * kFlagContexts + chain_context(t_radius_symbol);
}
// A child's cone lies inside its parent's, so its axis moves at most about the angle left between them.
uint32_t axis_context(const RefineInfo& s, const RefineInfo& v) {
  if (s.cone_angle == kNoCone) return 0;
  const int64_t room = std::max<int64_t>(0, int64_t(s.cone_angle) - v.cone_angle);
  return 1 + std::min<uint32_t>(uint32_t(std::bit_width(uint64_t(room))), kAxisContexts - 2);
}

constexpr uint16_t RefineInfo::*kLengths[3] = {&RefineInfo::radius, &RefineInfo::mu, &RefineInfo::delta};
constexpr uint32_t kCodesPerStep[3] = {kRadiusCodesPerStep, kMuCodesPerStep, kDeltaCodesPerStep};

// A nested value as coded (kZeroSymbol above): its symbol and the raw bits after it.
struct EntryCode {
  uint32_t symbol = kZeroSymbol;
  uint64_t raw = 0;
  unsigned raw_bits = 0;
};
EntryCode entry_code(uint32_t k, uint32_t exact, unsigned exact_bits) {
  if (k == kNoEntry) return {kExactSymbol, exact, exact_bits};
  if (k < kDirectEntries) return {2 + k};
  const auto width = unsigned(std::bit_width(k));
  return {kFirstClassSymbol + width - kFirstClass, k & ((1u << (width - 1)) - 1), width - 1};
}
// The child's length against v_s's: the lattice entry it is, or exact.
EntryCode length_code_of(uint16_t parent, uint16_t child, uint32_t codes_per_step) {
  if (child == 0) return {};
  uint32_t k = length_entry(parent, child, codes_per_step);
  if (k != kNoEntry && length_at_entry(parent, k, codes_per_step) != child) k = kNoEntry;
  return entry_code(k, child >> kLengthDroppedBits, kExactLengthBits);
}
// The child's cone angle (not kNoCone) against v_s's (which may be).
EntryCode angle_code_of(uint16_t parent, uint16_t child) {
  if (child == 0) return {};
  uint32_t k = parent == kNoCone ? kNoEntry : angle_entry(parent, child);
  if (k != kNoEntry && angle_at_entry(parent, k) != child) k = kNoEntry;
  return entry_code(k, child, kConeAngleBits);
}
template <class Out>
void put_entry(Out& out, uint32_t slot, const EntryCode& e) {
  out.symbol(slot, e.symbol, refinement);
  if (e.raw_bits > 0) out.raw(e.raw, e.raw_bits, refinement);
}
// The entry number after a symbol that is neither zero nor exact.
uint32_t read_entry(uint32_t sym, BitReader& r, const char* field) {
  if (sym < kFirstClassSymbol) return sym - 2;
  if (sym >= kEntrySymbols) r.fail_field(field, "not a lattice entry");
  const uint32_t width = sym - kFirstClassSymbol + kFirstClass;
  return (1u << (width - 1)) | uint32_t(r.bits(width - 1, field));
}
uint16_t read_length(uint32_t sym, BitReader& r, uint16_t parent, uint32_t codes_per_step, const char* field) {
  if (sym == kZeroSymbol) return 0;
  const uint32_t value = sym == kExactSymbol ? uint32_t(r.bits(kExactLengthBits, field)) << kLengthDroppedBits
                                             : length_at_entry(parent, read_entry(sym, r, field), codes_per_step);
  if (value > 0x7C00) r.fail_field(field, "length outside the lattice or the half-float range");
  return uint16_t(value);
}
uint16_t read_angle(uint32_t sym, BitReader& r, uint16_t parent, const char* field) {
  if (sym == kZeroSymbol) return 0;
  if (sym != kExactSymbol && parent == kNoCone) r.fail_field(field, "a lattice entry below no cone");
  const uint32_t value =
      sym == kExactSymbol ? uint32_t(r.bits(kConeAngleBits, field)) : angle_at_entry(parent, read_entry(sym, r, field));
  if (value > kConeSteps) r.fail_field(field, "cone angle out of range");
  return uint16_t(value);
}
// Own axes lie on the coarse grid (kAxisSnapBits) and are coded in its steps from v_s's, rounded down.
constexpr int64_t kAxisSnap = int64_t(1) << kAxisSnapBits;
int64_t coarse_axis(uint16_t q) {
  return int64_t(int16_t(q)) >= 0 ? int16_t(q) / kAxisSnap : -((kAxisSnap - 1 - int16_t(q)) / kAxisSnap);
}
// Where a child's axis coordinate is coded from, in coarse steps. v_t's: v_s's. v_u's: beyond v_s's from
// v_t's, since the merged cone's axis lies between the children's, α_s − α_t from v_t's and α_s − α_u
// from v_u's (refinement_info.cpp, merge_cones): v_s's coordinate plus (α_s − α_u) / (α_s − α_t) of v_t's
// offset from it, in integers (the octahedral map is nearly linear over a cone's width).
int64_t axis_origin(const RefineInfo& s, const RefineInfo* t, const RefineInfo& v, uint16_t RefineInfo::*q) {
  const int64_t from = int16_t(s.*q);
  if (!t || s.cone_angle == kNoCone || t->cone_angle == kNoCone || never_refines(*t))
    return coarse_axis(uint16_t(from));
  const int64_t num = int64_t(s.cone_angle) - v.cone_angle, den = int64_t(s.cone_angle) - t->cone_angle;
  if (den <= 0 || num < 0) return coarse_axis(uint16_t(from));
  const int64_t predicted = std::clamp<int64_t>(from + (from - int16_t(t->*q)) * num / den, -kAxisSteps, kAxisSteps);
  return coarse_axis(uint16_t(int16_t(predicted)));
}
bool on_coarse_grid(const RefineInfo& v) {
  return int16_t(v.cone_x) % kAxisSnap == 0 && int16_t(v.cone_y) % kAxisSnap == 0;
}

// v_t's attributes move from v_s's by more the longer the edge between them (v_t - v_s on the grid).
uint32_t edge_class(const int64_t d[3]) {
  const uint64_t largest = uint64_t(std::max({std::abs(d[0]), std::abs(d[1]), std::abs(d[2])}));
  return std::min<uint32_t>(uint32_t(std::bit_width(largest)), kSizeClasses - 1);
}
uint32_t size_class(uint32_t int_sym, uint32_t classes) { return std::min((int_sym + 1) / 2, classes - 1); }

// Where v_t's normal is coded from, and the table's context. A cone axis where there is one, as its angle
// bounds how far off the normal lies: the cone holds the normals of the faces below the node, which a
// vertex normal averages. v_t's own when it refines, else v_s's (v_t's faces are among v_s's), else v_s's
// normal (a neighbour's, off by more the longer the edge). The axis is on the same octahedral square in
// kAxisSteps, scaled (rounded half away from 0).
uint16_t axis_on_normal_square(uint16_t axis) {
  const int64_t a = int16_t(axis);
  return uint16_t(int16_t((2 * a * kOctahedralMax + (a >= 0 ? kAxisSteps : -kAxisSteps)) / (2 * kAxisSteps)));
}
bool has_cone(const RefineInfo& info) { return !never_refines(info) && info.cone_angle != kNoCone; }
uint32_t normal_origin(const SplitContext& c, const SplitPayload& p, uint32_t edge, uint16_t origin[2]) {
  const bool own = has_cone(p.info_t);
  const RefineInfo& cone = own ? p.info_t : c.info_s;
  if (!own && !has_cone(cone)) {
    std::copy_n(c.normal_s, 2, origin);
    return edge;
  }
  origin[0] = axis_on_normal_square(cone.cone_x);
  origin[1] = axis_on_normal_square(cone.cone_y);
  const uint32_t angle = std::min<uint32_t>(uint32_t(std::bit_width(uint32_t(cone.cone_angle))), kConeClasses - 1);
  return kSizeClasses + (own ? 0 : kConeClasses) + angle;
}
// A channel's difference modulo 256, centred.
int64_t color_step(uint8_t s, uint8_t t) { return int8_t(uint8_t(t - s)); }

}  // namespace

template <class Out>
void SplitCodec::emit_cuts(const SplitContext& c, const SplitPayload& p, Out& out) const {
  if (!is_vertex(p.cut_l) && !is_vertex(p.cut_r))
    fail("split record", "split of " + to_string(c.vs) + " has no cut vertex");
  References refs = references(c);
  uint32_t ref_slot = left_reference_slot(refs);
  for (int side = 0; side < 2; ++side) {
    const VertexId cut = side == 0 ? p.cut_l : p.cut_r;
    if (side == 1) refs.add(p.cut_l);
    if (!is_vertex(cut)) {
      out.symbol(ref_slot, kAbsentSymbol, topology);
      ref_slot = kSlotCutRight + kAbsentSymbol;
      continue;
    }
    if (cut.tree >= root_count_ || uint32_t(cut.depth()) > max_depth_ || is_ancestor_or_self(c.vs, cut))
      fail("split record", "split of " + to_string(c.vs) + ": cut vertex " + to_string(cut) + " cannot be coded");
    const CutCoding coding = cut_coding(refs, cut);
    const uint32_t best = coding.ref;
    const bool escape = best == refs.count, equal = coding.equal;
    const uint32_t ref_symbol = escape ? kEscapeSymbol : 1 + best;
    out.symbol(ref_slot, ref_symbol, topology);
    ref_slot = kSlotCutRight + ref_symbol;
    if (escape) {
      out.raw(cut.tree, tree_bits(root_count_), topology);
      out.symbol(kSlotCutDepth, uint32_t(cut.depth()), topology);
      out.raw(cut.node, unsigned(cut.depth()), topology);
      continue;
    }
    const VertexId ref = refs.id[best];
    const uint32_t up = equal ? 0 : uint32_t(ref.depth() - 1 - coding.common);
    out.symbol(up_slot(c, max_depth_, side, best, refs.own(best)), equal ? kEqualSymbol : 1 + up, topology);
    if (equal) continue;
    put_int(out, depth_step_slot(c, max_depth_, side, best, up), int64_t(cut.depth()) - ref.depth(), topology);
    out.raw(cut.node, unsigned(cut.depth() - coding.common - 1), topology);
  }
}

template <class Out>
void SplitCodec::emit(const SplitContext& context, const SplitPayload& p, Out& out) const {
  const SplitContext c = coding_context(context);
  emit_cuts(c, p, out);
  // Position of v_t against v_s's.
  const PositionFrame frame = position_frame(c.info_s, steps_, position_bits_);
  int64_t d[3] = {0, 0, 0};
  for (uint32_t axis = 0; axis < 3; ++axis) {
    if (position_bits_ < 32 && p.position_t[axis] >> position_bits_)
      fail("split record", "split of " + to_string(c.vs) + ": position outside the grid");
    d[axis] = int64_t(p.position_t[axis]) - int64_t(c.position_s[axis]);
  }
  put_pair(out, in_plane_tables(c), d[frame.order[0]], d[frame.order[1]], geometry);
  const int64_t predicted = frame.plane ? plane_prediction(frame, d) : 0;
  put_int(out, third_position_slot(frame, d), d[frame.order[2]] - predicted, geometry, kOffPlanePrecision);
  emit_children(c, p, out);
  emit_attributes(c, p, edge_class(d), out);
}

// Refinement info of v_t and v_u against v_s's; in the plain form only whether each has a split.
template <class Out>
void SplitCodec::emit_children(const SplitContext& c, const SplitPayload& p, Out& out) const {
  const RefineInfo* child[2] = {&p.info_t, &p.info_u};
  for (const RefineInfo* info : child)
    if (!is_canonical(*info) || !(*info == as_sent(*info)))
      fail("split record", "split of " + to_string(c.vs) + ": refinement info is not as sent");
  if (form_ == RecordForm::plain && !(p == plain_payload(p, !never_refines(p.info_t), !never_refines(p.info_u))))
    fail("split record", "split of " + to_string(c.vs) + ": refinement info in the plain form");
  const RefineInfo& s = c.info_s;
  // The plain form's flags are the hierarchy's shape, not refinement info: counted as topology.
  out.symbol(kSlotInfoFlags + height_context(c, max_depth_),
             (never_refines(p.info_t) ? 1u : 0u) | (never_refines(p.info_u) ? 2u : 0u),
             form_ == RecordForm::plain ? topology : refinement);
  if (form_ == RecordForm::plain) return;
  uint32_t t_radius = kNoRadiusSymbol;
  for (uint32_t k = 0; k < 2; ++k) {
    const RefineInfo& v = *child[k];
    if (never_refines(v)) continue;
    uint32_t slot = radius_slot(c, max_depth_, k, t_radius);
    for (uint32_t f = 0; f < 3; ++f) {
      const EntryCode e = length_code_of(s.*kLengths[f], v.*kLengths[f], kCodesPerStep[f]);
      put_entry(out, slot, e);
      if (f == 0 && k == 0) t_radius = e.symbol;
      slot = (f == 0 ? kSlotMu : kSlotDelta) + k * kChainContexts + chain_context(e.symbol);
    }
    const uint32_t angle_slot = kSlotAngle + 2 * k + (s.cone_angle != kNoCone ? 1 : 0);
    if (v.cone_angle == kNoCone) {
      out.symbol(angle_slot, kNoConeSymbol, refinement);
      continue;
    }
    put_entry(out, angle_slot, angle_code_of(s.cone_angle, v.cone_angle));
    const uint32_t axis_slot = kSlotAxis + k * kAxisContexts + axis_context(s, v);
    if (!on_coarse_grid(v)) {  // not an axis the builder snapped: both coordinates as stored
      out.symbol(axis_slot, kFineAxisSymbol, refinement);
      for (uint16_t q : {v.cone_x, v.cone_y})
        out.raw(uint64_t(int64_t(int16_t(q)) + kAxisSteps), kAxisBits, refinement);
      continue;
    }
    const RefineInfo* t = k == 1 ? child[0] : nullptr;
    const int64_t dx = coarse_axis(v.cone_x) - axis_origin(s, t, v, &RefineInfo::cone_x);
    const int64_t dy = coarse_axis(v.cone_y) - axis_origin(s, t, v, &RefineInfo::cone_y);
    put_pair(out, axis_tables(axis_slot, k), dx, dy, refinement);
  }
}

template <class Out>
void SplitCodec::emit_attributes(const SplitContext& c, const SplitPayload& p, uint32_t edge, Out& out) const {
  const auto refuse = [&](const char* what) { fail("split record", "split of " + to_string(c.vs) + ": " + what); };
  if (has_normals_) {
    if (!is_canonical_normal(c.normal_s) || !is_canonical_normal(p.normal_t))
      refuse("a normal encode_normal does not produce");
    int64_t d[2];
    uint16_t origin[2];
    const uint32_t normal_class = normal_origin(c, p, edge, origin);
    octahedral_step(origin, p.normal_t, d);
    const uint32_t sym = put_int(out, kSlotNormal + normal_class, d[0], normal);
    put_int(out, kSlotNormalSecond + size_class(sym, kNormalClasses), d[1], normal);
  } else if (p.normal_t[0] || p.normal_t[1]) {
    refuse("a normal in a model without normals");
  }
  if (has_colors_) {
    uint32_t slot = kSlotColor + edge;
    for (uint32_t channel = 0; channel < 4; ++channel) {
      const uint32_t sym = put_int(out, slot, color_step(c.color_s[channel], p.color_t[channel]), color);
      slot = kSlotColorNext + channel * kColorClasses + size_class(sym, kColorClasses);
    }
  } else if (p.color_t[0] || p.color_t[1] || p.color_t[2] || p.color_t[3]) {
    refuse("a color in a model without colors");
  }
}

void SplitCodec::decode_attributes(const SplitContext& c, uint32_t edge, BitReader& r, SplitPayload& p) const {
  if (has_normals_) {
    uint16_t origin[2];
    const uint32_t normal_class = normal_origin(c, p, edge, origin);
    const uint32_t first = codes_[kSlotNormal + normal_class].read(r, "normal");
    const int64_t d[2] = {
        get_int(first, r, "normal"),
        get_int(codes_[kSlotNormalSecond + size_class(first, kNormalClasses)].read(r, "normal"), r, "normal")};
    if (!octahedral_unstep(origin, d, p.normal_t)) r.fail_field("normal", "off the octahedral square");
    if (!is_canonical_normal(p.normal_t)) r.fail_field("normal", "the mirror image of the canonical point on an edge");
  }
  if (has_colors_) {
    uint32_t slot = kSlotColor + edge;
    for (uint32_t channel = 0; channel < 4; ++channel) {
      const uint32_t sym = codes_[slot].read(r, "color");
      const int64_t step = get_int(sym, r, "color");
      if (step < -128 || step > 127) r.fail_field("color", "a step outside -128 .. 127");
      p.color_t[channel] = uint8_t(c.color_s[channel] + step);
      slot = kSlotColorNext + channel * kColorClasses + size_class(sym, kColorClasses);
    }
  }
}

void SplitCodec::encode(const SplitContext& context, const SplitPayload& payload, BitWriter& w,
                        RecordBits* bits) const {
  if (codes_.size() != kSlotCount) fail("split record", "the codec has no tables");
  Writing out{codes_, w, {}};
  emit(context, payload, out);
  if (bits) *bits = out.bits;
}

SplitPayload SplitCodec::decode(const SplitContext& context, BitReader& r) const {
  if (codes_.size() != kSlotCount) fail("split record", "the codec has no tables");
  const SplitContext c = coding_context(context);
  SplitPayload p;
  References refs = references(c);
  uint32_t ref_slot = left_reference_slot(refs);
  for (int side = 0; side < 2; ++side) {
    const char* field = side == 0 ? "v̂_l" : "v̂_r";
    if (side == 1) refs.add(p.cut_l);
    const uint32_t sym = codes_[ref_slot].read(r, field);
    ref_slot = kSlotCutRight + sym;
    if (sym == kAbsentSymbol) continue;
    VertexId cut;
    if (sym == kEscapeSymbol) {
      cut.tree = uint32_t(r.bits(tree_bits(root_count_), field));
      const uint32_t depth = codes_[kSlotCutDepth].read(r, field);
      if (depth > max_depth_) r.fail_field(field, "deeper than the model");
      cut.node = (uint64_t(1) << depth) | r.bits(depth, field);
    } else {
      const uint32_t i = sym - 1;
      if (i >= refs.count) r.fail_field(field, "names a reference the client does not hold");
      const VertexId ref = refs.id[i];
      const uint32_t up_symbol = codes_[up_slot(c, max_depth_, side, i, refs.own(i))].read(r, field);
      if (up_symbol == kEqualSymbol) {
        if (i == 0) r.fail_field(field, "equal to v_s");
        cut = ref;
      } else {
        const uint32_t up = up_symbol - 1;
        const int dr = ref.depth();
        if (int(up) >= dr) r.fail_field(field, "parts above the root");
        const int common = dr - 1 - int(up);
        const uint64_t prefix = ref.node >> (dr - common);
        const uint64_t other = ((ref.node >> (dr - common - 1)) & 1) ^ 1;
        const int64_t rest =
            get_int(codes_[depth_step_slot(c, max_depth_, side, i, up)].read(r, field), r, field) + int64_t(up);
        if (rest < 0 || common + 1 + rest > int64_t(max_depth_)) r.fail_field(field, "depth outside the model");
        cut = {ref.tree, (((prefix << 1) | other) << rest) | r.bits(unsigned(rest), field)};
      }
    }
    if (cut.tree >= root_count_) r.fail_field(field, "tree-id outside the model");
    if (is_ancestor_or_self(c.vs, cut)) r.fail_field(field, "inside v_s's subtree");
    // Each id has one coding, the encoder's: a record that decodes is the one its split encodes to.
    if (cut_coding(refs, cut).ref != (sym == kEscapeSymbol ? refs.count : sym - 1))
      r.fail_field(field, "not coded against the reference its path follows furthest");
    (side == 0 ? p.cut_l : p.cut_r) = cut;
  }
  if (!is_vertex(p.cut_l) && !is_vertex(p.cut_r)) r.fail_field("v̂_r", "neither v̂_l nor v̂_r is present");
  const PositionFrame frame = position_frame(c.info_s, steps_, position_bits_);
  int64_t d[3] = {0, 0, 0};
  const int64_t top = position_bits_ >= 32 ? int64_t(UINT32_MAX) : (int64_t(1) << position_bits_) - 1;
  const auto place = [&](uint32_t axis, int64_t step) {
    const int64_t v = int64_t(c.position_s[axis]) + step;
    if (v < 0 || v > top) r.fail_field("position", "outside the grid");
    d[axis] = step;
    p.position_t[axis] = uint32_t(v);
  };
  const PairTables in_plane = in_plane_tables(c);
  int64_t pair[2];
  get_pair(codes_, in_plane, codes_[in_plane.first].read(r, "position"), r, "position", pair);
  place(frame.order[0], pair[0]);
  place(frame.order[1], pair[1]);
  const int64_t predicted = frame.plane ? plane_prediction(frame, d) : 0;
  place(frame.order[2], predicted + get_int(codes_[third_position_slot(frame, d)].read(r, "position"), r, "position",
                                            kOffPlanePrecision));
  decode_children(c, r, p);
  decode_attributes(c, edge_class(d), r, p);
  return p;
}

void SplitCodec::decode_children(const SplitContext& c, BitReader& r, SplitPayload& p) const {
  const RefineInfo& s = c.info_s;
  const uint32_t flags = codes_[kSlotInfoFlags + height_context(c, max_depth_)].read(r, "info flags");
  if (form_ == RecordForm::plain) {
    p = plain_payload(p, !(flags & 1u), !(flags & 2u));
    return;
  }
  uint32_t t_radius = kNoRadiusSymbol;
  RefineInfo* child[2] = {&p.info_t, &p.info_u};
  for (uint32_t k = 0; k < 2; ++k) {
    const char* field = k == 0 ? "info_t" : "info_u";
    RefineInfo& v = *child[k];
    if (flags & (1u << k)) {
      v = as_sent(RefineInfo{});
      continue;
    }
    uint32_t slot = radius_slot(c, max_depth_, k, t_radius);
    for (uint32_t f = 0; f < 3; ++f) {
      const uint32_t sym = codes_[slot].read(r, field);
      v.*kLengths[f] = read_length(sym, r, s.*kLengths[f], kCodesPerStep[f], field);
      if (f == 0 && k == 0) t_radius = sym;
      slot = (f == 0 ? kSlotMu : kSlotDelta) + k * kChainContexts + chain_context(sym);
    }
    const uint32_t sym = codes_[kSlotAngle + 2 * k + (s.cone_angle != kNoCone ? 1 : 0)].read(r, field);
    if (sym == kNoConeSymbol) {
      v.cone_angle = kNoCone;
      v.cone_x = v.cone_y = 0;
    } else {
      v.cone_angle = read_angle(sym, r, s.cone_angle, field);
      const PrefixCode& axis_code = codes_[kSlotAxis + k * kAxisContexts + axis_context(s, v)];
      const uint32_t x_sym = axis_code.read(r, field);
      if (x_sym == kFineAxisSymbol) {
        for (uint16_t RefineInfo::*q : {&RefineInfo::cone_x, &RefineInfo::cone_y})
          v.*q = uint16_t(int16_t(int64_t(r.bits(kAxisBits, field)) - kAxisSteps));
      } else {
        int64_t steps[2];
        get_pair(codes_, axis_tables(0, k), x_sym - 1, r, field, steps);
        for (uint16_t RefineInfo::*q : {&RefineInfo::cone_x, &RefineInfo::cone_y}) {
          const int64_t step = steps[q == &RefineInfo::cone_x ? 0 : 1];
          const int64_t value = (axis_origin(s, k == 1 ? &p.info_t : nullptr, v, q) + step) * kAxisSnap;
          if (value < -kAxisSteps || value > kAxisSteps) r.fail_field(field, "cone axis out of range");
          v.*q = uint16_t(int16_t(value));
        }
      }
    }
    if (!is_canonical(v) || never_refines(v)) r.fail_field(field, "not a value the quantizer produces");
  }
}

namespace {

// Node ranges, one per core, holding about as many splits each: in breadth-first order the coarse half
// of the nodes holds most of them (dragon 70 %), so ranges of equal node counts kept a core waiting.
std::vector<size_t> split_bounds(const ModelData& model) {
  const size_t n = model.node_count(), ranges = range_count(n, kParallelNodes);
  size_t splits = 0;
  if (ranges > 1)
    for (size_t node = 0; node < n; ++node) splits += !model.is_leaf(uint32_t(node));
  std::vector<size_t> bounds{0};
  size_t node = 0, seen = 0;
  for (size_t k = 1; k < ranges; ++k) {
    while (node < n && seen * ranges < splits * k) seen += !model.is_leaf(uint32_t(node++));
    bounds.push_back(node);
  }
  bounds.push_back(n);
  return bounds;
}

}  // namespace

SplitCodec SplitCodec::build(const ModelData& model, std::span<const uint32_t> positions, uint32_t position_bits,
                             RecordForm form) {
  return fit(model, positions, position_bits, form, nullptr);
}

SplitPayload SplitCodec::form_payload(const ModelData& model, std::span<const uint32_t> positions,
                                      uint32_t node) const {
  const SplitPayload p = split_payload(model, positions, node);
  if (form_ == RecordForm::info) return p;
  const uint32_t t = model.first_child[node];
  return plain_payload(p, !model.is_leaf(t), !model.is_leaf(t + 1));
}

SplitContext SplitCodec::coding_context(const SplitContext& context) const {
  SplitContext c = context;
  if (form_ == RecordForm::plain) c.info_s = as_sent(RefineInfo{});
  return c;
}

SplitCodec SplitCodec::fit(const ModelData& model, std::span<const uint32_t> positions, uint32_t position_bits,
                           RecordForm form, std::vector<SymbolLog>* logs) {
  check_node_arrays(model);
  if (positions.size() != 3 * model.node_count()) fail("split record", "positions are not 3 per node");
  if (!(position_bits >= 1 && position_bits <= 32)) fail("split record", "position bits outside 1..32");
  SplitCodec codec;
  codec.root_count_ = model.root_count;
  codec.position_bits_ = position_bits;
  codec.steps_ = grid_step_ratios(model);
  codec.grid_step_ = largest_grid_step(model, position_bits);
  codec.has_normals_ = !model.normals.empty();
  codec.has_colors_ = !model.colors.empty();
  codec.form_ = form;
  for (size_t n = 0; n < model.node_count(); ++n)
    codec.max_depth_ = std::max<uint32_t>(codec.max_depth_, uint32_t(model.id(uint32_t(n)).depth()));
  // One fit: every choice the coding makes is canonical, so no symbol depends on the tables.
  struct Range {
    Counts counts;
    SymbolLog log;
  };
  std::vector<Range> parts = map_bounded_ranges(split_bounds(model), [&](size_t begin, size_t end) {
    Range part;
    part.counts.counts.assign(kAllSymbols, 0);
    Fitting out{part.counts, logs ? &part.log : nullptr};
    for (uint32_t node = uint32_t(begin); node < end; ++node) {
      if (!model.is_leaf(node))
        codec.emit(split_context(model, positions, node), codec.form_payload(model, positions, node), out);
      if (logs) part.log.end_record();
    }
    return part;
  });
  for (size_t i = 1; i < parts.size(); ++i) parts[0].counts.add(parts[i].counts);
  codec.codes_.resize(kSlotCount);
  map_bounded_ranges(slot_bounds(), [&](size_t begin, size_t end) {
    for (size_t s = begin; s < end; ++s) codec.codes_[s] = PrefixCode::from_counts(parts[0].counts.of(uint32_t(s)));
    return end - begin;  // slots fitted
  });
  if (logs)
    for (Range& part : parts) logs->push_back(std::move(part.log));
  return codec;
}

std::vector<uint32_t> SplitCodec::code_words() const {
  std::vector<uint32_t> words(kAllSymbols);
  map_bounded_ranges(slot_bounds(), [&](size_t begin, size_t end) {
    for (size_t s = begin; s < end; ++s) {
      const PrefixCode& code = codes_[s];
      uint32_t* slot_words = &words[kFirstSymbol[s]];
      for (uint32_t sym = 0; sym < code.alphabet(); ++sym)
        if (code.has(sym)) slot_words[sym] = code.cost(sym) << 16 | code.word(sym);
    }
    return end - begin;  // slots done
  });
  return words;
}

bool SplitCodec::carried(uint32_t slot) const {
  if (slot >= kSlotRadius && slot < kCoreSlots) return form_ == RecordForm::info;
  if (slot < kCoreSlots) return true;
  return slot < kSlotColor ? has_normals_ : has_colors_;
}

void SplitCodec::serialize(BitWriter& w) const {
  if (codes_.size() != kSlotCount) fail("split record", "the codec has no tables");
  w.bits(root_count_, 32);
  w.bits(max_depth_, 8);
  w.bits(position_bits_, 8);
  for (uint16_t step : steps_) w.bits(step, 16);
  w.bits(bit_cast<uint32_t>(grid_step_), 32);
  w.bits(
      (has_normals_ ? kHasNormals : 0) | (has_colors_ ? kHasColors : 0) | (form_ == RecordForm::plain ? kPlainForm : 0),
      8);
  std::vector<const PrefixCode*> carried_codes;
  for (uint32_t slot = 0; slot < kSlotCount; ++slot)
    if (carried(slot)) carried_codes.push_back(&codes_[slot]);
  serialize_code_set(carried_codes, w);
}

SplitCodec SplitCodec::deserialize(BitReader& r) {
  SplitCodec codec;
  codec.root_count_ = uint32_t(r.bits(32, "root count"));
  codec.max_depth_ = uint32_t(r.bits(8, "max depth"));
  codec.position_bits_ = uint32_t(r.bits(8, "position bits"));
  for (uint16_t& step : codec.steps_) step = uint16_t(r.bits(16, "grid steps"));
  codec.grid_step_ = bit_cast<float>(uint32_t(r.bits(32, "grid step")));
  if (!std::isfinite(codec.grid_step_) || codec.grid_step_ < 0) r.fail_field("grid step", "not a finite length >= 0");
  if (codec.root_count_ == 0) r.fail_field("root count", "0");
  if (codec.max_depth_ > 63) r.fail_field("max depth", "above 63");
  if (codec.position_bits_ < 1 || codec.position_bits_ > 32) r.fail_field("position bits", "outside 1..32");
  const auto attributes = uint32_t(r.bits(8, "attributes"));
  if (attributes & ~uint32_t(kHasNormals | kHasColors | kPlainForm)) r.fail_field("attributes", "unknown bits set");
  codec.has_normals_ = attributes & kHasNormals;
  codec.has_colors_ = attributes & kHasColors;
  codec.form_ = attributes & kPlainForm ? RecordForm::plain : RecordForm::info;
  std::vector<uint32_t> slots;
  std::vector<size_t> alphabets;
  for (uint32_t s = 0; s < kSlotCount; ++s)
    if (codec.carried(s)) slots.push_back(s), alphabets.push_back(alphabet(s));
  std::vector<PrefixCode> codes = deserialize_code_set(r, alphabets, "code table");
  codec.codes_.resize(kSlotCount);
  for (size_t i = 0; i < slots.size(); ++i) codec.codes_[slots[i]] = std::move(codes[i]);
  return codec;
}

namespace {

// A node's normal as the wire quantizes it and its color; zeros for what the model lacks.
void copy_attributes(const ModelData& model, uint32_t node, uint16_t normal[2], uint8_t color[4]) {
  if (!model.normals.empty()) encode_normal(&model.normals[3 * size_t(node)], normal);
  if (!model.colors.empty()) std::copy_n(&model.colors[4 * size_t(node)], 4, color);
}

}  // namespace

const char* record_form_name(RecordForm form) { return form == RecordForm::plain ? "plain" : "info"; }

RefineInfo plain_split_info() {
  // The largest finite length the quantizer stores: the sphere holds any view and the error any tolerance.
  constexpr uint16_t kLargestLength = 0x7BFF & ~uint16_t((1u << kLengthDroppedBits) - 1);
  return {kLargestLength, kLargestLength, kLargestLength, 0, 0, kNoCone};
}

SplitPayload plain_payload(SplitPayload payload, bool t_has_split, bool u_has_split) {
  payload.info_t = t_has_split ? plain_split_info() : as_sent(RefineInfo{});
  payload.info_u = u_has_split ? plain_split_info() : as_sent(RefineInfo{});
  return payload;
}

SplitContext split_context(const ModelData& model, std::span<const uint32_t> positions, uint32_t node) {
  SplitContext c;
  c.vs = model.id(node);
  std::copy_n(&positions[3 * size_t(node)], 3, c.position_s);
  c.info_s = as_sent(model.refine[node]);
  copy_attributes(model, node, c.normal_s, c.color_s);
  uint32_t n = node;
  for (int i = 0; i < kCutAncestors; ++i) {
    n = model.parent[n];
    if (n == kNone) break;
    for (int side = 0; side < 2; ++side) {
      const uint32_t cut = side == 0 ? model.cut_left[n] : model.cut_right[n];
      c.ancestor_cuts[2 * i + side] = cut == kNone ? kNoVertex : model.id(cut);
    }
  }
  return c;
}

SplitPayload split_payload(const ModelData& model, std::span<const uint32_t> positions, uint32_t node) {
  if (model.is_leaf(node)) fail("split record", "node " + std::to_string(node) + " is a leaf");
  SplitPayload p;
  const uint32_t t = model.first_child[node];
  if (model.cut_left[node] != kNone) p.cut_l = model.id(model.cut_left[node]);
  if (model.cut_right[node] != kNone) p.cut_r = model.id(model.cut_right[node]);
  std::copy_n(&positions[3 * size_t(t)], 3, p.position_t);
  p.info_t = as_sent(model.refine[t]);
  p.info_u = as_sent(model.refine[t + 1]);
  copy_attributes(model, t, p.normal_t, p.color_t);
  return p;
}

std::array<uint16_t, 3> grid_step_ratios(const ModelData& model) {
  double extent[3], largest = 0;
  for (int i = 0; i < 3; ++i)
    largest = std::max(largest, extent[i] = double(model.bbox_max[i]) - double(model.bbox_min[i]));
  std::array<uint16_t, 3> steps{};
  for (int i = 0; i < 3; ++i) steps[i] = largest > 0 ? uint16_t(std::lround(65535 * extent[i] / largest)) : 0;
  return steps;
}

float largest_grid_step(const ModelData& model, uint32_t position_bits) {
  if (position_bits > kGridBits) return 0;
  double largest = 0;
  for (int i = 0; i < 3; ++i) largest = std::max(largest, double(model.bbox_max[i]) - double(model.bbox_min[i]));
  const double scale = model.scale > 0 && std::isfinite(model.scale) ? model.scale : 1;
  return float(largest / double((uint64_t(1) << position_bits) - 1) / scale);
}

PositionGrid model_grid(const ModelData& model, uint32_t position_bits) {
  PositionGrid grid;
  std::copy_n(model.bbox_min, 3, grid.min);
  std::copy_n(model.bbox_max, 3, grid.max);
  grid.bits = position_bits;
  return grid;
}

std::vector<uint32_t> grid_positions(const ModelData& model, uint32_t position_bits) {
  const PositionGrid grid = model_grid(model, position_bits);
  std::vector<uint32_t> q(3 * model.node_count());
  for_each_range(model.node_count(), size_t(1) << 15, [&](size_t begin, size_t end) {
    for (size_t n = begin; n < end; ++n) quantize_position(grid, &model.position[3 * n], &q[3 * n]);
  });
  return q;
}

EncodedRecords encode_records(const ModelData& model, uint32_t position_bits, RecordForm form) {
  const std::vector<uint32_t> q = grid_positions(model, position_bits);
  std::vector<SplitCodec::SymbolLog> logs;
  const SplitCodec codec = SplitCodec::fit(model, q, position_bits, form, &logs);
  EncodedRecords out;
  BitWriter tables;
  codec.serialize(tables);
  out.tables = tables.bytes();
  struct Range {
    BitWriter records;
    std::vector<uint64_t> offsets;  // from the range's start
  };
  const std::vector<uint32_t> code_words = codec.code_words();
  std::vector<Range> parts = map_bounded_ranges(even_bounds(logs.size(), logs.size()), [&](size_t begin, size_t end) {
    Range part;
    for (size_t i = begin; i < end; ++i) {
      logs[i].write(code_words, part.records, part.offsets);
      logs[i] = {};
    }
    return part;
  });
  BitWriter records;
  out.offsets.reserve(model.node_count() + 1);
  for (Range& part : parts) {
    const uint64_t start = records.size();
    for (uint64_t offset : part.offsets) out.offsets.push_back(start + offset);
    if (start == 0) records = std::move(part.records);
    else records.append(part.records);
  }
  out.offsets.push_back(records.size());
  out.records = std::move(records).take();
  return out;
}

SplitCodec check_records(const std::string& where, const ModelData& model, std::span<const uint8_t> tables,
                         std::span<const uint64_t> offsets, std::span<const uint8_t> records) {
  BitReader table_reader(tables, where + ": split tables");
  SplitCodec codec = SplitCodec::deserialize(table_reader);
  if (table_reader.bits_left() >= 8) fail(where, "split tables: bytes after the tables");
  uint32_t depth = 0;
  for (uint64_t id : model.node_id) depth = std::max(depth, uint32_t(63 - std::countl_zero(id)));
  if (codec.root_count() != model.root_count || codec.max_depth() != depth ||
      !valid_position_bits(codec.position_bits()))
    fail(where, "split tables: root count, depth or position bits do not match the model");
  if (codec.has_normals() != !model.normals.empty() || codec.has_colors() != !model.colors.empty())
    fail(where, "split tables: the normals and colors they carry are not the model's");
  if (codec.form() != RecordForm::info) fail(where, "split tables: stored records carry the refinement info");
  const size_t n = model.node_count();
  if (offsets.size() != n + 1) fail(where, "split record offsets: not one per node plus one");
  const uint64_t bits = 8 * uint64_t(records.size());
  if (offsets[0] != 0 || offsets[n] > bits || bits - offsets[n] >= 8)
    fail(where, "split record offsets: do not span the records");
  const std::vector<uint32_t> q = grid_positions(model, codec.position_bits());
  map_bounded_ranges(split_bounds(model), [&](size_t begin, size_t end) {
    for (uint32_t node = uint32_t(begin); node < end; ++node) {
      if (offsets[node + 1] < offsets[node])
        fail(where, "split record offsets: not in order at node " + std::to_string(node));
      if (model.is_leaf(node)) {
        if (offsets[node + 1] != offsets[node])
          fail(where, "split records: leaf " + std::to_string(node) + " has a record");
        continue;
      }
      BitReader r(records, offsets[node], offsets[node + 1], where + ": split record of node " + std::to_string(node));
      if (!(codec.decode(split_context(model, q, node), r) == split_payload(model, q, node)) || r.bits_left() != 0)
        fail(where, "split records: node " + std::to_string(node) + "'s record is not its split");
    }
    return end - begin;  // nodes checked
  });
  return codec;
}

}  // namespace pms
