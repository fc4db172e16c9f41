#include "bench/e7_phases.h"

#include <algorithm>
#include <numeric>
#include <optional>

#include "bench/bench_refine.h"

namespace pms::bench {
using nlohmann::json;
using server::Phase;
namespace {

// cheng-ooi's Table 1 row by row, in seconds (Happy Buddha, both protocols after all its splits were
// received), and the phase of ours that stands for it. The sender-driven server codes each split's ids with
// its record once per model (protocol/packet_table.h): its "encode IDs" is part of search_splits' copy.
struct PaperRow {
  const char* name;
  std::optional<double> sender_s, receiver_s;  // none: the paper's "-" (not done by that sender)
  std::optional<Phase> ours;                   // none: "encode IDs" (in search) or "others" (the rest of the CPU)
};
constexpr PaperRow kPaperRows[] = {
    {"send base mesh", 1.40, 1.13, Phase::send_base},
    {"decode IDs", std::nullopt, 1.55, Phase::decode_ids},
    {"search vertex split", 1.85, 1.85, Phase::search_splits},
    {"determine visibility", 0.41, std::nullopt, Phase::determine_visibility},
    {"update vertex front", 1.41, std::nullopt, Phase::update_front},
    {"encode IDs", 0.94, std::nullopt, std::nullopt},
    {"others", 0.16, 0.16, std::nullopt},
};

double timed_ms(const PhaseCost& c) { return std::accumulate(c.phase_ms.begin(), c.phase_ms.end(), 0.0); }

// Our milliseconds for a paper row: its phase, "others" the CPU no phase timed, "encode IDs" none.
std::optional<double> ours_ms(const PaperRow& row, const PhaseCost& c) {
  if (row.ours) return c.phase_ms[size_t(*row.ours)];
  if (std::string(row.name) == "others") return std::max(0.0, c.cpu_ms - timed_ms(c));
  return std::nullopt;
}

std::string seconds(std::optional<double> s) { return s ? fixed(*s, 2) : "-"; }

std::string share(std::optional<double> part, double whole) {
  return part && whole > 0 ? fixed(100 * *part / whole, 1) + " %" : "";
}

double paper_total(bool sender) {
  double total = 0;
  for (const PaperRow& row : kPaperRows) total += (sender ? row.sender_s : row.receiver_s).value_or(0);
  return total;
}

}  // namespace

PhaseMs phase_ms_of(const json& phases) {
  PhaseMs ms{};
  for (size_t p = 0; p < ms.size(); ++p) ms[p] = phases.at(server::kPhaseNames[p]).get<double>();
  return ms;
}

Table e7_phase_table() {
  return Table({{"model", false},
                {"phase", false},
                {"paper sender s", true},
                {"paper receiver s", true},
                {"sender ms", true},
                {"sender share", true},
                {"receiver ms", true},
                {"receiver share", true}});
}

void add_e7_phase_rows(const std::string& model, const PhaseCost& sender, const PhaseCost& receiver, Table& table) {
  const auto cell = [](const PhaseCost& c, std::optional<double> ms) {
    return c.error.empty() && ms ? fixed(*ms, 2) : std::string(c.error.empty() ? "-" : "");
  };
  for (const PaperRow& row : kPaperRows) {
    const std::optional<double> s = ours_ms(row, sender), r = ours_ms(row, receiver);
    print_now(table.add_row({model, row.name, seconds(row.sender_s), seconds(row.receiver_s), cell(sender, s),
                         share(s, sender.cpu_ms), cell(receiver, r), share(r, receiver.cpu_ms)}));
  }
  const double paper_s = paper_total(true), paper_r = paper_total(false);
  print_now(table.add_row({model, "all (server CPU)", fixed(paper_s, 2), fixed(paper_r, 2),
                       sender.error.empty() ? fixed(sender.cpu_ms, 2) : "", "",
                       receiver.error.empty() ? fixed(receiver.cpu_ms, 2) : "",
                       sender.error.empty() && receiver.error.empty() && sender.cpu_ms > 0
                           ? "receiver / sender " + fixed(receiver.cpu_ms / sender.cpu_ms, 2) + " (paper " +
                                 fixed(paper_r / paper_s, 2) + ")"
                           : ""}));
}

json e7_phase_record(const PhaseCost& sender, const PhaseCost& receiver) {
  const auto record = [](const PhaseCost& c) {
    json phases = json::object();
    for (size_t p = 0; p < c.phase_ms.size(); ++p) phases[server::kPhaseNames[p]] = c.phase_ms[p];
    return json{{"cpu_ms", c.cpu_ms}, {"phases_ms", phases}, {"error", c.error}};
  };
  return {{"sender", record(sender)}, {"receiver", record(receiver)}};
}

std::string e7_phase_notes() {
  return "cheng-ooi's Table 1 row by row: the paper's seconds for Happy Buddha (Core 2 Duo, after every split was "
         "received) beside our servers' milliseconds and share of their CPU over E7's orbit, from flights of their "
         "own with `serve --profile-phases` (each phase timed on the I/O thread that runs it; "
         "docs/operating.md, \"The JSON lines\"). Ours: send base mesh = BASE and the code tables (built once "
         "per model, so a session only queues them); decode IDs = a request's base64url and id set; search vertex "
         "split = the records looked up and copied into the answer (sender-driven: the packets, whose ids are "
         "coded with their record once per model, so its encode IDs is in this row); determine visibility = the "
         "view's criteria over the front; update vertex front = the front moved below the splits sent (and "
         "coded compact or back while idle); others = the rest of the server's CPU (reading and writing sockets, "
         "HTTP parsing, VIEW decoding).\n\n";
}

}  // namespace pms::bench
