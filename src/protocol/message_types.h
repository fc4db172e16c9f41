// The wire's vocabulary (docs/protocol.md): version, message types, error codes and the error every
// decoder throws. Every message is  u32 LE payload length | u8 MessageType | payload.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/error.h"
#include "spm/position_grid.h"

namespace pms::protocol {

// Version 6: a sender-driven session gets CODEC after BASE, and its VSPLITS packets are v_s's id and the
// compact split record (v_t's normal and color included); in the full packets (view-independent, plain,
// DAG_OPS) a node with mu = delta = 0 sends its refinement info as one flag bit. Version 7 is version 6 and
// AHEAD, with the VSPLITS that answer it (flag bit 1): a server speaks both, and a session greeted with 6
// is one that never asks ahead (AHEAD there is out_of_order). A server answers any other version with
// unsupported_version: each earlier one codes the packets differently.
constexpr uint16_t kProtocolVersion = 7;
constexpr uint16_t kMinProtocolVersion = 6;
constexpr char kMagic[4] = {'P', 'M', 'S', 'T'};
constexpr size_t kFrameHeaderBytes = 5;                 // u32 payload length + u8 type
constexpr uint32_t kDefaultMaxMessage = 16u << 20;      // payload bytes a reader accepts by default
constexpr size_t kMaxNameBytes = 1024;                  // model, client and server names
constexpr uint64_t kDefaultMaxResumeLeaves = 1u << 22;  // OPEN: leaves a resume front may list
// VSPLITS and DAG_OPS: packets in one message (a server batches at most `serve --batch`, <= this). What bounds a
// client's memory per message when split records can be as short as their ids (docs/protocol.md, "Limits").
constexpr uint32_t kMaxPacketsPerMessage = 1u << 16;
using pms::kDefaultPositionBits;

// Client -> server types have the high bit clear, server -> client set.
enum class MessageType : uint8_t {
  hello = 0x01,
  list = 0x02,
  open = 0x03,
  view = 0x04,
  close = 0x05,
  dag_view = 0x06,
  ahead = 0x07,
  hello_ok = 0x81,
  catalogue = 0x82,
  base = 0x83,
  vsplits = 0x84,
  error = 0x85,
  dag_ops = 0x86,
  codec = 0x87,
};
std::string to_string(MessageType type);  // "VSPLITS", or "type 0x42" for an unknown byte

enum class ErrorCode : uint16_t {
  bad_message = 1,          // malformed framing or payload
  unsupported_version = 2,  // HELLO with a version the server does not speak
  unknown_model = 3,        // OPEN of a name not in the catalogue
  bad_id = 4,               // a vertex id outside the model (tree, depth or node)
  too_large = 5,            // a frame over the receiver's limit
  out_of_order = 6,         // a message the session's state does not allow yet (VIEW before OPEN)
  server_full = 7,
  timeout = 8,
  internal = 9,
};
std::string to_string(ErrorCode code);  // "bad_message", or "code 42" for a value this build does not know

// What every decoder and the frame reader throw; `code` is the ERROR to answer with.
struct ProtocolError : Error {
  ErrorCode code;
  ProtocolError(ErrorCode c, const std::string& what) : Error(what), code(c) {}
};

}  // namespace pms::protocol
