// Multilevel files on disk: either form read whole (bounded by the limits), written through PATH.tmp and a
// rename so that a failed write leaves an existing file untouched.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/error.h"
#include "multilevel/file.h"

namespace pms {

MultilevelMesh read_multilevel(const std::string& path, const MultilevelLimits& limits) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory");
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) fail(path, std::string("cannot open: ") + std::strerror(errno));
  const std::streamoff end = file.tellg();
  if (end < 0) fail(path, "cannot read (not a regular file?)");
  const auto size = uint64_t(end);
  if (size > limits.max_file_bytes) fail(path, "larger than " + std::to_string(limits.max_file_bytes) + " bytes");
  std::vector<uint8_t> bytes(size);
  file.seekg(0);
  if (!file.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size))) fail(path, "read failed");
  if (is_multilevel_binary(bytes)) return parse_multilevel_binary(path, bytes, limits);
  return parse_multilevel_ascii(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                                limits);
}

void write_multilevel(const std::string& path, const MultilevelMesh& mesh, bool ascii) {
  std::vector<uint8_t> binary;
  std::string text;
  if (ascii) text = format_multilevel_ascii(mesh);
  else binary = format_multilevel_binary(mesh);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) fail(path, "cannot create " + tmp);
    if (ascii) out.write(text.data(), std::streamsize(text.size()));
    else out.write(reinterpret_cast<const char*>(binary.data()), std::streamsize(binary.size()));
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      fail(path, "cannot write " + tmp);
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    fail(path, "cannot rename " + tmp + " over it");
  }
}

}  // namespace pms
