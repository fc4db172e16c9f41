// The HTTP attack classes of http_attackers.h. Each attacker repeats its class's round until told to stop,
// on a fresh connection each round (the flood keeps its connections), paced so that ten of them are an
// attack on the server, not a contest with the good client for the machine's cores. The deadline a round
// must be ended by is the server's own for that class (docs/operating.md, "HTTP"), plus a slack for a
// loaded machine.
#include "bench/http_attackers.h"

#include <algorithm>
#include <memory>
#include <thread>

#include "bench/raw_http_peer.h"

namespace pms::bench {
namespace {

using std::chrono::milliseconds;

constexpr milliseconds kConnect(2000);
// The answers a server owes a bomb or a malformed request come without waiting for any deadline.
constexpr milliseconds kPromptly(1000);

AttackClock::time_point after(milliseconds wait) { return AttackClock::now() + wait; }

uint64_t ms_since(AttackClock::time_point start) {
  return uint64_t(std::chrono::duration_cast<milliseconds>(AttackClock::now() - start).count());
}

std::string address_of(int index) { return "127.0.0." + std::to_string(2 + index % 4); }

std::string request(const std::string& method, const std::string& target, const std::string& fields = "") {
  return method + " " + target + " HTTP/1.1\r\nHost: attack\r\n" + fields + "\r\n";
}

void raise_to(std::atomic<uint64_t>& value, uint64_t candidate) {
  for (uint64_t seen = value.load(); candidate > seen && !value.compare_exchange_weak(seen, candidate);) {
  }
}

// A 501 is the RFC's answer to a transfer coding the server does not know: the request's fault, like a 4xx.
void tally_answers(const RawHttpPeer& peer, AttackTally& tally) {
  for (const int status : peer.answers().statuses()) {
    tally.answers++;
    if (status < 400) tally.ok++;
    if (status == 503) tally.refused++;
    if ((status >= 400 && status < 500) || status == 501) tally.client_errors++;
    if (status >= 500 && status != 501 && status != 503) tally.server_errors++;
    if (status == 413) tally.statuses_413++;
    if (status == 414) tally.statuses_414++;
    if (status == 431) tally.statuses_431++;
  }
}

// A round the server must end within `deadline` of its start.
// `allowed`: the deadline the round had, with the target's slack.
void tally_end(const RawHttpPeer& peer, AttackClock::time_point start, milliseconds allowed, AttackTally& tally) {
  tally_answers(peer, tally);
  if (peer.ended()) {
    tally.closed++;
    if (peer.reset()) tally.resets++;
    raise_to(tally.longest_close_ms, ms_since(start));
  }
  if (!peer.ended() || ms_since(start) > uint64_t(allowed.count())) tally.late++;
}

// Connects from the attacker's address; nothing when the server would not take the connection.
std::unique_ptr<RawHttpPeer> connect(const AttackTarget& target, int index, AttackTally& tally, int receive_buffer = 0,
                                     bool head = false) {
  tally.rounds++;
  auto peer = std::make_unique<RawHttpPeer>(address_of(index), target.port, after(kConnect), receive_buffer, head);
  if (peer->connected()) return peer;
  tally.connect_failures++;
  return nullptr;
}

// ---- slow peers: each must be ended by its deadline, whatever it keeps sending or not reading ----

// `opening`, then `drip` a byte at a time, a twentieth of the request deadline apart, never completing the
// request: the request deadline ends it.
void drip_round(const AttackTarget& target, int index, AttackTally& tally, const std::string& opening,
                const std::string& drip) {
  const auto start = AttackClock::now();
  const auto peer = connect(target, index, tally);
  if (!peer) return;
  const milliseconds interval = std::max(milliseconds(10), target.request_timeout / 20);
  peer->send(opening, after(kConnect));
  const auto give_up = start + target.request_timeout + 2 * target.slack;
  for (size_t i = 0; !peer->ended() && AttackClock::now() < give_up; ++i) {
    peer->send(std::string_view(&drip[i % drip.size()], 1), after(interval));
    peer->read(after(interval));  // the pace of the drip: nothing comes until the server ends it
  }
  tally_end(*peer, start, target.request_timeout + target.slack, tally);
}

void slowloris(const AttackTarget& target, int index, AttackTally& tally) {
  drip_round(target, index, tally, "GET " + target.model + "/base HTTP/1.1\r\nHost: attack\r\n", "X-Drip: 42\r\n");
}

void dripped_body(const AttackTarget& target, int index, AttackTally& tally) {
  drip_round(target, index, tally, request("POST", target.model + "/splits", "Content-Length: 4000\r\n"), "A");
}

// Four BASEs through a 4 KiB window, a little read every twentieth of the write deadline: slow but steady, so
// the server keeps it, and it must cost the good client nothing.
void slow_reader(const AttackTarget& target, int index, const std::atomic<bool>& stop, AttackTally& tally) {
  constexpr size_t kAnswers = 4, kSip = 1024;
  const auto peer = connect(target, index, tally, 4096);
  if (!peer) return;
  std::string requests;
  for (size_t i = 0; i < kAnswers; ++i) requests += request("GET", target.model + "/base");
  peer->send(requests, after(kConnect));
  const milliseconds interval = std::max(milliseconds(10), target.write_timeout / 20);
  while (!stop && !peer->ended() && peer->answers().statuses().size() < kAnswers) {
    peer->read(after(interval), kSip);
    std::this_thread::sleep_for(interval);  // the reader's pace, not a wait for the server
  }
  tally_answers(*peer, tally);
  if (peer->ended()) tally.closed++;
}

// Answers that all fit the server's send buffer but not this peer's small window, never read: the server's
// writes all succeed, and only its kernel holds the bytes. The write deadline must reset it, not the idle
// deadline close it.
void unread_pipeline(const AttackTarget& target, int index, AttackTally& tally) {
  const auto start = AttackClock::now();
  const auto peer = connect(target, index, tally, 4096);
  if (!peer) return;
  std::string requests;
  for (uint32_t i = 0; i < target.unread_count; ++i) requests += request("GET", target.unread);
  peer->send(requests, after(kConnect));
  peer->wait_ended_unread(start + target.idle_timeout + 2 * target.slack);
  tally_end(*peer, start, target.write_timeout + target.slack, tally);
}

// ---- parsing, pipelining and expensive requests ----

// Each refused with a 4xx (or 501) at once, never a 5xx of the server's own.
std::vector<std::string> malformed_requests(const AttackTarget& target) {
  const std::string& m = target.model;
  return {
      request("BREW", "/models"),
      "GET /models HTTP/1.7\r\nHost: attack\r\n\r\n",
      request("GET", "models"),
      request("GET", m + "/splits/!!!!"),
      request("GET", m + "/splits/"),
      request("GET", m + "/blocks/99999999/1/2"),
      request("GET", m + "/blocks/0/2/2"),
      request("GET", "/models/no-such-model/base"),
      request("GET", "/models?x=1"),
      request("POST", m + "/splits", "Content-Length: 5\r\n") + "xxxxx",
      request("GET", m + "/base", "Content-Length: -1\r\n"),
      std::string("\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03\r\n\r\n", 15),
      "GET /models HTTP/1.1\r\nHost attack\r\n\r\n",
      "GET /models HTTP/1.1\r\n Host: attack\r\n\r\n",
  };
}

void malformed(const AttackTarget& target, int index, uint64_t round, AttackTally& tally) {
  const auto requests = malformed_requests(target);
  const auto start = AttackClock::now();
  const auto peer = connect(target, index, tally);
  if (!peer) return;
  peer->send(requests[round % requests.size()], after(kConnect));
  if (!peer->read_answers(1, after(kPromptly + target.slack))) tally.late++;
  tally_answers(*peer, tally);
  raise_to(tally.longest_close_ms, ms_since(start));
}

// A URL, a header and a body each over its limit: 414, 431 and 413 from the first bytes, at once.
void bombs(const AttackTarget& target, int index, uint64_t round, AttackTally& tally) {
  const auto start = AttackClock::now();
  const auto peer = connect(target, index, tally);
  if (!peer) return;
  constexpr size_t kBody = 100000;
  if (round % 3 == 0) peer->send(request("GET", "/" + std::string(5000, 'u')), after(kConnect));
  if (round % 3 == 1)
    peer->send(request("GET", "/models", "X-Bomb: " + std::string(12000, 'h') + "\r\n"), after(kConnect));
  if (round % 3 == 2)  // the server may close before it has taken the whole body
    peer->send(request("POST", target.model + "/splits", "Content-Length: " + std::to_string(kBody) + "\r\n") +
                   std::string(kBody, 'b'),
               after(kPromptly));
  if (!peer->read_answers(1, after(kPromptly + target.slack))) tally.late++;
  tally_answers(*peer, tally);
  raise_to(tally.longest_close_ms, ms_since(start));
}

// Sixteen of the most expensive requests the limits allow, pipelined, every answer read.
void expensive(const AttackTarget& target, int index, bool head, AttackTally& tally) {
  constexpr size_t kDepth = 16;
  const auto start = AttackClock::now();
  const auto peer = connect(target, index, tally, 0, head);
  if (!peer) return;
  std::string requests;
  for (size_t i = 0; i < kDepth; ++i) requests += request(head ? "HEAD" : "GET", target.expensive);
  peer->send(requests, after(kConnect));
  // Budgets slow these down by design; the write deadline bounds any one answer.
  // A connection refused over the per-address cap ends at once, with its 503.
  if (!peer->read_answers(kDepth, after(kDepth * (target.write_timeout + target.slack))) && !peer->ended()) tally.late++;
  tally_answers(*peer, tally);
  raise_to(tally.longest_close_ms, ms_since(start));
}

// A request whose framing is not a final chunked (RFC 9112 §6.1, §6.3), a whole request right behind it:
// the server must refuse the first and close, so the second is never read as a request of its own.
void smuggling(const AttackTarget& target, int index, uint64_t round, AttackTally& tally) {
  const std::string smuggled = request("GET", "/models");
  const std::string post = "POST " + target.model + "/splits HTTP/1.1\r\nHost: attack\r\n";
  const std::string variants[] = {
      post + "Transfer-Encoding: chunked, identity\r\n\r\n" + smuggled,
      post + "Transfer-Encoding: identity\r\nContent-Length: " + std::to_string(smuggled.size()) + "\r\n\r\n" +
          smuggled,
      post + "Transfer-Encoding: chunked\r\nTransfer-Encoding: identity\r\n\r\n" + smuggled,
  };
  const auto start = AttackClock::now();
  const auto peer = connect(target, index, tally);
  if (!peer) return;
  peer->send(variants[round % std::size(variants)], after(kConnect));
  peer->wait_closed(after(kPromptly + target.slack));
  const auto& statuses = peer->answers().statuses();
  if (statuses.size() > 1) tally.smuggled += statuses.size() - 1;
  if (!statuses.empty() && statuses[0] < 400) tally.smuggled++;  // the framing itself was taken
  tally_end(*peer, start, kPromptly + target.slack, tally);
}

// ---- connection floods ----

// Holds up to flood_connections connections, idle, and replaces each the server ends (refused over the
// per-address cap, or closed by the idle deadline) as soon as it sees it gone.
void connection_flood(const AttackTarget& target, int index, const std::atomic<bool>& stop, AttackTally& tally) {
  constexpr size_t kOpensPerPace = 2;
  std::vector<std::unique_ptr<RawHttpPeer>> held;
  auto finish = [&](RawHttpPeer& peer) {
    tally_answers(peer, tally);
    if (peer.ended()) tally.closed++;
  };
  while (!stop) {
    for (auto& peer : held) {
      peer->read(AttackClock::now());
      if (!peer->ended()) continue;
      finish(*peer);
      peer.reset();
    }
    std::erase(held, nullptr);
    for (size_t opened = 0; held.size() < target.flood_connections && opened < kOpensPerPace; ++opened)
      if (auto peer = connect(target, index, tally)) held.push_back(std::move(peer));
    std::this_thread::sleep_for(target.pace);
  }
  for (auto& peer : held) finish(*peer);
}

}  // namespace

const char* attack_class_name(AttackClass attack) {
  switch (attack) {
    case AttackClass::slowloris:
      return "slowloris";
    case AttackClass::dripped_body:
      return "dripped body";
    case AttackClass::slow_reader:
      return "slow reader";
    case AttackClass::unread_pipeline:
      return "unread pipeline";
    case AttackClass::malformed:
      return "malformed";
    case AttackClass::bombs:
      return "URL/header/body bombs";
    case AttackClass::expensive_pipeline:
      return "expensive pipeline";
    case AttackClass::expensive_head:
      return "expensive HEAD";
    case AttackClass::smuggling:
      return "smuggling";
    case AttackClass::connection_flood:
      return "connection flood";
  }
  return "?";
}

const std::vector<AttackGroup>& attack_groups() {
  static const std::vector<AttackGroup> groups = {
      {"slow peers",
       {AttackClass::slowloris, AttackClass::dripped_body, AttackClass::slow_reader, AttackClass::unread_pipeline}},
      {"parsing, pipelining, expensive requests",
       {AttackClass::malformed, AttackClass::bombs, AttackClass::expensive_pipeline, AttackClass::expensive_head,
        AttackClass::smuggling}},
      {"connection flood", {AttackClass::connection_flood}},
  };
  return groups;
}

void run_attacker(AttackClass attack, const AttackTarget& target, int index, const std::atomic<bool>& stop,
                  AttackTally& tally) {
  if (attack == AttackClass::connection_flood) return connection_flood(target, index, stop, tally);
  for (uint64_t round = uint64_t(index); !stop; ++round, std::this_thread::sleep_for(target.pace)) {
    switch (attack) {
      case AttackClass::slowloris:
        slowloris(target, index, tally);
        break;
      case AttackClass::dripped_body:
        dripped_body(target, index, tally);
        break;
      case AttackClass::slow_reader:
        slow_reader(target, index, stop, tally);
        break;
      case AttackClass::unread_pipeline:
        unread_pipeline(target, index, tally);
        break;
      case AttackClass::malformed:
        malformed(target, index, round, tally);
        break;
      case AttackClass::bombs:
        bombs(target, index, round, tally);
        break;
      case AttackClass::expensive_pipeline:
        expensive(target, index, false, tally);
        break;
      case AttackClass::expensive_head:
        expensive(target, index, true, tally);
        break;
      case AttackClass::smuggling:
        smuggling(target, index, round, tally);
        break;
      case AttackClass::connection_flood:
        break;
    }
  }
}

}  // namespace pms::bench
