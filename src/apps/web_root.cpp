#include "apps/web_root.h"

#include <filesystem>
#include <system_error>

namespace pms::app {

std::string default_web_root() {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return "web";  // no /proc: beside the working directory
  return (exe.parent_path() / "web").string();
}

}  // namespace pms::app
