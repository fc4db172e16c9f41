// Shared helpers for tests: where ../shared/models is, and skipping cleanly when it is not there.
#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace pms::test {

// A sanitizer build runs 2-10x slower and unevenly so, which makes latency ratios between two runs
// measure the instrumentation, not the code: such bounds are asserted in the release run only.
#ifdef PMSTREAM_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

// ../shared/models next to the checkout, or empty when this clone has no ../shared.
std::filesystem::path shared_models_dir();

// Path of a model in ../shared/models (e.g. "bunny.ply.xz"); empty when absent.
std::filesystem::path shared_model(const std::string& file);

// A fresh directory under the system temp dir, unique per test; removed at the end of the test program
// when every test passed (kept when one failed, or with PMSTREAM_KEEP_TEST_DIRS set).
std::filesystem::path temp_dir();

// Runs the pmstream binary (PMSTREAM_BINARY) with `args` (shell words) and captures both streams.
struct CliRun {
  int exit_code;  // -1 when it did not exit normally
  std::string out, err;
};
CliRun run_pmstream(const std::string& args);

}  // namespace pms::test

// Skips the test with a clear message when the shared model is not available (a user's fresh clone).
#define PMS_REQUIRE_SHARED_MODEL(var, file)         \
  const auto var = ::pms::test::shared_model(file); \
  if (var.empty())                                  \
  GTEST_SKIP() << "../shared/models/" << (file)     \
               << " not found: this test needs "    \
                  "the shared test meshes (CI has them beside the checkout)"
