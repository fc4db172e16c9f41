// Runs another program and measures it: wall time and the child's own rusage from wait4(2).
// The bench runs every build (ours and OpenMesh's) as a child so each peak RSS belongs to that
// build alone. Caveat: Linux keeps the pre-exec high-water mark, so a child's ru_maxrss is at least
// what it inherited from this process at fork; the bench stays small to keep that floor low.
#pragma once
#include <sys/types.h>
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace pms::bench {

struct ChildOptions {
  double timeout_seconds = 0;                    // 0: no limit; else SIGKILL once this much wall time has passed
  std::string stdout_path;                       // when set, stdout goes to this file instead of being captured
  size_t max_captured_bytes = size_t(16) << 20;  // per stream; the rest is read and dropped
  // Called in the parent once the child runs, with its pid: a long-running child (a server) can be
  // signalled from another thread while run_child waits for it.
  std::function<void(pid_t)> on_start;
  // Called with each piece of stdout as it arrives (it is captured as well), on the thread that runs
  // run_child: a caller can act on a line (a server's "listening") while the child keeps running.
  std::function<void(std::string_view)> on_stdout;
  // "NAME=VALUE" entries the child gets on top of this process's environment (a NAME given here
  // replaces the inherited one): what a configuration file reads as "${NAME}" (HAProxy's).
  std::vector<std::string> environment;
};

struct ChildResult {
  int exit_code = -1;       // valid when term_signal == 0
  int term_signal = 0;      // the signal that ended it, 0 when it exited
  bool timed_out = false;   // killed by us after ChildOptions::timeout_seconds
  std::string out, err;     // captured stdout (unless redirected) and stderr
  double wall_seconds = 0;  // fork to reap
  double user_seconds = 0, system_seconds = 0;
  double peak_rss_mb = 0;  // ru_maxrss

  bool ok() const { return !timed_out && term_signal == 0 && exit_code == 0; }
  // "exit code 2", "killed by signal 11 (Segmentation fault)", "timed out after 60 s", plus the last
  // line of stderr when there is one: the one line a report shows for a failed step.
  std::string failure() const;
};

// The executable `name` resolves to, searched on PATH like a shell does (a name with a '/' is taken
// as is); empty when there is no such executable.
std::string find_program(const std::string& name);

// Runs argv (argv[0] resolved with find_program) with stdin from /dev/null and waits for it.
// Throws pms::Error when the program cannot be started; a child that fails is reported in the result.
ChildResult run_child(const std::vector<std::string>& argv, const ChildOptions& options = {});

}  // namespace pms::bench
