// Corrupt .pms files (docs/pms-format.md, "Reader behaviour"): every damage is a pms::Error
// "NAME: section TAG: problem" (or "NAME: header: problem") — never a crash, a hang or a huge allocation.
// Structural damage is made with checksums fixed up afterwards, so the validation itself has to catch it.
#include <gtest/gtest.h>
#include <xxhash.h>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/bit_stream.h"
#include "common/error.h"
#include "pm_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/split_codec.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms {
namespace {

// The layout of docs/pms-format.md, written down independently of the reader's structs.
constexpr size_t kHeaderBytes = 40, kEntryBytes = 32;
constexpr size_t kVersionAt = 8, kSectionCountAt = 16, kChecksumAt = 32;
constexpr size_t kHeadNodeCount = 4, kHeadRootCount = 0, kHeadFlags = 12, kHeadScale = 40;

struct Entry {
  std::string tag;
  size_t at;  // of the table entry
  uint32_t element_size;
  uint64_t offset, count;
  uint64_t bytes() const { return element_size * count; }
};

template <class T>
T load(const std::vector<uint8_t>& b, size_t at) {
  T v;
  std::memcpy(&v, &b[at], sizeof v);
  return v;
}
template <class T>
void store(std::vector<uint8_t>& b, size_t at, T v) {
  std::memcpy(&b[at], &v, sizeof v);
}

class PmsBytes {
 public:
  explicit PmsBytes(const Hierarchy& h) {
    const auto path = test::temp_dir() / "model.pms";
    write_pms(path.string(), h, stats());
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  static BuildStats stats() {
    BuildStats s;
    s.input_name = "model.ply";
    s.options = "abc";
    return s;
  }

  std::vector<Entry> entries() const {
    std::vector<Entry> out;
    for (uint32_t i = 0; i < load<uint32_t>(bytes, kSectionCountAt); ++i) {
      const size_t at = kHeaderBytes + i * kEntryBytes;
      out.push_back({std::string(reinterpret_cast<const char*>(&bytes[at]), 4), at, load<uint32_t>(bytes, at + 4),
                     load<uint64_t>(bytes, at + 8), load<uint64_t>(bytes, at + 16)});
    }
    return out;
  }
  Entry entry(const std::string& tag) const {
    for (const Entry& e : entries())
      if (e.tag == tag) return e;
    ADD_FAILURE() << "no section " << tag;
    return {};
  }
  size_t table_end() const { return kHeaderBytes + entries().size() * kEntryBytes; }

  // Element `index` of section `tag`, as a T at byte `field` inside the element.
  template <class T>
  void set(const std::string& tag, size_t index, T value, size_t field = 0) {
    const Entry e = entry(tag);
    store(bytes, e.offset + index * e.element_size + field, value);
  }
  template <class T>
  T get(const std::string& tag, size_t index, size_t field = 0) const {
    const Entry e = entry(tag);
    return load<T>(bytes, e.offset + index * e.element_size + field);
  }

  // Recomputes every section checksum and then the header checksum, as a writer would.
  void fix_checksums() {
    for (const Entry& e : entries())
      if (e.offset + e.bytes() <= bytes.size())
        store<uint64_t>(bytes, e.at + 24, XXH64(&bytes[e.offset], e.bytes(), 0));
    std::vector<uint8_t> head(bytes.begin(), bytes.begin() + long(table_end()));
    store<uint64_t>(head, kChecksumAt, 0);
    store<uint64_t>(bytes, kChecksumAt, XXH64(head.data(), head.size(), 0));
  }

  // The error message of opening these bytes, without the "model.pms: " prefix.
  std::string error() const {
    try {
      PmsFile::from_bytes("model.pms", bytes.data(), bytes.size());
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind("model.pms: ", 0), 0u) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      return message.substr(std::min<size_t>(message.size(), 11));
    }
    return "(opened fine)";
  }

