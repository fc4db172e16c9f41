// The pmstream binary links none of the libraries only the bench needs (issue 41): the codecs it compares
// against and fmt. Checked on the built binary, as the dynamic loader sees it.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "test_support.h"

namespace pms {
namespace {

// What `command` prints on stdout; empty if it cannot run.
std::string output_of(const std::string& command) {
  std::string text;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[4096];
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) text.append(buffer, n);
    pclose(pipe);
  }
  return text;
}

TEST(LinkedLibraries, PmstreamLinksNoneOfTheBenchsLibraries) {
  const std::string binary = PMSTREAM_BINARY;
  // The libraries pmstream asks for itself.
  const std::string needed = output_of("readelf -d " + binary + " 2>/dev/null");
  if (needed.empty()) GTEST_SKIP() << "readelf is not installed";
  ASSERT_NE(needed.find("(NEEDED)"), std::string::npos) << needed;
  // Every library the loader maps for it. Debian's libassimp itself needs libdraco, so libdraco may
  // appear there, but only through libassimp.
  const std::string loaded = output_of("ldd " + binary + " 2>/dev/null");
  ASSERT_NE(loaded.find("libc.so"), std::string::npos) << loaded;
  const std::string assimp_needs =
      output_of("ldd " + binary + " | grep -o '/[^ ]*libassimp[^ ]*' | xargs -r readelf -d");
  for (const char* library : {"libdraco", "libmeshoptimizer", "libzstd", "libfmt"}) {
    EXPECT_EQ(needed.find(library), std::string::npos) << binary << " needs " << library;
    if (std::string(library) == "libdraco" && assimp_needs.find(library) != std::string::npos) continue;
    EXPECT_EQ(loaded.find(library), std::string::npos) << binary << " loads " << library << ":\n" << loaded;
  }
}

}  // namespace
}  // namespace pms
