// Writing a .pms file (docs/pms-format.md): the hierarchy is validated with the reader's own
// checks first, so no writer bug produces a file the reader rejects, then streamed section by
// section from the vectors (no copy of the model) into PATH.tmp, which is renamed into place. The
// split records, coded last, go after the hierarchy's sections and the header goes in at the end.
#include <fcntl.h>
#include <unistd.h>
#include <xxhash.h>
#include <algorithm>
#include <cerrno>
#include <cstring>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/pms_format_internal.h"
#include "spm/position_grid.h"
#include "spm/split_codec.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

using namespace format;

uint64_t align_up(uint64_t offset) { return (offset + kAlignment - 1) / kAlignment * kAlignment; }

// Lengths validate_model() takes for granted; the contents are its job.
void check_shape(const std::string& where, const Hierarchy& h) {
  const size_t n = h.node_count();
  if (n >= kNone) fail(where, std::to_string(n) + " nodes do not fit 32-bit indices");
  const auto expect = [&](const char* name, size_t size, size_t per_node) {
    if (size != per_node * n)
      fail(where, std::string(name) + " has " + std::to_string(size) + " values for " + std::to_string(n) + " nodes");
  };
  expect("first_child", h.first_child.size(), 1);
  expect("position", h.position.size(), 3);
  expect("cut_left", h.cut_left.size(), 1);
  expect("cut_right", h.cut_right.size(), 1);
  expect("refine", h.refine.size(), 1);
  expect("leaf_vertex", h.leaf_vertex.size(), 1);
  if (!h.normals.empty()) expect("normals", h.normals.size(), 3);
  if (!h.colors.empty()) expect("colors", h.colors.size(), 4);
  if (h.base_faces.size() % 3 != 0 || h.base_faces.size() / 3 >= kNone)
    fail(where,
         "base_faces holds " + std::to_string(h.base_faces.size()) + " indices, not a 32-bit count of triangles");
}

HeadSection make_head(const Hierarchy& h) {
  HeadSection head{};
  head.root_count = h.root_count;
  head.node_count = uint32_t(h.node_count());
  head.base_face_count = uint32_t(h.base_faces.size() / 3);
  head.flags = (h.normals.empty() ? 0 : kHasNormals) | (h.colors.empty() ? 0 : kHasColors);
  std::copy_n(h.bbox_min, 3, head.bbox_min);
  std::copy_n(h.bbox_max, 3, head.bbox_max);
  head.scale = h.scale;
  return head;
}

struct Chunk {
  Section section;
  const void* data;
  uint64_t count;
  uint64_t bytes() const { return count * kSections[section].element_size; }
};

// PATH.tmp, renamed over PATH by commit(): readers never see a half-written model, and an error
// (or exception) before commit() removes the temporary file and leaves PATH as it was.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path) : path_(path), tmp_(path + ".tmp") {
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) io_error("cannot create " + tmp_);
  }
  ~AtomicFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(tmp_.c_str());
  }
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Appends after what is written.
  void write(const void* data, uint64_t bytes) {
    write_at(written_, data, bytes);
    written_ += bytes;
  }
  // Zero padding up to the next section start (the same align_up the table was laid out with).
  void align() {
    static constexpr char zeros[kAlignment] = {};
    write(zeros, align_up(written_) - written_);
  }
  uint64_t written() const { return written_; }
  // At `offset`: the end, or over bytes already written (the header, once the sections after it are known).
  void write_at(uint64_t offset, const void* data, uint64_t bytes) {
    const char* p = static_cast<const char*>(data);
    while (bytes > 0) {
      const ssize_t done = ::pwrite(fd_, p, std::min<uint64_t>(bytes, 1u << 30), off_t(offset));
      if (done < 0 && errno == EINTR) continue;
      if (done <= 0) io_error("cannot write " + tmp_);
      p += done, offset += uint64_t(done), bytes -= uint64_t(done);
    }
  }
  // Asks the kernel to start writing what is written so far, without waiting: advice, so errors are
  // left to commit()'s fsync.
  void start_writeback() {
#if defined(__linux__)
    ::sync_file_range(fd_, 0, 0, SYNC_FILE_RANGE_WRITE);
#endif
  }
  void commit() {
    if (::fsync(fd_) != 0) io_error("cannot write " + tmp_);
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) io_error("cannot write " + tmp_);
    if (::rename(tmp_.c_str(), path_.c_str()) != 0) io_error("cannot rename " + tmp_ + " to it");
    committed_ = true;
  }

 private:
  [[noreturn]] void io_error(const std::string& what) { fail(path_, what + ": " + std::strerror(errno)); }
  std::string path_, tmp_;
  int fd_ = -1;
  uint64_t written_ = 0;
  bool committed_ = false;
};

}  // namespace