  std::vector<uint8_t> bytes;
};

// Asserts the error starts with `prefix` (e.g. "section PRNT: ") and contains `detail`.
void expect_error(const PmsBytes& file, const std::string& prefix, const std::string& detail,
                  const std::string& context = "") {
  const std::string message = file.error();
  EXPECT_EQ(message.rfind(prefix, 0), 0u) << message << " " << context;
  EXPECT_NE(message.find(detail), std::string::npos) << message << " " << context;
}

PmsBytes small() { return PmsBytes(test::make_small_hierarchy()); }

TEST(PmsCorrupt, TheUntouchedFixtureOpens) {
  PmsBytes f = small();
  EXPECT_EQ(f.error(), "(opened fine)");
  f.fix_checksums();  // the helper reproduces the writer's checksums exactly
  EXPECT_EQ(f.error(), "(opened fine)");
}

// A cut inside the header or table is the header's problem; anywhere later, the first section
// that no longer fits is named.
TEST(PmsCorrupt, TruncatedAtEveryOffset) {
  const PmsBytes full = small();
  const std::vector<Entry> entries = full.entries();
  for (size_t size = 0; size < full.bytes.size(); ++size) {
    PmsBytes cut = full;
    cut.bytes.resize(size);
    if (size < full.table_end()) {
      expect_error(cut, "header: ", "", "cut at " + std::to_string(size));
      continue;
    }
    std::string tag;
    for (const Entry& e : entries)
      if (tag.empty() && (e.offset > size || e.offset + e.bytes() > size)) tag = e.tag;
    expect_error(cut, "section " + tag + ": ", "run past the end", "cut at " + std::to_string(size));
  }
  PmsBytes longer = full;
  longer.bytes.push_back(0);
  expect_error(longer, "header: ", "file is " + std::to_string(full.bytes.size() + 1) + " bytes but the header says");
}

TEST(PmsCorrupt, FlippedByteInEachSectionFailsItsChecksum) {
  const PmsBytes clean = small();
  for (const Entry& e : clean.entries()) {
    ASSERT_GT(e.bytes(), 0u) << e.tag;
    for (const uint64_t at : {e.offset, e.offset + e.bytes() / 2, e.offset + e.bytes() - 1}) {
      PmsBytes f = clean;
      f.bytes[at] ^= 0x10;
      expect_error(f, "section " + e.tag + ": ", "checksum mismatch", "byte " + std::to_string(at));
    }
  }
}

TEST(PmsCorrupt, FlippedByteInHeaderOrTable) {
  const PmsBytes clean = small();
  for (size_t at = 0; at < clean.table_end(); ++at) {
    PmsBytes f = clean;
    f.bytes[at] ^= 0x01;
    expect_error(f, "header: ", "", "byte " + std::to_string(at));
  }
}

TEST(PmsCorrupt, WrongMagicAndNewerVersion) {
  PmsBytes f = small();
  f.bytes[0] = 'X';
  expect_error(f, "header: ", "not a .pms file");
  f = small();
  store<uint32_t>(f.bytes, kVersionAt, 8);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "header: unsupported version 8 (this build reads 7)");
  f = small();
  store<uint32_t>(f.bytes, kVersionAt, 6);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "header: unsupported version 6 (this build reads 7; rebuild the file with this pmstream)");
}

TEST(PmsCorrupt, AbsurdNodeCountInHead) {
  PmsBytes f = small();
  f.set<uint32_t>("HEAD", 0, 0x7FFFFFFF, kHeadNodeCount);
  f.fix_checksums();
  expect_error(f, "section PRNT: ", "HEAD says 2147483647 nodes");
  f = small();
  f.set<uint32_t>("HEAD", 0, 0xFFFFFFFF, kHeadRootCount);
  f.fix_checksums();
  expect_error(f, "section HEAD: ", "4294967295 base vertices but only 9 nodes");
}

