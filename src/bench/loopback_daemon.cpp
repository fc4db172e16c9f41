#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include "bench/loopback_daemon.h"

#include <boost/asio.hpp>
#include <chrono>
#include <fstream>
#include <iterator>

#include "common/error.h"

namespace pms::bench {
namespace fs = std::filesystem;

std::string file_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string find_daemon(const std::string& name) {
  const std::string found = find_program(name);
  return found.empty() ? find_program("/usr/sbin/" + name) : found;
}

uint16_t free_loopback_port() {
  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor acceptor(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
  return acceptor.local_endpoint().port();
}

bool accepts_connections(uint16_t port) {
  boost::asio::io_context io;
  boost::asio::ip::tcp::socket socket(io);
  boost::system::error_code ec;
  socket.connect({boost::asio::ip::make_address("127.0.0.1"), port}, ec);
  return !ec;
}

LoopbackDaemon::LoopbackDaemon(std::string what, std::function<DaemonStart()> prepare, fs::path log_file,
                               int stop_signal)
    : what_(std::move(what)), log_file_(std::move(log_file)), stop_signal_(stop_signal) {
  options_.timeout_seconds = 900;  // a hung test is stopped by ctest's timeout first
  options_.on_start = [this](pid_t pid) { pid_ = pid; };
  for (int attempt = 0; attempt < 3 && !start(prepare()); ++attempt) stop();
  if (!running_) {
    std::string why = run_.failure().empty() ? "its port never took a connection" : run_.failure();
    fail(what_, "did not start: " + why + "\n" + run_.err + file_text(log_file_));
  }
}

LoopbackDaemon::~LoopbackDaemon() { stop(); }

bool LoopbackDaemon::start(const DaemonStart& start) {
  exited_ = false;
  options_.environment = start.environment;
  thread_ = std::thread([this, argv = start.argv] {
    try {
      run_ = run_child(argv, options_);
    } catch (const Error& e) {  // not started at all: said where the constructor fails
      run_.err = e.what();
    }
    exited_ = true;
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!exited_ && std::chrono::steady_clock::now() < deadline) {
    if (accepts_connections(start.ready_port)) return running_ = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

void LoopbackDaemon::stop() {
  if (pid_ > 0 && !exited_) ::kill(pid_, stop_signal_);
  if (thread_.joinable()) thread_.join();
  pid_ = 0;
  running_ = false;
}

}  // namespace pms::bench
