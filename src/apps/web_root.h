// Where the browser viewer's assembled site is by default: `web/` beside the pmstream executable (the build
// puts build/web beside build/pmstream; docs/web.md).
#pragma once
#include <string>

namespace pms::app {

std::string default_web_root();

}  // namespace pms::app