TEST(PmsCorrupt, AbsurdCountsInTheTable) {
  // Huge, and huge enough that count * 12 wraps around 2^64 to a small number.
  for (const uint64_t count : {uint64_t(1) << 61, uint64_t(0x1555555555555556)}) {
    PmsBytes f = small();
    store<uint64_t>(f.bytes, f.entry("POSI").at + 16, count);
    f.fix_checksums();
    expect_error(f, "section POSI: ", std::to_string(count) + " elements of 12 bytes");
  }
  PmsBytes f = small();
  store<uint32_t>(f.bytes, kSectionCountAt, 0x7FFFFFFF);
  expect_error(f, "header: ", "section table of 2147483647 entries runs past the end");
  f = small();
  store<uint64_t>(f.bytes, f.entry("SORD").at + 8, uint64_t(-64));  // offset near 2^64
  f.fix_checksums();
  expect_error(f, "section SORD: ", "run past the end");
}

TEST(PmsCorrupt, TableEntryProblems) {
  PmsBytes f = small();
  store<uint64_t>(f.bytes, f.entry("CHLD").at + 8, f.entry("CHLD").offset + 4);
  f.fix_checksums();
  expect_error(f, "section CHLD: ", "not 64-byte aligned");

  f = small();
  store<uint64_t>(f.bytes, f.entry("CHLD").at + 8, f.entry("PRNT").offset);
  f.fix_checksums();
  expect_error(f, "section CHLD: ", "overlaps");

  f = small();
  store<uint32_t>(f.bytes, f.entry("RINF").at + 4, 6);
  f.fix_checksums();
  expect_error(f, "section RINF: ", "element size 6, expected 12");

  f = small();
  std::memcpy(&f.bytes[f.entry("PRNT").at], "XXXX", 4);  // an unknown section is skipped...
  f.fix_checksums();
  EXPECT_EQ(f.error(), "section PRNT: missing");  // ...so the parents are missing

  f = small();
  std::memcpy(&f.bytes[f.entry("CHLD").at], "PRNT", 4);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "section PRNT: appears twice");

  f = small();
  std::memcpy(&f.bytes[f.entry("CHLD").at], "\x01\xff\n!", 4);
  store<uint32_t>(f.bytes, f.entry("PRNT").at + 4, 0);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "section PRNT: element size 0") << "the tag is printed cleanly";
}

TEST(PmsCorrupt, HeadValues) {
  PmsBytes f = small();
  f.set<uint32_t>("HEAD", 0, 0, kHeadRootCount);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "section HEAD: no base vertices");

  f = small();
  f.set<float>("HEAD", 0, NAN, kHeadScale);
  f.fix_checksums();
  expect_error(f, "section HEAD: ", "scale");

  f = small();
  f.set<uint32_t>("HEAD", 0, 0, kHeadFlags);
  f.fix_checksums();
  expect_error(f, "section NRML: ", "present but HEAD says no normals");

  PmsBytes plain(test::make_small_hierarchy(false));
  plain.set<uint32_t>("HEAD", 0, 2, kHeadFlags);
  plain.fix_checksums();
  expect_error(plain, "section COLR: ", "missing but HEAD says the model has colors");
}

// One tampered value per check family, checksums fixed, so only the structural check can tell.
struct Tamper {
  const char* tag;
  size_t index;
  uint32_t value;
  const char* expected;  // full message after "model.pms: "
};

