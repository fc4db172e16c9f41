#include "test_support.h"

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <mutex>
#include <vector>

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

namespace {

// The directories temp_dir() made in this process: removed when every test passed, kept (and named) when
// one failed or PMSTREAM_KEEP_TEST_DIRS is set, so that a failure can be looked into.
class TempDirs : public ::testing::EmptyTestEventListener {
 public:
  static TempDirs& instance() {
    static TempDirs* dirs = [] {
      auto* listener = new TempDirs;  // owned by gtest's listener list from here on
      ::testing::UnitTest::GetInstance()->listeners().Append(listener);
      return listener;
    }();
    return *dirs;
  }
  void add(const std::filesystem::path& dir) {
    std::lock_guard lock(mutex_);
    dirs_.push_back(dir);
  }
  void OnTestProgramEnd(const ::testing::UnitTest& unit) override {
    std::lock_guard lock(mutex_);
    if (unit.Passed() && !std::getenv("PMSTREAM_KEEP_TEST_DIRS")) {
      std::error_code ignored;
      for (const auto& dir : dirs_) std::filesystem::remove_all(dir, ignored);
    } else if (!dirs_.empty()) {
      std::fprintf(stderr, "test directories kept (%zu), e.g. %s\n", dirs_.size(), dirs_.front().c_str());
    }
    dirs_.clear();
  }

 private:
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};

}  // namespace

std::filesystem::path temp_dir() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "pmstream";
  std::replace(name.begin(), name.end(), '/', '_');  // parameterized tests: one directory, not a tree
  auto dir = std::filesystem::temp_directory_path() /
             ("pmstream-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++) + "-" + name);
  std::filesystem::create_directories(dir);
  TempDirs::instance().add(dir);
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
