// The streaming modes a session can be opened in, as OPEN names them and the CLI spells them.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace pms::protocol {

// sender_driven: kim-lee-kobbelt §5.3, the default: the server answers each VIEW with the splits the
// client's front needs, with refinement info, and the client refines on its own in between.
// view_independent: the baseline of kim-lee-kobbelt §8 (Fig. 9): the plain PM order, coarse to fine,
// without refinement info, until the prefix sent satisfies the client's view.
// sender_plain: kim-lee-kobbelt §6.3's variation of sender_driven (Fig. 10, middle column), for viewers that
// will not refine on their own: the same splits in the same order, but each packet names the cut vertices
// it has on the client's mesh (the active ancestors of the fundamental ones) and carries no refinement
// info; the client applies every split as it arrives and never coarsens. On the wire an option of the
// sender-driven mode (OPEN flag bit 2).
// dag: zheng-chan 2006 for a thin client: the server keeps the client's cut of the DAG of operations
// (dag/cut.h) and answers each DAG_VIEW with MANAGE-TRAVERSAL's collapses and splits, the splits with
// their geometry; the client applies them in order and evaluates nothing itself (OPEN flag bit 3).
enum class StreamMode : uint8_t { sender_driven, view_independent, sender_plain, dag };

// The CLI's name of a mode ("sender", "vi", "sender-plain", "dag"), and back; every name, comma-separated, for help
// texts.
const char* mode_name(StreamMode mode);
std::optional<StreamMode> mode_named(std::string_view name);
std::string mode_names();

}  // namespace pms::protocol