TEST(PmsCorrupt, StructuralDamageNamesTheSection) {
  const Tamper cases[] = {
      {"PRNT", 2, 0, "section PRNT: root 2 has parent 0"},
      {"PRNT", 5, 7, "section PRNT: node 5: parent 7 is not before it in the array"},
      {"PRNT", 5, kNone, "section PRNT: node 5 is not a root but has no parent"},
      {"PRNT", 8, 1, "section CHLD: node 4: children 7, 8 do not name it as their parent"},
      {"CHLD", 4, 5, "section CHLD: node 4: children 5, 6 do not name it as their parent"},
      {"CHLD", 4, 3, "section CHLD: node 4: children 3, 4 are not after it inside the array"},
      {"CHLD", 4, 8, "section CHLD: node 4: children 8, 9 are not after it inside the array"},
      {"CHLD", 4, kNone, "section CHLD: node 7 is not a child of its parent 4"},
      {"CUTL", 1, 4, "section CUTL: node 1: cut vertex 4 is not a leaf"},
      {"CUTL", 0, 7, "section CUTL: node 0: cut vertex 7 lies below the node itself"},
      {"CUTR", 4, 8, "section CUTR: node 4: cut vertex 8 lies below the node itself"},
      {"CUTL", 1, 9, "section CUTL: node 1: cut vertex 9 out of range"},
      {"CUTR", 3, 2, "section CUTR: leaf 3 has cut vertex 2"},
      {"CUTL", 1, kNone, "section CUTL: node 1: a split needs at least one cut vertex, both are missing"},
      {"LEAF", 3, 0, "section LEAF: input vertex 0 belongs to two leaves (not a permutation)"},
      {"LEAF", 3, 6, "section LEAF: leaf 3: input vertex 6 >= leaf count 6"},
      {"LEAF", 3, kNone, "section LEAF: leaf 3 has no input vertex"},
      {"LEAF", 0, 0, "section LEAF: internal node 0 has input vertex 0"},
      {"BASE", 0, 3, "section BASE: face 0: vertex 3 is not a base vertex (3 roots)"},
      {"SORD", 1, 4, "section SORD: node 4 comes before its parent 0"},
      {"SORD", 1, 1, "section SORD: node 1 appears twice"},
      {"SORD", 0, 2, "section SORD: entry 0: node 2 is a leaf"},
      {"SORD", 0, 99, "section SORD: entry 0: node 99 out of range"},
  };
  for (const Tamper& t : cases) {
    PmsBytes f = small();
    f.set<uint32_t>(t.tag, t.index, t.value);
    f.fix_checksums();
    EXPECT_EQ(f.error(), t.expected) << t.tag << "[" << t.index << "] = " << t.value;
  }
}

TEST(PmsCorrupt, NonFiniteAndNegativeValues) {
  PmsBytes f = small();
  f.set<float>("POSI", 4, INFINITY, 8);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "section POSI: node 4: value is not finite");

  f = small();
  f.set<float>("NRML", 2, NAN);
  f.fix_checksums();
  EXPECT_EQ(f.error(), "section NRML: node 2: value is not finite");

  f = small();
  const std::string bad_rinf =
      "section RINF: node 6: a length is negative, NaN or finer than stored, or the cone is out of range";
  f.set<uint16_t>("RINF", 6, 0xBC00);  // radius -1
  f.fix_checksums();
  EXPECT_EQ(f.error(), bad_rinf);

  f = small();
  f.set<uint16_t>("RINF", 6, 0x7E00, 4);  // delta NaN
  f.fix_checksums();
  EXPECT_EQ(f.error(), bad_rinf);

  f = small();
  f.set<uint16_t>("RINF", 6, 0x3C01, 2);  // mu with a mantissa bit the file format drops
  f.fix_checksums();
  EXPECT_EQ(f.error(), bad_rinf);

  f = small();
  f.set<uint16_t>("RINF", 6, 1023 + 1, 10);  // cone angle past pi/2 that is not kNoCone
  f.fix_checksums();
  EXPECT_EQ(f.error(), bad_rinf);
}

