// Another process's CPU time, read from /proc as an operator's tools read it: the benches and the attack
// tests watch a server child from outside this way.
#pragma once
#include <sys/types.h>

namespace pms {

// User + system seconds of `pid` so far (/proc/PID/stat); 0 once it is gone.
double process_cpu_seconds(pid_t pid);

}  // namespace pms
