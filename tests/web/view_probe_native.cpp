// The native side of tests/web/wasm_view_math.mjs: web/view_probe.h's cases as raw floats on stdin, their
// outputs as raw floats on stdout, evaluated by the native build's code (glibc's libm beside ours).
#include <cstdio>
#include <vector>

#include "web/view_probe.h"

int main() {
  std::vector<float> in(pms::web::kProbeInputs), out(pms::web::kProbeOutputs);
  while (std::fread(in.data(), sizeof(float), in.size(), stdin) == in.size()) {
    pms::web::probe_view_math(in.data(), out.data());
    if (std::fwrite(out.data(), sizeof(float), out.size(), stdout) != out.size()) return 1;
  }
  return 0;
}