TEST(PmsCorrupt, Meta) {
  PmsBytes f = small();
  const Entry meta = f.entry("META");
  const std::string json(reinterpret_cast<const char*>(&f.bytes[meta.offset]), meta.bytes());
  const auto replace = [&](const std::string& from, const std::string& to) {
    ASSERT_EQ(from.size(), to.size());
    const size_t at = json.find(from);
    ASSERT_NE(at, std::string::npos) << json;
    PmsBytes g = f;
    std::memcpy(&g.bytes[meta.offset + at], to.data(), to.size());
    g.fix_checksums();
    f = g;
  };
  const PmsBytes clean = f;
  replace("\"options\":\"abc\"", "\"options\":12345");
  EXPECT_EQ(f.error(), "section META: field \"options\" has the wrong type");

  f = clean;
  replace(json, "{" + std::string(json.size() - 2, ' ') + "}");
  EXPECT_EQ(f.error(), "(opened fine)") << "missing fields are tolerated";

  f = clean;
  replace(json.substr(0, 1), "[");
  EXPECT_EQ(f.error(), "section META: not valid JSON");

  f = clean;
  replace(json, "\"" + std::string(json.size() - 2, 'x') + "\"");
  EXPECT_EQ(f.error(), "section META: not a JSON object");
}

// The split records must be the hierarchy's: a flipped bit in a record, an offset moved, a record given to
// a leaf or tables that name another model are refused even with every checksum recomputed.
TEST(PmsCorrupt, SplitRecordsMustBeTheModels) {
  PmsBytes f = small();
  EXPECT_EQ(f.error(), "(opened fine)");
  const Entry records = f.entry("SREC");
  ASSERT_GT(records.count, 0u);
  for (size_t byte = 0; byte < records.count; ++byte) {
    PmsBytes g = f;
    g.bytes[records.offset + byte] ^= 0x10;
    g.fix_checksums();
    const std::string e = g.error();
    if (byte == records.count - 1 && e == "(opened fine)") continue;  // a padding bit
    EXPECT_NE(e.find("split record"), std::string::npos) << e;
  }
  PmsBytes moved = f;
  moved.set<uint64_t>("SROF", 1, moved.get<uint64_t>("SROF", 1) + 1);
  moved.fix_checksums();
  EXPECT_NE(moved.error().find("split record"), std::string::npos) << moved.error();
  PmsBytes leaf = f;  // node 2 is a leaf: give it the start of node 3's record
  leaf.set<uint64_t>("SROF", 3, leaf.get<uint64_t>("SROF", 3) + 1);
  leaf.fix_checksums();
  EXPECT_NE(leaf.error().find("split record"), std::string::npos) << leaf.error();
  PmsBytes tables = f;
  tables.set<uint32_t>("SRTB", 0, 7);  // the root count the tables were fitted to
  tables.fix_checksums();
  EXPECT_NE(tables.error().find("split tables"), std::string::npos) << tables.error();
  // The model has normals and colors: tables that say the records carry neither (or another attribute) are refused.
  constexpr size_t kAttributesByte = (32 + 8 + 8 + 3 * 16 + 32) / 8;
  ASSERT_EQ(f.get<uint8_t>("SRTB", kAttributesByte), 3u);
  for (const uint8_t attributes : {0, 1, 2, 7}) {
    PmsBytes other = f;
    other.set<uint8_t>("SRTB", kAttributesByte, attributes);
    other.fix_checksums();
    EXPECT_NE(other.error().find("split tables"), std::string::npos) << int(attributes) << ": " << other.error();
  }
}

TEST(PmsFile, StoredSplitRecordsDecodeToTheModel) {
  PmsBytes f = small();
  const auto file = PmsFile::from_bytes("model.pms", f.bytes.data(), f.bytes.size());
  const ModelData& model = file->model();
  const std::vector<uint32_t> q = grid_positions(model, file->split_codec().position_bits());
  size_t decoded = 0;
  for (uint32_t node = 0; node < model.node_count(); ++node) {
    if (model.is_leaf(node)) continue;
    BitReader r(file->split_records(), file->split_offsets()[node], file->split_offsets()[node + 1], "record");
    EXPECT_EQ(file->split_codec().decode(split_context(model, q, node), r), split_payload(model, q, node));
    ++decoded;
  }
  EXPECT_EQ(decoded, model.split_order.size());
}

}  // namespace
}  // namespace pms
