// The bounds a server puts on its peers, with their defaults (docs/operating.md).
#pragma once
#include <cstddef>
#include <cstdint>

#include "protocol/message_types.h"
#include "protocol/position_grid.h"
#include "server/client_address.h"

namespace pms::server {

// Every bound the server puts on a peer (docs/operating.md says what each one protects against).
struct ServerLimits {
  uint32_t max_sessions = 1000;
  uint32_t max_client_message = 4u << 20;                      // a resume front of millions of leaves is ~2 bits each
  uint32_t max_server_message = protocol::kDefaultMaxMessage;  // BASE, CATALOGUE and VSPLITS; checked at start
  size_t send_queue_bytes = 64u << 10;                         // back-pressure: no new batch while more than this waits
  size_t send_burst_bytes = 1u << 20;     // sent at once by one handler before other sessions get a turn
  uint32_t batch_splits = 1024;           // vsplit packets per VSPLITS message
  uint32_t slice_work = 2048;             // nodes evaluated or split per Session::pump() call
  uint32_t turn_us = 1000;                // one session's turn on an I/O thread before others get theirs
  uint32_t max_message_rate = 500;        // messages a session may send per second (bursts of as many); 0 = any
  uint32_t idle_timeout_ms = 120000;      // no message in and no answer byte out for this long: closed
  uint32_t handshake_timeout_ms = 10000;  // HELLO and OPEN must be done within this of connecting
  uint32_t frame_timeout_ms = 10000;      // a frame, once begun, must arrive whole within this
  uint32_t write_timeout_ms = 10000;      // answer bytes waiting and none taken for this long: closed
  uint32_t accept_backoff_ms = 1000;      // longest pause after a failed accept (EMFILE...), doubling from 10 ms
  uint32_t position_bits = protocol::kDefaultPositionBits;
  uint32_t threads = 0;  // I/O threads; 0 = one per core
  // A sender-driven session holds its front coded (compact_front.h) once it has had no message for
  // park_after_ms (0: after every answer), or as windowed active tags throughout (kim-lee-kobbelt §6.1; the
  // bench's baseline). Coding and decoding cost a pass over the front each: a flying session, which sends
  // a VIEW a frame, keeps its tags; an idle one, most of a real fleet, holds about two bits a node.
  bool compact_fronts = true;
  uint32_t park_after_ms = 1000;
  // kim-lee-kobbelt §9's idle time: the bytes a sender-driven session may send ahead (AHEAD's answers) over
  // its life, at most one batch over; 0: AHEAD is taken and never answered.
  uint32_t ahead_budget_bytes = 1u << 20;
  bool profile_phases = false;  // time the sessions' work by cheng-ooi's Table 1 phases (phase_times.h)
};

// Every bound the HTTP transport (receiver-driven mode) puts on a peer (docs/operating.md, "HTTP").
struct HttpLimits {
  uint32_t max_connections = 1000;       // more are answered 503 and closed
  uint32_t max_connections_per_address = 32;  // one client address's at once (a trusted proxy's: any)
  uint32_t address_budget = 1000000;     // work units a second per client address (burst: as many); 0 = any
  uint32_t connection_budget = 500000;   // work units a second per connection (burst: as many); 0 = any
  uint32_t turn_us = 1000;               // one connection's turn on an I/O thread before others get theirs
  uint32_t send_buffer_bytes = 128u << 10;    // SO_SNDBUF asked per connection (Linux doubles it)
  uint32_t receive_buffer_bytes = 32u << 10;  // SO_RCVBUF asked per connection (Linux doubles it)
  uint32_t max_target_bytes = 4096;      // the request line's URL: 414 over it (larger codes are POSTed)
  uint32_t max_header_bytes = 8192;      // the request line (414 over it), and the fields (431)
  uint32_t max_body_bytes = 16384;       // a POSTed request code: 413 over it
  uint32_t max_request_ids = 4096;       // ids in one request code: 413 over it
  uint32_t max_request_depth = 8;        // a request's descendant depth: 400 over it
  uint32_t max_response_splits = 65536;  // split records in one answer (ids and their descendants): 413
  uint32_t idle_timeout_ms = 30000;      // keep-alive: no request begun for this long: closed
  uint32_t request_timeout_ms = 10000;   // a request, once begun, must arrive whole within this
  uint32_t write_timeout_ms = 10000;     // answer bytes waiting and none taken for this long: closed
  uint32_t threads = 0;                  // I/O threads; 0 = one per core
  uint32_t catalogue_max_age_s = 60;     // GET /models: how long a cache may use it unasked (0: ask each time)
  // Peers whose X-Forwarded-For names the client the per-address limits apply to (--trusted-proxy).
  AddressRanges trusted_proxies;
  bool profile_phases = false;  // time the answers' work by cheng-ooi's Table 1 phases (phase_times.h)
};

// The most the kernel holds for the HTTP connections' socket buffers: Linux doubles what SO_SNDBUF and
// SO_RCVBUF ask for (its bookkeeping), for each of max_connections (docs/operating.md, "HTTP").
inline uint64_t http_socket_buffer_bound(const HttpLimits& limits) {
  return uint64_t(limits.max_connections) * 2 * (uint64_t(limits.send_buffer_bytes) + limits.receive_buffer_bytes);
}

}  // namespace pms::server
