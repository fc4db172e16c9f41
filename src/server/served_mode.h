// The modes a served model builds tables for, as `stream --mode` and `serve --preload` spell them: the
// four TCP modes OPEN names, and the two HTTP ones (receiver-driven records, multilevel levels).
#pragma once
#include <bitset>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "protocol/stream_mode.h"

namespace pms::server {

enum class ServedMode : uint8_t { sender, sender_plain, view_independent, dag, receiver, multilevel };
constexpr size_t kServedModeCount = 6;

// A set of modes, one bit per ServedMode.
using ModeSet = std::bitset<kServedModeCount>;

const char* served_mode_name(ServedMode mode);  // "sender", "sender-plain", "vi", "dag", "receiver", "multilevel"
std::optional<ServedMode> served_mode_named(std::string_view name);
ServedMode served_mode_of(protocol::StreamMode mode);
inline size_t index_of(ServedMode mode) { return size_t(mode); }
inline ServedMode served_mode_at(size_t index) { return ServedMode(index); }

ModeSet all_modes();
// What a catalogue opened without options builds at once: every mode but the multilevel derivation, the
// tables every in-process user of a Session or the routes expects.
ModeSet streaming_modes();
// "all", or mode names separated by commas; pms::Error naming `option` for an unknown or empty name.
ModeSet parse_modes(std::string_view list, const std::string& option);

}  // namespace pms::server