void write_pms(const std::string& path, const Hierarchy& h, const BuildStats& stats) {
  const std::string where = path + ": refusing to write an invalid hierarchy";
  check_shape(where, h);
  std::vector<uint32_t> tree_id;
  std::vector<uint64_t> node_id;
  validate_model(where, model_of(h), tree_id, node_id);

  const HeadSection head = make_head(h);
  const std::string meta = stats_to_json(stats);
  const uint64_t n = h.node_count();
  std::vector<Chunk> chunks = {{Head, &head, 1},
                               {Meta, meta.data(), meta.size()},
                               {Base, h.base_faces.data(), h.base_faces.size() / 3},
                               {Parent, h.parent.data(), n},
                               {Children, h.first_child.data(), n},
                               {Position, h.position.data(), n},
                               {CutLeft, h.cut_left.data(), n},
                               {CutRight, h.cut_right.data(), n},
                               {Refine, h.refine.data(), n},
                               {Leaf, h.leaf_vertex.data(), n},
                               {SplitOrder, h.split_order.data(), h.split_order.size()}};
  if (!h.normals.empty()) chunks.push_back({Normal, h.normals.data(), n});
  if (!h.colors.empty()) chunks.push_back({Color, h.colors.data(), n});
  constexpr size_t kRecordSections = 3;  // tables, offsets, records: last, so nothing before them waits

  FileHeader header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.version = kVersion;
  header.header_bytes = sizeof header;
  header.section_count = uint32_t(chunks.size() + kRecordSections);
  std::vector<uint8_t> header_and_table(sizeof header + header.section_count * sizeof(SectionEntry));
  AtomicFile file(path);
  file.write(header_and_table.data(), header_and_table.size());  // zeros until every section is known
  size_t entry_count = 0;
  const auto put = [&](const Chunk& c) {
    file.align();
    SectionEntry e{};
    std::memcpy(e.tag, kSections[c.section].tag, sizeof e.tag);
    e.element_size = kSections[c.section].element_size;
    e.offset = file.written();
    e.count = c.count;
    e.checksum = XXH64(c.data, c.bytes(), 0);
    std::memcpy(&header_and_table[sizeof header + entry_count++ * sizeof e], &e, sizeof e);
    file.write(c.data, c.bytes());
  };
  for (const Chunk& c : chunks) put(c);
  // The disk takes the hierarchy while the records are coded: the final fsync waits for their part only.
  file.start_writeback();

  ModelData model = model_of(h);
  model.tree_id = tree_id;
  model.node_id = node_id;
  const EncodedRecords records = encode_records(model, kDefaultPositionBits);
  put({SplitTables, records.tables.data(), records.tables.size()});
  put({SplitOffsets, records.offsets.data(), records.offsets.size()});
  put({SplitRecords, records.records.data(), records.records.size()});

  header.file_size = file.written();
  std::memcpy(header_and_table.data(), &header, sizeof header);
  header.header_checksum = header_checksum(header_and_table.data(), header_and_table.size());
  std::memcpy(header_and_table.data(), &header, sizeof header);
  file.write_at(0, header_and_table.data(), header_and_table.size());
  file.commit();
}

}  // namespace pms
