// The message of the pms::Error a call throws, or "" when it throws none: what tests of hostile input
// compare against the exact message they expect.
#pragma once
#include <functional>
#include <string>

#include "common/error.h"

namespace pms::test {

inline std::string error_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace pms::test
