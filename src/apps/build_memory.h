// The builder's memory tuning: on while a build runs, off for everything that serves.
#pragma once

namespace pms::app {

// What the process does once its build is done, which decides how far the build may tune malloc.
enum class AfterBuild {
  kExit,   // `build`, `multilevel build`: the process only builds
  kServe,  // `demo`: a server and a client run in the same process afterwards
};

// The builder's memory tuning (why: build_pipeline.cpp) while this object lives: blocks of 2 MiB and more on
// huge pages (the binary's operator new, large_allocations.cpp), glibc's heap never trimmed, grown by a
// large pad on huge pages, and for kExit one malloc arena for every thread. A server must not inherit it:
// its memory is sessions that come and go, where a heap that keeps what they freed and 2 MiB pages for
// every big block only raise its resident size. So it is off unless a builder asks, and for kServe it asks
// only for what can be undone (glibc fixes its arena limit the first time it reads it) and undoes it here.
class BuildMemoryTuning {
 public:
  explicit BuildMemoryTuning(AfterBuild after);
  ~BuildMemoryTuning();
  BuildMemoryTuning(const BuildMemoryTuning&) = delete;
  BuildMemoryTuning& operator=(const BuildMemoryTuning&) = delete;

 private:
  AfterBuild after_;
};

// Read by the binary's operator new (large_allocations.cpp): true while a BuildMemoryTuning lives.
bool large_blocks_on_huge_pages();

}  // namespace pms::app
