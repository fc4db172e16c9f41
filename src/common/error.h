// One exception type for every user-facing failure: the CLI prints what() as the single error line.
#pragma once
#include <stdexcept>
#include <string>

namespace pms {

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "FILE: problem" — every error that concerns a file names it first.
[[noreturn]] inline void fail(const std::string& where, const std::string& what) {
  throw Error(where.empty() ? what : where + ": " + what);
}

}  // namespace pms
