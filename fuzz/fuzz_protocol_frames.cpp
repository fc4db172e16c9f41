// libFuzzer target for the frame reader and the two direction dispatchers (docs/architecture.md,
// "Correctness properties", 5): a byte stream cut into chunks (sizes from the input) must frame exactly as
// it would in one piece, frames never exceed the limit, and every frame decodes or throws ProtocolError. A
// BASE that decodes becomes the context of later VSPLITS, as in a client session; an OPEN before it in
// view-independent mode takes the refinement info out of that context.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"

namespace {

using namespace pms::protocol;

void check(bool condition) {
  if (!condition) __builtin_trap();
}

struct Outcome {
  std::vector<Frame> frames;
  bool failed = false;
  bool mid_frame = false;
};

// Feeds `stream` in chunks whose sizes come from `chunks` (cycled; 0 = the whole rest).
Outcome read_frames(const uint8_t* stream, size_t size, uint32_t limit, const uint8_t* chunks, size_t chunk_count) {
  Outcome out;
  FrameReader reader(limit);
  size_t at = 0, k = 0;
  try {
    while (at < size) {
      size_t take = chunk_count == 0 ? size - at : chunks[k++ % chunk_count];
      if (take == 0 || take > size - at) take = size - at;
      reader.feed(stream + at, take);
      at += take;
      Frame frame;
      while (reader.next(frame)) {
        check(frame.payload.size() <= limit);
        out.frames.push_back(std::move(frame));
      }
    }
  } catch (const ProtocolError& e) {
    check(e.code == ErrorCode::too_large && reader.failed() && reader.ready() == 0);
    out.failed = true;
  }
  out.mid_frame = reader.mid_frame();
  return out;
}

void decode_frames(const std::vector<Frame>& frames) {
  std::optional<StreamContext> context;
  bool has_refinement = true;
  for (const Frame& frame : frames) {
    try {
      if (uint8_t(frame.type) & 0x80) {
        const ServerMessage message = decode_server_message(frame, context ? &*context : nullptr);
        if (const Base* base = std::get_if<Base>(&message)) {
          context = stream_context(*base);
          context->has_refinement = has_refinement;
        }
      } else {
        const ClientMessage message = decode_client_message(frame, 1u << 16);
        if (const Open* open = std::get_if<Open>(&message)) has_refinement = open->mode == StreamMode::sender_driven;
      }
    } catch (const ProtocolError&) {
    }
  }
}

}  // namespace

// Input: u8 chunk-table size n, n chunk sizes, u16 limit (in units of 16 bytes), then the stream.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const size_t chunk_count = std::min<size_t>(data[0], size - 3);
  const uint8_t* chunks = data + 1;
  const uint8_t* rest = data + 1 + chunk_count;
  const uint32_t limit = 16u * (uint32_t(rest[0]) | uint32_t(rest[1]) << 8);
  const uint8_t* stream = rest + 2;
  const size_t stream_size = size - (stream - data);

  const Outcome chunked = read_frames(stream, stream_size, limit, chunks, chunk_count);
  const Outcome whole = read_frames(stream, stream_size, limit, nullptr, 0);
  // Chunking never changes what is framed.
  check(chunked.failed == whole.failed && chunked.frames.size() == whole.frames.size());
  for (size_t i = 0; i < whole.frames.size(); ++i)
    check(chunked.frames[i].type == whole.frames[i].type && chunked.frames[i].payload == whole.frames[i].payload);
  check(chunked.mid_frame == whole.mid_frame);
  decode_frames(whole.frames);
  return 0;
}
