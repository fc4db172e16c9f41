#include "bench/pmstream_binary.h"

#include <unistd.h>

#include <filesystem>

#include "common/error.h"

namespace pms::bench {
namespace fs = std::filesystem;

std::string locate_pmstream(const std::string& explicit_path) {
  fs::path path = explicit_path;
  if (path.empty()) {
    std::error_code error;
    const fs::path self = fs::read_symlink("/proc/self/exe", error);
    if (error)
      fail("/proc/self/exe", "cannot find this program's directory (" + error.message() + "); give --pmstream PATH");
    path = self.parent_path() / "pmstream";
  }
  std::error_code error;
  const fs::path absolute = fs::absolute(path, error).lexically_normal();
  const std::string where = explicit_path.empty()
                                ? " beside pmstream-bench (build the pmstream target, or give --pmstream PATH)"
                                : " (--pmstream)";
  if (error || !fs::is_regular_file(absolute, error)) fail(absolute.string(), "no pmstream binary here" + where);
  if (::access(absolute.c_str(), X_OK) != 0) fail(absolute.string(), "not executable" + where);
  return absolute.string();
}

}  // namespace pms::bench
