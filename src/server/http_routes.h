// The receiver-driven mode's resources (cheng-ooi 2008): the routes of the HTTP transport as a pure
// function of the catalogue and one request, with no I/O, no Beast and no per-client state, so any number
// of server processes answer a URL with the same bytes. docs/protocol.md, "Receiver-driven over HTTP".
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "server/catalogue.h"
#include "server/limits.h"
#include "server/phase_times.h"

namespace pms::server {

struct HttpRequest {
  std::string_view method;  // "GET", "HEAD", "POST", ...
  std::string_view target;  // the request line's URL (origin form: starts with '/')
  std::span<const uint8_t> body;
  std::string_view if_none_match;  // the header's value; empty when absent
  PhaseTimes* phases = nullptr;     // the server's, when it profiles phases (HttpLimits::profile_phases)
};

// A body built a piece at a time by the transport, so that one large answer does not hold an I/O thread
// past its turn (docs/operating.md, "HTTP").
class BodyBuilder {
 public:
  virtual ~BodyBuilder() = default;
  // Builds on until the body is done (true) or `until` has passed (false: call again).
  virtual bool build(std::chrono::steady_clock::time_point until) = 0;
  virtual std::vector<uint8_t> take() = 0;
};

// How long a cache may use an answer without asking the origin (its Cache-Control).
enum class Caching : uint8_t {
  no_store,    // errors, redirects: not stored
  immutable,   // a versioned resource: its URL's bytes never change (max-age a year, immutable)
  max_age,     // GET /models: used for max_age_s, then revalidated (the model set changes)
  revalidate,  // revalidated on every use (the page's files: their names stay)
};

struct HttpAnswer {
  int status = 200;
  std::string_view content_type = "text/plain; charset=utf-8";  // a literal
  std::string etag;                                             // strong, quoted; empty for errors
  Caching caching = Caching::no_store;
  uint32_t max_age_s = 0;  // Caching::max_age's
  std::string allow;                                            // the methods a 405's resource takes
  std::string location;                                         // a redirect's target: the canonical URL
  uint64_t splits = 0;                                          // split records in the body
  bool split_resource = false;  // an answer of /splits or /blocks (200 or 304): what a cache saves the origin
  // The body: bytes shared with the catalogue (BASE), from an offset, or its own.
  std::shared_ptr<const std::vector<uint8_t>> shared;
  size_t shared_offset = 0;
  std::vector<uint8_t> owned;
  // Set when `owned` is still to be built (a 200 of split records): body() is empty until finish_body().
  std::shared_ptr<BodyBuilder> builder;
  // Set with a 503 when the resource needs tables of the model that are not built yet: the transport
  // waits for them (under the request deadline) and routes the request again, or sends the 503 then.
  const ServedModel* waits_for = nullptr;
  ServedMode waits_for_mode = ServedMode::receiver;

  std::span<const uint8_t> body() const {
    return shared ? std::span<const uint8_t>(*shared).subspan(shared_offset) : std::span<const uint8_t>(owned);
  }
};

// The answer to one request: 200, 304 (If-None-Match matched), or a 4xx with a short text body (a 410,
// a model version this server does not serve, with the model's catalogue entry in JSON).
HttpAnswer route(const Catalogue& catalogue, const HttpLimits& limits, const HttpRequest& request);

// Builds `answer`'s body to the end, in one go, if it has a builder.
void finish_body(HttpAnswer& answer);

// A 4xx or 5xx with `text` (and a newline) as its body.
HttpAnswer error_answer(int status, const std::string& text);

// Blocks a client should ask for (GET /models lists it): subtrees of this many levels below the node.
// Clients behind one cache share blocks only when they use the same depth; docs/protocol.md says why 2.
constexpr uint32_t kSuggestedBlockDepth = 2;

}  // namespace pms::server
