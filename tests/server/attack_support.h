// What the attack tests (attack_test.cpp, issue 14) need around a real server: `pmstream serve --json` as a
// child process watched only from outside (its JSON lines, its CPU time in /proc, how long SIGTERM takes),
// raw peers on loopback that misbehave on purpose, OPEN frames with hand-written resume codes the encoder
// would refuse, and a good client that flies a path and keeps each frame's latency.
// Every wait has a deadline: a server that hangs fails the test instead of hanging it.
#pragma once
#include <utility>  // before asio with C++20

#include <sys/types.h>
#include <boost/asio.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/camera.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "streaming_fixture.h"

namespace pms::test {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

inline Clock::time_point after(milliseconds wait) { return Clock::now() + wait; }
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// ---- the server as a child process ---------------------------------------------------------------------

class ServerProcess {
 public:
  // Runs `pmstream serve MODEL --host 127.0.0.1 --port 0 --json FLAGS...` and waits for its "listening"
  // line; pms::Error when it exits or stays silent instead.
  ServerProcess(const std::string& model_path, const std::vector<std::string>& flags);
  ~ServerProcess();  // kills a child that is still running
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  uint16_t port() const { return port_; }
  // SIGUSR1, then the "stats" line it prints; pms::Error when none comes within two seconds.
  nlohmann::json stats();
  // Asks for stats until sessions_active is `count` or `within` has passed; returns the last count seen.
  uint64_t wait_for_sessions(uint64_t count, milliseconds within);
  // The child's user + system CPU time so far (/proc/PID/stat).
  double cpu_seconds() const;
  // Samples the CPU time until some whole second used under `idle` of one core, or `within` passes;
  // returns that second's use, or the lowest second seen.
  double wait_for_idle(double idle, milliseconds within);

  struct Exit {
    double seconds = 0;                     // SIGTERM to exit
    bool exited = false;                    // by itself, within the patience given (else killed)
    int exit_code = -1;                     // when it exited normally
    std::optional<nlohmann::json> stopped;  // its "stopped" line
  };
  // SIGTERM, then waits up to `patience` (longer than the deadline under test, to say by how much it
  // missed it) before SIGKILL.
  Exit terminate(milliseconds patience);

 private:
  std::optional<nlohmann::json> next_event(const std::string& event, Clock::time_point deadline);

  pid_t pid_ = -1;
  int out_ = -1;  // the read end of the child's stdout
  std::string pending_;
  uint16_t port_ = 0;
};

// ---- raw peers -----------------------------------------------------------------------------------------

// One client that speaks raw bytes over a non-blocking socket, so that it can stop reading, drip, cut a frame
// or reset whenever a test likes; every wait takes a deadline.
class Peer {
 public:
  // A receive buffer set before connecting keeps the TCP window small (a peer that hardly reads).
  explicit Peer(uint16_t port, int receive_buffer = 0);

  // All of `bytes`, unless the connection fails (false) or the deadline passes (false).
  bool send(std::span<const uint8_t> bytes, Clock::time_point deadline);
  // All of `bytes` while handing each frame that arrives meanwhile to `on_frame`, reading every `pause` (a
  // slow reader) or as soon as anything comes; false when the connection ends or the deadline passes first.
  bool send_reading(std::span<const uint8_t> bytes, const std::function<void(const protocol::Frame&)>& on_frame,
                    Clock::time_point deadline, milliseconds pause = milliseconds(0));
  // One byte every `interval`, reading what arrives meanwhile; false once the server has closed.
  bool drip(std::span<const uint8_t> bytes, milliseconds interval);
  // The next frame; nullopt when the connection ends or the deadline passes (closed() says which).
  std::optional<protocol::Frame> receive(Clock::time_point deadline);
  // Hands each frame that arrives to `done` until it returns true (then true), or the connection ends or the
  // deadline passes (false).
  bool read_until(const std::function<bool(const protocol::Frame&)>& done, Clock::time_point deadline);
  // Reads (and drops) until the server ends the connection; false when the deadline passes first.
  bool wait_closed(Clock::time_point deadline);
  // Closes at once with an RST (SO_LINGER 0), as a crashing client does.
  void abort();

  bool closed() const { return closed_; }
  // The ERROR codes read so far, in order.
  const std::vector<protocol::ErrorCode>& errors() const { return errors_; }

 private:
  ptrdiff_t send_some(std::span<const uint8_t> bytes);  // what the socket takes now; -1 once it is gone
  bool wait_for(short events, Clock::time_point deadline);
  bool read_available();

  boost::asio::ip::tcp::socket socket_;
  protocol::FrameReader reader_;
  std::vector<protocol::ErrorCode> errors_;
  bool closed_ = false;
};

std::vector<uint8_t> hello_frame();
std::vector<uint8_t> open_frame(const std::string& model);
std::vector<uint8_t> view_frame(const Camera& camera, float tolerance, uint32_t frame);
// Little-endian u32 length and a type: the five bytes that start a frame (to announce what never comes).
std::vector<uint8_t> frame_header(uint32_t length, uint8_t type);
void append(std::vector<uint8_t>& bytes, const std::vector<uint8_t>& more);
// Frames back to back, to go out in one write.
std::vector<uint8_t> joined(std::initializer_list<std::vector<uint8_t>> frames);
// `count` copies of `frame` back to back: a flood in one write.
std::vector<uint8_t> repeated(const std::vector<uint8_t>& frame, size_t count);

// ---- resume fronts by hand -----------------------------------------------------------------------------

// The preorder code of an OPEN's resume front (docs/protocol.md): 1 = split (both children follow), 0 = a
// listed leaf, tree after tree. Written bit by bit so a test can say what protocol::encode(Open) refuses.
struct FrontCode {
  explicit FrontCode(uint32_t announced_trees) : trees(announced_trees) {}
  uint32_t trees;  // the tree count the OPEN announces
  std::vector<bool> bits;

  FrontCode& leaves(size_t count);  // `count` trees (or subtrees) that are one listed leaf each
  // Splits along v_t children `depth` times and lists everything met: a chain down to depth `depth`.
  FrontCode& chain(int depth);
};
// OPEN{model, resume} with the code as given, padded to a byte, then `extra` bytes.
std::vector<uint8_t> open_with_front(const std::string& model, const FrontCode& front,
                                     const std::vector<uint8_t>& extra = {});

// ---- the good client -----------------------------------------------------------------------------------

struct Flight {
  std::vector<double> latency_ms;  // per frame that sent VIEW: VIEW out to its answer applied
  Faces mesh;                      // at the end of the path
  double seconds = 0;
};
// A fresh StreamingClient flies `path` at `tolerance`; pms::Error (or ConnectionError) if the server
// fails it, or keeps it waiting over 10 s for an answer.
Flight fly(uint16_t port, const std::string& model, const std::vector<Camera>& path, float tolerance);

// The nearest-rank percentile `p` (0..100); 0 for no samples.
double percentile(std::vector<double> samples, double p);

}  // namespace pms::test
