#include "bench/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <utility>

#include "apps/resource_usage.h"
#include "common/error.h"

namespace pms::bench {
using app::Stopwatch;
namespace {

// A file descriptor closed when it goes out of scope, so no error path leaks one.
class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  Fd(Fd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Fd& operator=(Fd&& other) noexcept {
    reset(std::exchange(other.fd_, -1));
    return *this;
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  int get() const { return fd_; }
  void reset(int fd = -1) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }

 private:
  int fd_ = -1;
};

struct Pipe {
  Fd read, write;
};

std::string errno_text(const char* call) { return std::string(call) + ": " + std::strerror(errno); }

// Close-on-exec, so a child only keeps the ends it dup2()s onto 0, 1 and 2.
Pipe make_pipe(const std::string& program) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) fail(program, errno_text("pipe2"));
  return {Fd(fds[0]), Fd(fds[1])};
}

bool is_executable_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

// This process's environment with `extra`'s entries in place of the inherited ones of the same names,
// built before fork: the child may not allocate.
std::vector<char*> child_environment(const std::vector<std::string>& extra) {
  std::vector<char*> env;
  for (const std::string& entry : extra) env.push_back(const_cast<char*>(entry.c_str()));
  const auto overridden = [&extra](std::string_view inherited) {
    const std::string_view name = inherited.substr(0, inherited.find('='));
    for (const std::string& entry : extra)
      if (std::string_view(entry).substr(0, entry.find('=')) == name) return true;
    return false;
  };
  for (char** e = environ; *e; ++e)
    if (!overridden(*e)) env.push_back(*e);
  env.push_back(nullptr);
  return env;
}

// Runs in the forked child: only async-signal-safe calls until execve. If anything fails, errno
// goes back through `report` (closed by a successful exec) so the parent can name the problem.
[[noreturn]] void exec_child(const char* program, char* const* argv, char* const* env, int in, int out, int err,
                             int report) {
  if (::dup2(in, STDIN_FILENO) >= 0 && ::dup2(out, STDOUT_FILENO) >= 0 && ::dup2(err, STDERR_FILENO) >= 0)
    ::execve(program, argv, env);
  const int error = errno;
  [[maybe_unused]] const ssize_t written = ::write(report, &error, sizeof error);
  ::_exit(127);
}

// Reads whatever the child writes until both pipes close; false when the deadline passed first.
bool drain(Fd& out, Fd& err, ChildResult& result, const ChildOptions& options, const Stopwatch& clock) {
  char buffer[1 << 16];
  while (out.get() >= 0 || err.get() >= 0) {
    pollfd fds[2];
    Fd* owners[2];
    std::string* sinks[2];
    int count = 0;
    for (auto [fd, sink] : {std::pair{&out, &result.out}, std::pair{&err, &result.err}}) {
      if (fd->get() < 0) continue;
      fds[count] = {fd->get(), POLLIN, 0};
      owners[count] = fd;
      sinks[count] = sink;
      ++count;
    }
    int wait_ms = -1;
    if (options.timeout_seconds > 0) {
      const double left = options.timeout_seconds - clock.seconds();
      if (left <= 0) return false;
      wait_ms = int(std::min(std::ceil(left * 1000), double(INT_MAX)));
    }
    if (::poll(fds, nfds_t(count), wait_ms) < 0) {
      if (errno == EINTR) continue;
      fail("poll", std::strerror(errno));
    }
    for (int i = 0; i < count; ++i) {
      if (fds[i].revents == 0) continue;
      const ssize_t got = ::read(fds[i].fd, buffer, sizeof buffer);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        owners[i]->reset();
        continue;
      }
      std::string& sink = *sinks[i];
      if (&sink == &result.out && options.on_stdout) options.on_stdout(std::string_view(buffer, size_t(got)));
      if (sink.size() < options.max_captured_bytes)
        sink.append(buffer, std::min(size_t(got), options.max_captured_bytes - sink.size()));
    }
  }
  return true;
}

}  // namespace

