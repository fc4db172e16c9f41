// The HTTP attack classes (docs/architecture.md, "Experiments": the attacks group), one function each,
// every attacker a thread working from its own loopback address until told to stop. What each class does
// and what the server should do about it is beside its function in http_attackers.cpp; what the attackers
// saw is tallied per class, for the test and the report to read.
#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace pms::bench {

enum class AttackClass : uint8_t {
  slowloris,           // headers dripped a byte at a time
  dripped_body,        // a POST body dripped a byte at a time
  slow_reader,         // answers read a little at a time through a small window
  unread_pipeline,     // requests pipelined, answers that fit the kernel's buffers never read
  malformed,           // requests the parser or the routes refuse
  bombs,               // URL, header and body over their limits
  expensive_pipeline,  // 16 pipelined GETs of the most expensive split request the limits allow
  expensive_head,      // the same as HEAD
  smuggling,           // Transfer-Encoding other than a final chunked, a smuggled request behind it
  connection_flood,    // one host taking every connection slot it can, and again as they free
};

const char* attack_class_name(AttackClass attack);

// The three groups of classes run one after the other, each group's classes at once: slow peers; parsing,
// pipelining and expensive requests; connection floods.
struct AttackGroup {
  const char* name;
  std::vector<AttackClass> classes;
};
const std::vector<AttackGroup>& attack_groups();

// Where the attackers aim and how hard.
struct AttackTarget {
  uint16_t port = 0;      // the server's HTTP port
  std::string model;      // its escaped path and version: "/models/terrain/0123456789abcdef"
  std::string expensive;  // the most expensive split request's URL (http_attack_targets.h)
  std::string unread;     // a URL whose answers, `unread_count` of them, fit the server's send buffer
  uint32_t unread_count = 16;
  std::chrono::milliseconds request_timeout{10000}, write_timeout{10000}, idle_timeout{30000};  // the server's
  std::chrono::milliseconds pace{5};  // between an attacker's rounds
  // How long past a deadline (or past "at once") the server may end a round and still be on time: what a
  // loaded machine's scheduling adds. A sanitizer build's server runs several times slower.
  std::chrono::milliseconds slack{1500};
  uint32_t flood_connections = 100;   // connections one flooding attacker keeps open
};

// What the attackers of one class saw, summed over its threads.
struct AttackTally {
  std::atomic<uint64_t> rounds{0}, connect_failures{0};
  std::atomic<uint64_t> answers{0}, ok{0}, client_errors{0}, refused{0}, server_errors{0};  // 503s are refused
  std::atomic<uint64_t> closed{0}, resets{0};  // connections the server ended, and of those with an RST
  std::atomic<uint64_t> longest_close_ms{0};   // a round's start to the server's end of it, the longest
  std::atomic<uint64_t> late{0};               // rounds the server did not end within the class's deadline
  std::atomic<uint64_t> smuggled{0};           // answers to requests hidden behind a refused framing
  std::atomic<uint64_t> statuses_413{0}, statuses_414{0}, statuses_431{0};
};

// The attacker `index` (its address 127.0.0.(2 + index % 4)) of class `attack`, until `stop`.
void run_attacker(AttackClass attack, const AttackTarget& target, int index, const std::atomic<bool>& stop,
                  AttackTally& tally);

}  // namespace pms::bench
