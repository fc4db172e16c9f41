// The pmstream binary the bench runs as a child for its builds and servers.
#pragma once
#include <string>

namespace pms::bench {

// `explicit_path` (--pmstream) if given, else the `pmstream` beside this program; the absolute path of an
// executable file, or pms::Error saying where it looked.
std::string locate_pmstream(const std::string& explicit_path);

}  // namespace pms::bench
