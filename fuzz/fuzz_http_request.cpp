// libFuzzer target for the HTTP request path (docs/architecture.md, "Correctness properties", 5): bytes go
// through Beast's request parser under the server's limits, then the routes over a real catalogue, then
// the response head, as many pipelined requests as the bytes hold. Input byte 0 picks the form: raw
// HTTP bytes, or the rest as a request code sent as GET /models/terrain/splits/BASE64 and as POST (so the
// fuzzer reaches the code paths without having to invent base64). Every answer must be a 2xx, 304, a
// redirect with its Location, 4xx or 501 whose body stays within the limits' bound; nothing may crash,
// hang or throw.
#include <unistd.h>
#include <cstddef>
#include <cstdint>
#include <string>

#include "protocol/base64url.h"
#include "server/catalogue.h"
#include "server/http_message.h"
#include "server/limits.h"
#include "terrain_catalogue.h"

namespace {

using namespace pms;
using namespace pms::server;

void check(bool condition) {
  if (!condition) __builtin_trap();
}

struct Fixture {
  std::shared_ptr<const Catalogue> catalogue;
  HttpLimits limits;
  size_t body_bound = 0;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture f;
    f.limits.max_request_ids = 64;
    f.limits.max_response_splits = 256;
    f.catalogue = fuzz_model::terrain_catalogue("http");
    // A vsplit packet is under 1024 bits; BASE and the catalogue are what they are.
    f.body_bound = std::max<size_t>(f.catalogue->find("terrain")->base_frame->size(),
                                    size_t(f.limits.max_response_splits) * 128 + 16) +
                   4096;
    return f;
  }();
  return f;
}

void check_answer(HttpAnswer answer, bool parsed) {
  finish_body(answer);
  const int s = answer.status;
  const bool redirect = s == 301 || s == 308;
  check(s == 200 || s == 304 || redirect || (s >= 400 && s < 500) || s == 501);
  check(parsed || s >= 400);
  check(redirect == !answer.location.empty());
  check(answer.body().size() <= fixture().body_bound);
  std::string head;
  write_response_head(answer, true, 11, head);  // every answer has a head, ending with an empty line
  check(head.starts_with("HTTP/1.1 ") && head.ends_with("\r\n\r\n"));
}

// Each request in `bytes` in turn, until the parser wants more than there is or refuses them.
void serve_bytes(std::string_view bytes) {
  const Fixture& f = fixture();
  for (int requests = 0; requests < 16 && !bytes.empty(); ++requests) {
    HttpParser parser;
    bound_parser(parser, f.limits);
    parser.eager(true);
    boost::beast::error_code ec;
    size_t used = 0;
    while (!parser.is_done() && used < bytes.size()) {
      const size_t n = parser.put(boost::asio::buffer(bytes.data() + used, bytes.size() - used), ec);
      used += n;
      if (ec == http::error::need_more) {
        if (n == 0) return;  // the rest would come in a later read
        ec = {};
        continue;
      }
      if (ec) return check_answer(parse_error_answer(ec, parser, bytes.substr(used), f.limits), false);
    }
    if (!parser.is_done()) return;
    if (const auto refusal = refuse_header(parser)) return check_answer(refusal->answer, false);  // and close
    check_answer(answer_request(*f.catalogue, f.limits, nullptr, parser.get()), true);
    bytes.remove_prefix(used);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  if (data[0] % 2 == 0) {
    serve_bytes(rest);
  } else {
    const std::string code = protocol::base64url_encode({data + 1, size - 1});
    serve_bytes("GET /models/terrain/splits/" + code +
                " HTTP/1.1\r\nHost: f\r\n\r\nPOST /models/terrain/splits "
                "HTTP/1.1\r\nHost: f\r\nContent-Length: " +
                std::to_string(size - 1) + "\r\n\r\n" + std::string(rest));
  }
  return 0;
}
