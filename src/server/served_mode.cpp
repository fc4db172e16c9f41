#include "server/served_mode.h"

#include "common/error.h"

namespace pms::server {
namespace {

constexpr const char* kNames[kServedModeCount] = {"sender", "sender-plain", "vi", "dag", "receiver", "multilevel"};

}  // namespace

const char* served_mode_name(ServedMode mode) { return kNames[index_of(mode)]; }

std::optional<ServedMode> served_mode_named(std::string_view name) {
  for (size_t i = 0; i < kServedModeCount; ++i)
    if (name == kNames[i]) return served_mode_at(i);
  return std::nullopt;
}

ServedMode served_mode_of(protocol::StreamMode mode) {
  switch (mode) {
    case protocol::StreamMode::sender_driven:
      return ServedMode::sender;
    case protocol::StreamMode::sender_plain:
      return ServedMode::sender_plain;
    case protocol::StreamMode::view_independent:
      return ServedMode::view_independent;
    case protocol::StreamMode::dag:
      return ServedMode::dag;
  }
  return ServedMode::sender;
}

ModeSet all_modes() { return ModeSet().set(); }

ModeSet streaming_modes() { return all_modes().reset(index_of(ServedMode::multilevel)); }

ModeSet parse_modes(std::string_view list, const std::string& option) {
  if (list == "all") return all_modes();
  ModeSet modes;
  std::string known;
  for (const char* name : kNames) {
    if (!known.empty()) known += ", ";
    known += name;
  }
  for (size_t at = 0; at <= list.size();) {
    const size_t comma = std::min(list.find(',', at), list.size());
    const std::string_view name = list.substr(at, comma - at);
    const std::optional<ServedMode> mode = served_mode_named(name);
    if (!mode) {
      std::string why = "'";
      why.append(name).append("' is not a mode (all, or some of: ").append(known).append(")");
      fail(option, why);
    }
    modes.set(index_of(*mode));
    at = comma + 1;
  }
  return modes;
}

}  // namespace pms::server