std::string ChildResult::failure() const {
  char what[96];
  if (timed_out) std::snprintf(what, sizeof what, "timed out after %.0f s", wall_seconds);
  else if (term_signal != 0)
    std::snprintf(what, sizeof what, "killed by signal %d (%s)", term_signal, strsignal(term_signal));
  else if (exit_code != 0) std::snprintf(what, sizeof what, "exit code %d", exit_code);
  else return "";
  // The last non-empty line of stderr is where our CLI and most tools say why.
  const size_t end = err.find_last_not_of("\r\n");
  if (end == std::string::npos) return what;
  const size_t newline = err.find_last_of('\n', end);
  const size_t begin = newline == std::string::npos ? 0 : newline + 1;
  return std::string(what) + ": " + err.substr(begin, end + 1 - begin);
}

std::string find_program(const std::string& name) {
  if (name.empty()) return {};
  if (name.find('/') != std::string::npos) return is_executable_file(name) ? name : std::string();
  const char* env = std::getenv("PATH");
  const std::string path = env ? env : "/usr/local/bin:/usr/bin:/bin";
  size_t begin = 0;
  while (begin <= path.size()) {
    size_t end = path.find(':', begin);
    if (end == std::string::npos) end = path.size();
    const std::string dir = end == begin ? "." : path.substr(begin, end - begin);  // "::" means "."
    const std::string candidate = dir + "/" + name;
    if (is_executable_file(candidate)) return candidate;
    begin = end + 1;
  }
  return {};
}

ChildResult run_child(const std::vector<std::string>& argv, const ChildOptions& options) {
  if (argv.empty()) fail("run_child", "no program given");
  const std::string& name = argv[0];
  const std::string program = find_program(name);
  if (program.empty()) fail(name, "no such executable (searched PATH)");
  std::vector<char*> args;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  const std::vector<char*> env = child_environment(options.environment);

  Fd in(::open("/dev/null", O_RDONLY | O_CLOEXEC));
  if (in.get() < 0) fail("/dev/null", std::strerror(errno));
  Fd out_file;
  Pipe out;
  if (!options.stdout_path.empty()) {
    out_file = Fd(::open(options.stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
    if (out_file.get() < 0) fail(options.stdout_path, std::strerror(errno));
  } else {
    out = make_pipe(name);
  }
  Pipe err = make_pipe(name);
  Pipe report = make_pipe(name);

  ChildResult result;
  const Stopwatch clock;
  const pid_t pid = ::fork();
  if (pid < 0) fail(name, errno_text("fork"));
  if (pid == 0)
    exec_child(program.c_str(), args.data(), env.data(), in.get(),
               out_file.get() >= 0 ? out_file.get() : out.write.get(), err.write.get(), report.write.get());

  // Drop the child's ends: end of file on a pipe then means the child (and anything it started) is done with it.
  in.reset();
  out_file.reset();
  out.write.reset();
  err.write.reset();
  report.write.reset();

  int exec_error = 0;
  ssize_t got;
  do {
    got = ::read(report.read.get(), &exec_error, sizeof exec_error);
  } while (got < 0 && errno == EINTR);
  const bool started = got != ssize_t(sizeof exec_error);
  if (started && options.on_start) options.on_start(pid);

  if (started && !drain(out.read, err.read, result, options, clock)) {
    ::kill(pid, SIGKILL);
    result.timed_out = true;
  }
  int status = 0;
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0)
    if (errno != EINTR) fail(name, errno_text("wait4"));
  if (!started) fail(name, "cannot run " + program + ": " + std::strerror(exec_error));

  result.wall_seconds = clock.seconds();
  if (WIFSIGNALED(status)) result.term_signal = WTERMSIG(status);
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  result.user_seconds = double(usage.ru_utime.tv_sec) + double(usage.ru_utime.tv_usec) * 1e-6;
  result.system_seconds = double(usage.ru_stime.tv_sec) + double(usage.ru_stime.tv_usec) * 1e-6;
  result.peak_rss_mb = double(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
  return result;
}

}  // namespace pms::bench
