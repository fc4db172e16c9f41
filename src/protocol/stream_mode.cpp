#include "protocol/stream_mode.h"

namespace pms::protocol {
namespace {

struct NamedMode {
  StreamMode mode;
  const char* name;
};
constexpr NamedMode kModes[] = {
    {StreamMode::sender_driven, "sender"},
    {StreamMode::view_independent, "vi"},
    {StreamMode::sender_plain, "sender-plain"},
    {StreamMode::dag, "dag"},
};

}  // namespace

const char* mode_name(StreamMode mode) {
  for (const NamedMode& m : kModes)
    if (m.mode == mode) return m.name;
  return "unknown";
}

std::optional<StreamMode> mode_named(std::string_view name) {
  for (const NamedMode& m : kModes)
    if (name == m.name) return m.mode;
  return std::nullopt;
}

std::string mode_names() {
  std::string names;
  for (const NamedMode& m : kModes) {
    if (!names.empty()) names += ", ";
    names += m.name;
  }
  return names;
}

}  // namespace pms::protocol
