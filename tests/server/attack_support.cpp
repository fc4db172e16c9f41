// The server child process, raw peers, hand-coded fronts and the good client (attack_support.h).
#include "attack_support.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <thread>

#include "client/streaming_client.h"
#include "common/error.h"
#include "common/process_cpu.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"

extern char** environ;

namespace pms::test {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

int milliseconds_left(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now()).count();
  return int(std::clamp<long long>(left, 0, 60000));
}

// Sockets only make synchronous calls, so one io_context that never runs serves every peer of the process.
asio::io_context& sockets() {
  static asio::io_context io;
  return io;
}

void append_le(std::vector<uint8_t>& out, uint64_t value, int bytes) {
  for (int k = 0; k < bytes; ++k) out.push_back(uint8_t(value >> (8 * k)));
}

bool connection_gone(const boost::system::error_code& ec) {
  return ec && ec != asio::error::would_block && ec != asio::error::try_again && ec != asio::error::interrupted;
}

}  // namespace

// ---- ServerProcess -------------------------------------------------------------------------------------

ServerProcess::ServerProcess(const std::string& model_path, const std::vector<std::string>& flags) {
  std::vector<std::string> args = {PMSTREAM_BINARY, "serve",  model_path, "--host",
                                   "127.0.0.1",     "--port", "0",        "--json"};
  args.insert(args.end(), flags.begin(), flags.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  int out[2];
  if (pipe2(out, O_CLOEXEC) != 0) fail("pipe2", std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  // The server sets up its own signals; it must not inherit a mask or an ignored disposition from the test.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  for (int s : {SIGPIPE, SIGINT, SIGTERM, SIGUSR1}) sigaddset(&defaults, s);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  const int spawned = posix_spawn(&pid_, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  ::close(out[1]);
  out_ = out[0];
  if (spawned != 0) {
    pid_ = -1;
    fail(PMSTREAM_BINARY, std::string("cannot start: ") + std::strerror(spawned));
  }
  const std::optional<nlohmann::json> listening = next_event("listening", after(milliseconds(30000)));
  if (!listening) fail("pmstream serve", "no \"listening\" line (unknown option, or it failed: see its stderr)");
  port_ = listening->at("port").get<uint16_t>();
}

ServerProcess::~ServerProcess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  if (out_ >= 0) ::close(out_);
}

std::optional<nlohmann::json> ServerProcess::next_event(const std::string& event, Clock::time_point deadline) {
  for (;;) {
    for (size_t end; (end = pending_.find('\n')) != std::string::npos;) {
      const nlohmann::json line = nlohmann::json::parse(pending_.substr(0, end), nullptr, false);
      pending_.erase(0, end + 1);
      if (line.is_object() && line.value("event", "") == event) return line;
    }
    pollfd fd{out_, POLLIN, 0};
    const int ready = ::poll(&fd, 1, milliseconds_left(deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) return std::nullopt;
    char buffer[4096];
    const ssize_t got = ::read(out_, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return std::nullopt;  // the child closed its stdout: it is gone
    pending_.append(buffer, size_t(got));
  }
}

nlohmann::json ServerProcess::stats() {
  if (pid_ <= 0 || ::kill(pid_, SIGUSR1) != 0) fail("pmstream serve", "not running");
  std::optional<nlohmann::json> line = next_event("stats", after(milliseconds(2000)));
  if (!line) fail("pmstream serve", "no \"stats\" line within 2 s of SIGUSR1");
  return *line;
}

uint64_t ServerProcess::wait_for_sessions(uint64_t count, milliseconds within) {
  const Clock::time_point deadline = after(within);
  for (;;) {
    const uint64_t active = stats().at("sessions_active").get<uint64_t>();
    if (active == count || Clock::now() >= deadline) return active;
    std::this_thread::sleep_for(milliseconds(50));
  }
}

double ServerProcess::cpu_seconds() const {
  if (pid_ <= 0) fail("pmstream serve", "not running");
  return process_cpu_seconds(pid_);
}

double ServerProcess::wait_for_idle(double idle, milliseconds within) {
  const Clock::time_point deadline = after(within);
  std::deque<std::pair<Clock::time_point, double>> samples{{Clock::now(), cpu_seconds()}};
  double lowest = 1e9;
  while (Clock::now() < deadline) {
    std::this_thread::sleep_for(milliseconds(100));
    samples.emplace_back(Clock::now(), cpu_seconds());
    // The newest sample at least a second older than this one starts the window.
    while (samples.size() > 2 && samples.back().first - samples[1].first >= std::chrono::seconds(1))
      samples.pop_front();
    const double wall = std::chrono::duration<double>(samples.back().first - samples.front().first).count();
    if (wall < 1) continue;
    const double use = (samples.back().second - samples.front().second) / wall;
    lowest = std::min(lowest, use);
    if (use < idle) return use;
  }
  return lowest;
}

ServerProcess::Exit ServerProcess::terminate(milliseconds patience) {
  Exit exit;
  const Clock::time_point start = Clock::now();
  ::kill(pid_, SIGTERM);
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(pid_, &status, WNOHANG);
    if (done == pid_) {
      exit.exited = true;
      break;
    }
    if (Clock::now() - start > patience) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      break;
    }
    std::this_thread::sleep_for(milliseconds(2));
  }
  exit.seconds = seconds_since(start);
  pid_ = -1;
  if (WIFEXITED(status)) exit.exit_code = WEXITSTATUS(status);
  exit.stopped = next_event("stopped", after(milliseconds(1000)));  // what it wrote before it went
  return exit;
}

// ---- Peer ----------------------------------------------------------------------------------------------

Peer::Peer(uint16_t port, int receive_buffer) : socket_(sockets()) {
  socket_.open(tcp::v4());
  if (receive_buffer > 0) socket_.set_option(asio::socket_base::receive_buffer_size(receive_buffer));
  socket_.connect({asio::ip::make_address("127.0.0.1"), port});
  socket_.non_blocking(true);
}

bool Peer::wait_for(short events, Clock::time_point deadline) {
  for (;;) {
    pollfd fd{socket_.native_handle(), events, 0};
    const int ready = ::poll(&fd, 1, milliseconds_left(deadline));
    if (ready < 0 && errno == EINTR) continue;
    return ready > 0;
  }
}

ptrdiff_t Peer::send_some(std::span<const uint8_t> bytes) {
  if (closed_) return -1;
  boost::system::error_code ec;
  const size_t n = socket_.write_some(asio::buffer(bytes.data(), bytes.size()), ec);
  if (connection_gone(ec)) {
    closed_ = true;
    return -1;
  }
  return ptrdiff_t(n);
}

bool Peer::send(std::span<const uint8_t> bytes, Clock::time_point deadline) {
  while (!bytes.empty()) {
    const ptrdiff_t n = send_some(bytes);
    if (n < 0) return false;
    bytes = bytes.subspan(size_t(n));
    if (!bytes.empty() && !wait_for(POLLOUT, deadline)) return false;
  }
  return true;
}

bool Peer::send_reading(std::span<const uint8_t> bytes, const std::function<void(const protocol::Frame&)>& on_frame,
                        Clock::time_point deadline, milliseconds pause) {
  while (!bytes.empty()) {
    const ptrdiff_t n = send_some(bytes);
    if (n < 0 || Clock::now() >= deadline) return false;
    bytes = bytes.subspan(size_t(n));
    if (pause.count() > 0) std::this_thread::sleep_for(pause);
    // Neither side moved: wait a little for either, rather than spin.
    const bool idle = n == 0 && pause.count() == 0 && !wait_for(POLLIN | POLLOUT, after(milliseconds(10)));
    if (idle) continue;
    while (auto frame = receive(Clock::now())) on_frame(*frame);
  }
  return true;
}

// Everything the socket holds now into the frame reader; false once the connection has ended.
bool Peer::read_available() {
  std::array<uint8_t, 1 << 16> buffer;
  for (;;) {
    boost::system::error_code ec;
    const size_t n = socket_.read_some(asio::buffer(buffer), ec);
    if (connection_gone(ec)) {
      closed_ = true;
      return false;
    }
    if (ec) return true;  // would block: all read
    reader_.feed(buffer.data(), n);
  }
}

std::optional<protocol::Frame> Peer::receive(Clock::time_point deadline) {
  for (;;) {
    protocol::Frame frame;
    if (reader_.next(frame)) {
      if (frame.type == protocol::MessageType::error) errors_.push_back(protocol::decode_error(frame.payload).code);
      return frame;
    }
    if (closed_ || !wait_for(POLLIN, deadline)) return std::nullopt;
    read_available();  // frames that came before an end of stream are still handed out
  }
}

bool Peer::read_until(const std::function<bool(const protocol::Frame&)>& done, Clock::time_point deadline) {
  while (auto frame = receive(deadline))
    if (done(*frame)) return true;
  return false;
}

bool Peer::wait_closed(Clock::time_point deadline) {
  while (receive(deadline)) {
  }  // the frames that came before the end count (an ERROR, most of all)
  return closed_;
}

bool Peer::drip(std::span<const uint8_t> bytes, milliseconds interval) {
  for (uint8_t byte : bytes) {
    if (send_some({&byte, 1}) != 1) return false;
    const Clock::time_point next = after(interval);
    while (receive(next)) {
    }  // an ERROR may come meanwhile
    if (closed_) return false;
  }
  return true;
}

void Peer::abort() {
  boost::system::error_code ignored;
  socket_.set_option(asio::socket_base::linger(true, 0), ignored);
  socket_.close(ignored);
  closed_ = true;
}

std::vector<uint8_t> hello_frame() { return protocol::encode(protocol::Hello{protocol::kProtocolVersion, "attack"}); }

std::vector<uint8_t> open_frame(const std::string& model) { return protocol::encode(protocol::Open{model, {}}); }

std::vector<uint8_t> view_frame(const Camera& camera, float tolerance, uint32_t frame) {
  return protocol::encode(protocol::View{camera, tolerance, frame});
}

std::vector<uint8_t> frame_header(uint32_t length, uint8_t type) {
  std::vector<uint8_t> header;
  append_le(header, length, 4);
  header.push_back(type);
  return header;
}

void append(std::vector<uint8_t>& bytes, const std::vector<uint8_t>& more) {
  bytes.insert(bytes.end(), more.begin(), more.end());
}

std::vector<uint8_t> joined(std::initializer_list<std::vector<uint8_t>> frames) {
  std::vector<uint8_t> out;
  for (const std::vector<uint8_t>& frame : frames) append(out, frame);
  return out;
}

std::vector<uint8_t> repeated(const std::vector<uint8_t>& frame, size_t count) {
  std::vector<uint8_t> out;
  out.reserve(frame.size() * count);
  for (size_t i = 0; i < count; ++i) append(out, frame);
  return out;
}

// ---- FrontCode -----------------------------------------------------------------------------------------

FrontCode& FrontCode::leaves(size_t count) {
  bits.insert(bits.end(), count, false);
  return *this;
}

FrontCode& FrontCode::chain(int depth) {
  bits.insert(bits.end(), size_t(depth), true);       // split v_t's line down to `depth`,
  bits.insert(bits.end(), size_t(depth) + 1, false);  // then its last v_t and every v_u, deepest first
  return *this;
}

std::vector<uint8_t> open_with_front(const std::string& model, const FrontCode& front,
                                     const std::vector<uint8_t>& extra) {
  std::vector<uint8_t> frame(protocol::kFrameHeaderBytes);  // written once the payload's length is known
  append_le(frame, model.size(), 2);
  for (char c : model) frame.push_back(uint8_t(c));  // (a range insert here trips GCC 12's -Wstringop-overflow)
  frame.push_back(1);                                // flags: a resume front follows
  append_le(frame, front.trees, 4);
  const size_t start = frame.size();
  frame.resize(start + (front.bits.size() + 7) / 8, 0);
  for (size_t i = 0; i < front.bits.size(); ++i)  // LSB first: bit i is bit i % 8 of byte i / 8
    if (front.bits[i]) frame[start + i / 8] |= uint8_t(1u << (i % 8));
  append(frame, extra);
  const std::vector<uint8_t> header =
      frame_header(uint32_t(frame.size() - protocol::kFrameHeaderBytes), uint8_t(protocol::MessageType::open));
  std::copy(header.begin(), header.end(), frame.begin());
  return frame;
}

// ---- the good client -----------------------------------------------------------------------------------

Flight fly(uint16_t port, const std::string& model, const std::vector<Camera>& path, float tolerance) {
  const Clock::time_point start = Clock::now();
  client::ClientOptions options{tolerance};
  options.answer_timeout = milliseconds(10000);
  client::StreamingClient client("127.0.0.1", port, options);
  client.open(model);
  Flight flight;
  for (const Camera& camera : path) {
    const client::FrameReport report = client.frame(camera);
    if (report.requested) flight.latency_ms.push_back(report.latency_ms);
  }
  flight.mesh = faces_by_id(client.session().mesh());
  flight.seconds = seconds_since(start);
  return flight;
}

double percentile(std::vector<double> samples, double p) {
  if (samples.empty()) return 0;
  std::sort(samples.begin(), samples.end());
  const size_t rank = size_t(std::ceil(p / 100 * double(samples.size())));
  return samples[std::clamp<size_t>(rank, 1, samples.size()) - 1];
}

}  // namespace pms::test
