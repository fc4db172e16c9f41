// Opening a .pms file (docs/pms-format.md, "Reader behaviour"): map it read-only, check the container
// (pms_layout.cpp), the HEAD counts and the model (pms_validate.cpp), then serve spans straight into the
// mapping, so a server holding many models pays for pages it touches, not for parsing.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cerrno>
#include <cstddef>
#include <cstring>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/pms_format_internal.h"
#include "spm/refine_info.h"
#include "spm/split_codec.h"

namespace pms {
namespace {

using namespace format;

template <class T>
std::span<const T> typed(const LocatedSection& s, size_t values_per_element) {
  return {reinterpret_cast<const T*>(s.data), size_t(s.count) * values_per_element};
}

HeadSection read_head(const std::string& where, const SectionMap& sections) {
  const LocatedSection& s = sections[Head];
  if (s.count != 1) section_error(where, Head, str(s.count) + " elements, expected 1");
  HeadSection head;
  std::memcpy(&head, s.data, sizeof head);
  if (head.flags & ~(kHasNormals | kHasColors)) section_error(where, Head, "unknown flags " + str(head.flags));
  return head;
}

// Every array's length follows from HEAD; the size check in locate_sections already bounded the
// counts by the file size, so nothing here or later allocates more than the file warrants.
void check_counts(const std::string& where, const SectionMap& sections, const HeadSection& head) {
  const auto expect = [&](Section k, uint64_t expected, const char* what) {
    if (sections[k].count != expected)
      section_error(where, k, str(sections[k].count) + " elements but HEAD says " + str(expected) + " " + what);
  };
  expect(Base, head.base_face_count, "base faces");
  for (Section k : {Parent, Children, Position, CutLeft, CutRight, Refine, Leaf}) expect(k, head.node_count, "nodes");
  const auto optional = [&](Section k, uint32_t flag, const char* what) {
    if (!(head.flags & flag) && sections[k].present)
      section_error(where, k, std::string("present but HEAD says no ") + what);
    if (head.flags & flag) {
      if (!sections[k].present) section_error(where, k, std::string("missing but HEAD says the model has ") + what);
      expect(k, head.node_count, "nodes");
    }
  };
  optional(Normal, kHasNormals, "normals");
  optional(Color, kHasColors, "colors");
}

ModelData make_model(const SectionMap& sections, const HeadSection& head) {
  ModelData v;
  v.root_count = head.root_count;
  v.base_faces = typed<uint32_t>(sections[Base], 3);
  v.parent = typed<uint32_t>(sections[Parent], 1);
  v.first_child = typed<uint32_t>(sections[Children], 1);
  v.position = typed<float>(sections[Position], 3);
  v.cut_left = typed<uint32_t>(sections[CutLeft], 1);
  v.cut_right = typed<uint32_t>(sections[CutRight], 1);
  v.refine = typed<RefineInfo>(sections[Refine], 1);
  v.leaf_vertex = typed<uint32_t>(sections[Leaf], 1);
  v.split_order = typed<uint32_t>(sections[SplitOrder], 1);
  v.normals = typed<float>(sections[Normal], 3);  // empty when absent
  v.colors = typed<uint8_t>(sections[Color], 4);
  // HEAD is 64-byte aligned, so its floats can be used in place.
  v.bbox_min = reinterpret_cast<const float*>(sections[Head].data + offsetof(HeadSection, bbox_min));
  v.bbox_max = reinterpret_cast<const float*>(sections[Head].data + offsetof(HeadSection, bbox_max));
  v.scale = head.scale;
  return v;
}

struct FileDescriptor {
  int fd;
  ~FileDescriptor() { ::close(fd); }
};

[[noreturn]] void io_error(const std::string& path, const char* what) {
  fail(path, what + std::string(": ") + std::strerror(errno));
}

}  // namespace

std::unique_ptr<PmsFile> PmsFile::open(const std::string& path) {
  std::unique_ptr<PmsFile> file(new PmsFile());
  const FileDescriptor f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (f.fd < 0) io_error(path, "cannot open");
  struct stat st;
  if (::fstat(f.fd, &st) != 0) io_error(path, "cannot stat");
  if (!S_ISREG(st.st_mode)) fail(path, "not a regular file");
  file->size_ = uint64_t(st.st_size);
  if (file->size_ > 0) {
    void* p = ::mmap(nullptr, file->size_, PROT_READ, MAP_PRIVATE, f.fd, 0);
    if (p != MAP_FAILED) {
      file->data_ = static_cast<const uint8_t*>(p);
      file->mapped_ = true;
    }
  }
  if (!file->mapped_) {  // e.g. a file system without mmap: read it instead
    file->owned_.resize(file->size_);
    for (uint64_t done = 0; done < file->size_;) {
      const ssize_t got = ::read(f.fd, file->owned_.data() + done, file->size_ - done);
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) io_error(path, "cannot read");
      if (got == 0) fail(path, "file shrank while being read");
      done += uint64_t(got);
    }
    file->data_ = file->owned_.data();
  }
  file->parse(path);
  // Validation read every page once; a server holds a model's pages only as its modes come to read them
  // again (they fault back in from the page cache), not the whole file from the start.
  if (file->mapped_) ::madvise(const_cast<uint8_t*>(file->data_), file->size_, MADV_DONTNEED);
  return file;
}

std::unique_ptr<PmsFile> PmsFile::from_bytes(const std::string& name, const uint8_t* data, size_t size) {
  std::unique_ptr<PmsFile> file(new PmsFile());
  file->owned_.assign(data, data + size);  // new[] alignment (max_align_t) covers every section type
  file->data_ = file->owned_.data();
  file->size_ = size;
  file->parse(name);
  return file;
}

PmsFile::~PmsFile() {
  if (mapped_) ::munmap(const_cast<uint8_t*>(data_), size_);
}

void PmsFile::parse(const std::string& name) {
  const SectionMap sections = locate_sections(name, data_, size_);  // checked the header and its checksum
  std::memcpy(&content_checksum_, data_ + offsetof(FileHeader, header_checksum), sizeof content_checksum_);
  const HeadSection head = read_head(name, sections);
  check_counts(name, sections, head);
  model_ = make_model(sections, head);
  validate_model(name, model_, tree_id_, node_id_);
  model_.tree_id = tree_id_;
  model_.node_id = node_id_;
  if (sections[SplitOffsets].count != uint64_t(head.node_count) + 1)
    section_error(name, SplitOffsets,
                  str(sections[SplitOffsets].count) + " elements for " + str(head.node_count) + " nodes");
  split_tables_ = {sections[SplitTables].data, size_t(sections[SplitTables].count)};
  split_offsets_ = typed<uint64_t>(sections[SplitOffsets], 1);
  split_records_ = {sections[SplitRecords].data, size_t(sections[SplitRecords].count)};
  split_codec_ = check_records(name, model_, split_tables_, split_offsets_, split_records_);
  if (sections[Meta].present)
    stats_ = stats_from_json(name, {reinterpret_cast<const char*>(sections[Meta].data), size_t(sections[Meta].count)});
}

}  // namespace pms
