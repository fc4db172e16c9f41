#include "test_support.h"

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <unistd.h>

namespace pms::test {

std::filesystem::path shared_models_dir() {
  if (const char* env = std::getenv("PMSTREAM_SHARED_DIR")) {
    std::filesystem::path dir = std::filesystem::path(env) / "models";
    if (std::filesystem::is_directory(dir)) return dir;
  }
  std::filesystem::path dir = std::filesystem::path(PMSTREAM_SHARED_DIR) / "models";
  if (std::filesystem::is_directory(dir)) return dir;
  return {};
}

std::filesystem::path shared_model(const std::string& file) {
  const auto dir = shared_models_dir();
  if (dir.empty()) return {};
  auto path = dir / file;
  return std::filesystem::exists(path) ? path : std::filesystem::path{};
}

std::filesystem::path temp_dir() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "pmstream";
  auto dir = std::filesystem::temp_directory_path() /
             ("pmstream-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++) + "-" + name);
  std::filesystem::create_directories(dir);
  return dir;
}

CliRun run_pmstream(const std::string& args) {
  const auto dir = temp_dir();
  const std::string out = (dir / "stdout").string(), err = (dir / "stderr").string();
  const std::string command = std::string(PMSTREAM_BINARY) + " " + args + " >" + out + " 2>" + err;
  const int status = std::system(command.c_str());
  auto slurp = [](const std::string& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

}  // namespace pms::test
