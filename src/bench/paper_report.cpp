// The four papers' figures and tables against ours (paper_report.h). The papers' own figures are quoted
// from ../shared/seeds; ours are read from the groups' JSON, so this file knows their layout (each group's
// record functions write it).
#include "bench/paper_report.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/report.h"

namespace pms::bench {
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

// The GROUP.json files of the directory, loaded once; a group that has not run is absent.
class Groups {
 public:
  explicit Groups(const fs::path& dir) {
    for (const BenchGroup& g : bench_groups()) {
      std::ifstream in(dir / (std::string(g.name) + ".json"));
      if (!in) continue;
      json j = json::parse(in, nullptr, false);
      if (!j.is_discarded()) data_[g.name] = std::move(j);
    }
  }
  const json* get(const std::string& name) const {
    const auto it = data_.find(name);
    return it == data_.end() ? nullptr : &it->second;
  }

 private:
  std::map<std::string, json> data_;
};

double mean(const json& values) {
  if (!values.is_array() || values.empty()) return 0;
  double sum = 0;
  for (const json& v : values) sum += v.get<double>();
  return sum / double(values.size());
}

std::string joined(const std::vector<std::string>& parts) {
  std::string s;
  for (const std::string& p : parts) s += (s.empty() ? "" : "; ") + p;
  return s;
}

// ---- kim-lee-kobbelt 2005 ------------------------------------------------------------------------------

std::string klk_table1(const Groups& g) {
  const json* build = g.get("build");
  if (!build) return "";
  std::vector<std::string> rows;
  for (const json& m : build->at("models")) {
    const json& p = m.at("pmstream");
    rows.push_back(m.at("model").get<std::string>() + " " + std::to_string(p.at("base_vertices").get<uint64_t>()) +
                   ", " + thousands(p.at("vsplits").get<uint64_t>()) + ", " +
                   id_bits(p.at("tree_id_bits").get<uint32_t>(), p.at("node_id_bits").get<uint32_t>()));
  }
  return joined(rows);
}

std::string klk_table2(const Groups& g) {
  const json* sender = g.get("sender");
  if (!sender || sender->at("models").empty()) return "";
  const json& m = sender->at("models").front();
  std::vector<std::string> rows;
  for (const json& row : m.at("e2").at("table2"))
    rows.push_back(row.at("framework").get<std::string>() + " " + fixed(row.at("bits_fitted").get<double>(), 1));
  return m.at("model").get<std::string>() + ", bits at the model's index widths: " + joined(rows);
}

std::string klk_fig6(const Groups& g) {
  const json* sender = g.get("sender");
  if (!sender) return "";
  std::vector<std::string> rows;
  for (const json& m : sender->at("models")) {
    const json& orbit = m.at("e3_e4");
    rows.push_back(m.at("model").get<std::string>() + ": tags " +
                   fixed(100 * orbit.at("tags_over_front_mean").get<double>(), 0) + " %, compact front " +
                   fixed(100 * orbit.at("compact_over_front_mean").get<double>(), 1) + " %");
  }
  return "of a stored 8-byte-per-node front, mean along the orbit: " + joined(rows);
}

std::string klk_fig7(const Groups& g) {
  const json* sender = g.get("sender");
  if (!sender) return "";
  std::vector<std::string> rows;
  for (const json& m : sender->at("models")) {
    const json& look = m.at("e3_e4_look");
    rows.push_back(m.at("model").get<std::string>() + ": lap 1 " + thousands(look.at("lap_down")[0].get<uint64_t>()) +
                   " B down, " + thousands(look.at("lap_up")[0].get<uint64_t>()) + " up; lap 2 " +
                   thousands(look.at("lap_down")[1].get<uint64_t>()) + " / " +
                   thousands(look.at("lap_up")[1].get<uint64_t>()));
  }
  return "the look path twice: " + joined(rows);
}

std::string klk_fig8(const Groups& g) {
  const json* sender = g.get("sender");
  if (!sender || !sender->contains("e13")) return "";
  const json& e = sender->at("e13");
  return e.at("model").get<std::string>() + " along the look path: " + fixed(mean(e.at("faces")), 0) +
         " faces, refinement " + fixed(mean(e.at("client_ms")), 2) + " ms, rendering " +
         fixed(mean(e.at("render_ms")), 2) + " ms a frame (means; the plot: sender-e13-" +
         e.at("model").get<std::string>() + ".png)";
}

std::string klk_fig9(const Groups& g) {
  const json* sender = g.get("sender");
  if (!sender) return "";
  std::vector<std::string> rows;
  for (const json& m : sender->at("models")) {
    const json& e5 = m.at("e5");
    const double vd = e5.at("vd_bytes").get<double>(), vi = e5.at("vi_bytes").get<double>();
    rows.push_back(m.at("model").get<std::string>() + " " + thousands(uint64_t(vd)) + " B against " +
                   thousands(uint64_t(vi)) + " (" + fixed(vi / std::max(1.0, vd), 1) + "×)");
  }
  return "view-dependent against view-independent: " + joined(rows);
}

std::string klk_fig10(const Groups& g) {
  const json* sender = g.get("sender");
  if (!sender || !sender->contains("e14")) return "";
  std::map<std::string, std::vector<std::string>> by_view;
  for (const json& row : sender->at("e14")) {
    if (row.at("budget") != "0.5MiB") continue;
    const std::string key = row.at("model").get<std::string>() + " " + row.at("view").get<std::string>();
    by_view[key].push_back(row.at("mode").get<std::string>() + " " + fixed(row.at("psnr").get<double>(), 1));
  }
  std::vector<std::string> rows;
  for (const auto& [view, modes] : by_view) {
    std::string r = view + ":";
    for (const std::string& m : modes) r += " " + m;
    rows.push_back(r + " dB");
  }
  return "PSNR after 0.5 MiB: " + joined(rows) + " (images sender-e14-MODEL-VIEW-BUDGET.png)";
}

// ---- cheng-ooi 2008 ------------------------------------------------------------------------------------

std::string cheng_table1(const Groups& g) {
  const json* receiver = g.get("receiver");
  if (!receiver) return "";
  std::vector<std::string> rows;
  for (const json& m : receiver->at("models")) {
    if (!m.contains("e7_phases")) continue;
    const double s = m.at("e7_phases").at("sender").at("cpu_ms").get<double>();
    const double r = m.at("e7_phases").at("receiver").at("cpu_ms").get<double>();
    if (s > 0) rows.push_back(m.at("model").get<std::string>() + " " + fixed(r / s, 2));
  }
  if (rows.empty()) return "not in this receiver.json: a run of `--only receiver` adds it";
  return "receiver-driven over sender-driven server CPU: " + joined(rows) + " (by phase in receiver.md)";
}

// The fewest bytes after which a mode's samples reach `psnr` dB; 0 when they never do.
uint64_t bytes_to(const json& mode, double psnr) {
  for (const json& s : mode.at("samples"))
    if (s.at("psnr").get<double>() >= psnr) return s.at("bytes").get<uint64_t>();
  return 0;
}

std::string cheng_fig8(const Groups& g) {
  const json* receiver = g.get("receiver");
  if (!receiver) return "";
  std::vector<std::string> rows;
  for (const json& m : receiver->at("models"))
    for (const json& view : m.at("e6")) {
      if (view.at("view") != "mid") continue;
      std::string r = m.at("model").get<std::string>() + " mid:";
      for (const char* mode : {"receiver-driven", "sender-driven", "view-independent"}) {
        const uint64_t b = view.at("modes").contains(mode) ? bytes_to(view.at("modes").at(mode), 35) : 0;
        r += std::string(" ") + mode + " " + (b ? thousands(b) : std::string("never"));
      }
      rows.push_back(r);
    }
  return "bytes to 35 dB: " + joined(rows) + " (plots receiver-e6-MODEL-VIEW.png)";
}

// ---- zheng-chan 2006 -----------------------------------------------------------------------------------

std::string dag_route_summary(const Groups& g, const char* figure) {
  const json* dag = g.get("dag");
  if (!dag || !dag->contains("route 1")) return "";
  const json& route = dag->at("route 1");
  std::vector<std::string> rows;
  for (const char* t : {"priority", "linear", "constant-time"}) {
    if (!route.contains(t)) continue;
    const json& r = route.at(t);
    const std::string f = figure;
    if (f == "times") rows.push_back(std::string(t) + " " + fixed(mean(r.at("frame_ms")), 2) + " ms");
    if (f == "accuracy" && t != std::string("priority"))
      rows.push_back(std::string(t) + " " + fixed(100 * mean(r.at("accuracy_every_5_frames")), 1) + " %");
    if (f == "fronts")
      rows.push_back(std::string(t) + " " + fixed(mean(r.at("triangles")), 0) + " triangles, front " +
                     fixed(100 * mean(r.at("front_share")), 1) + " % of the nodes");
  }
  return dag->at("model").get<std::string>() + ", route 1, means: " + joined(rows) + " (route 2 in dag.md)";
}
std::string zc_fig6(const Groups& g) { return dag_route_summary(g, "times"); }
std::string zc_fig7(const Groups& g) { return dag_route_summary(g, "accuracy"); }
std::string zc_fig9(const Groups& g) { return dag_route_summary(g, "fronts"); }

// ---- gueziec et al. 1999 -------------------------------------------------------------------------------

std::string gueziec_fig1(const Groups& g) {
  const json* ml = g.get("multilevel");
  if (!ml) return "";
  std::vector<std::string> rows;
  for (const json& m : ml->at("models")) {
    std::vector<std::string> nearest_counts;
    for (const uint64_t want : {247, 665, 1519, 4350}) {
      uint64_t nearest = 0;
      for (const json& level : m.at("levels_bytes")) {
        const uint64_t t = level.at("lod_triangles").get<uint64_t>();
        if (!nearest || (t > want ? t - want : want - t) < (nearest > want ? nearest - want : want - nearest))
          nearest = t;
      }
      nearest_counts.push_back(thousands(nearest));
    }
    std::string counts;
    for (const std::string& c : nearest_counts) counts.append(counts.empty() ? "" : ", ").append(c);
    rows.push_back(m.at("model").get<std::string>() + ", " + std::to_string(m.at("levels").get<uint32_t>()) +
                   " levels: LODs of " + counts + " triangles");
  }
  return joined(rows);
}

// ---- the elements ----------------------------------------------------------------------------------------

using Headline = std::string (*)(const Groups&);

struct Element {
  const char* figure;
  const char* shows;  // what the paper's element shows
  const char* paper;  // its figures, quoted
  const char* where;  // the experiment and the report, or the code and the tests of an illustration
  const char* group;  // the group whose JSON `ours` reads; nullptr for an illustration
  Headline ours;      // nullptr: see `where`
};

struct Paper {
  const char* title;
  const char* models;  // the paper's models we have and have not
  std::span<const Element> elements;
};

constexpr Element kKimLeeKobbelt[] = {
    {"Fig. 1", "the framework: server, client, view information up, vsplit packets down", "illustration",
     "docs/architecture.md (\"Data flow\"); `server/sender_driven_mode.cpp`, `client/streaming_client.cpp`; "
     "tests/server/streaming_test.cpp",
     nullptr, nullptr},
    {"Fig. 2", "truly selective refinement: fundamental cut vertices, climbing to active ones", "illustration",
     "`spm/selective_mesh.cpp` (SelVSplit, ActiveAncestor); tests/spm", nullptr, nullptr},
    {"Fig. 3", "the packets: view information up, vsplit packets down", "illustration",
     "docs/protocol.md (VIEW, VSPLITS); E2 measures the packets (sender.md)", nullptr, nullptr},
    {"Fig. 4", "windowed active tags", "illustration",
     "`server/active_tags.h`; E3 measures them (sender.md); tests/server/compact_front_test.cpp", nullptr, nullptr},
    {"Table 1", "base vertices, details and <tree-id, node-id> bits of balanced hierarchies",
     "bunny 62, 34,772, <6, 16>; horse 75, 19,776, <7, 14>; feline 12, 49,852, <4, 28>; skull 146, 98,160, "
     "<8, 23>; Buddha 65, 545,557, <7, 25>",
     "E1, [build.md](build.md)", "build", klk_table1},
    {"Table 2", "topological detail bits per vsplit packet of five frameworks",
     "To 256, El-Sana 192, Southern 256, its variation 192, ours 96 (32-bit indices)",
     "E2, [sender.md](sender.md) \"Table 2\" (every scheme on our splits, at 32 bits and at the model's widths)",
     "sender", klk_table2},
    {"Fig. 5", "the navigation path: look around the model from top to bottom, twice", "illustration (a path)",
     "`pmstream path look` (`apps/camera_path.cpp`, PathKind::look); E3/E4 fly it beside the orbit", nullptr,
     nullptr},
    {"Fig. 6", "server memory per session along the path: windowed tags against a stored front (Buddha)",
     "tags about 10 % of a stored front", "E3, [sender.md](sender.md) \"E3/E4\"", "sender", klk_fig6},
    {"Fig. 7", "bytes up and down accumulated over two laps (bunny)", "lap 2 sends nothing either way",
     "E4, [sender.md](sender.md) \"E3/E4\"", "sender", klk_fig7},
    {"Fig. 8", "faces, refinement and rendering time per frame (Buddha)",
     "times follow the faces; peaks at sudden view changes", "E13 on dragon, [sender.md](sender.md) \"E13\"",
     "sender", klk_fig8},
    {"Fig. 9", "bytes to satisfy a screen-space tolerance, view-dependent against view-independent",
     "bunny 177,120 against 827,688 B (4.7×); dragon 946,400 against 3,816,384 B (4.0×)",
     "E5, [sender.md](sender.md) \"E5\"", "sender", klk_fig9},
    {"Fig. 10", "the meshes after the same 0.5 MB: view-dependent, its plain variation, view-independent (Buddha)",
     "VD better close, worse far; the plain variation better than VI at both",
     "E14, [sender.md](sender.md) \"E14\" (rendered side by side)", "sender", klk_fig10},
};

constexpr Element kChengOoi[] = {
    {"Fig. 1", "edge collapse and vertex split", "illustration", "`spm/hierarchy.h`, `builder/`; tests/builder",
     nullptr, nullptr},
    {"Fig. 2", "sender-driven against receiver-driven protocol", "illustration",
     "docs/protocol.md (\"Session\", \"Receiver-driven over HTTP\")", nullptr, nullptr},
    {"Fig. 3", "vertex hierarchy, front and ids", "illustration", "`spm/vertex_id.h`; tests/spm", nullptr, nullptr},
    {"Fig. 4", "the receiver-driven sender: decode ids, search splits, encode", "illustration",
     "`server/http_routes.cpp`, `server/split_records_body.cpp`; tests/server/http_test.cpp", nullptr, nullptr},
    {"Fig. 5", "importance from a vertex's visible screen area", "illustration",
     "`client/screen_importance.cpp` (native), `client/face_id_importance.cpp` (WebGL face ids)", nullptr,
     nullptr},
    {"Fig. 6", "the id code of a request", "illustration (27 bits an id for Buddha)",
     "docs/protocol.md \"Split request code\"; receiver.md \"Up\" measures bits per id", nullptr, nullptr},
    {"Table 1", "the sender's CPU by phase, both protocols (Buddha)",
     "sender-driven 6.17 s, receiver-driven 4.69 s (0.76)", "E7, [receiver.md](receiver.md) \"E7 by phase\"",
     "receiver", cheng_table1},
    {"Fig. 7", "three viewpoints: rendered images and meshes", "illustration of E6's views",
     "E6's far, mid and close views; rendered in [refine.md](refine.md) \"Image quality\"", nullptr, nullptr},
    {"Table 2", "errors when only the visible vertices are split (500×500)",
     "305, 226, 115 error pixels; PSNR 37.8, 38.3, 40.6", "E8, [receiver.md](receiver.md) \"E8\"", nullptr,
     nullptr},
    {"Fig. 8", "PSNR against bytes received: receiver-driven, sender-driven, view-independent",
     "receiver-driven rises fastest, view-independent slowest", "E6, [receiver.md](receiver.md) \"E6\"",
     "receiver", cheng_fig8},
};

constexpr Element kZhengChan[] = {
    {"Fig. 1", "maintaining the DAG's front", "illustration", "`dag/` (the cut); tests/dag", nullptr, nullptr},
    {"Fig. 2", "FREE and BUDGET management of the hierarchy", "illustration",
     "`client/dag_management.cpp` (`--management auto`); E9's management rows in dag.md", nullptr, nullptr},
    {"Fig. 3", "the priority-oriented traversal", "algorithm", "`dag/` priority traversal; tests/dag", nullptr,
     nullptr},
    {"Fig. 4", "the linear traversal", "algorithm", "`dag/` linear traversal; tests/dag", nullptr, nullptr},
    {"Fig. 5", "the constant-time traversal", "algorithm", "`dag/` constant-time traversal; tests/dag", nullptr,
     nullptr},
    {"Fig. 6", "traversal time per frame, three traversals (Buddha)",
     "constant-time fastest, priority slowest", "E9, [dag.md](dag.md)", "dag", zc_fig6},
    {"Fig. 7", "accuracy of linear and constant-time against priority", "both close to 100 %",
     "E9, [dag.md](dag.md)", "dag", zc_fig7},
    {"Fig. 8", "the three traversals' meshes at frame 110", "images",
     "E9, [dag.md](dag.md) \"Fig. 8\" (dag-fig8-TRAVERSAL.png)", nullptr, nullptr},
    {"Fig. 9", "front size against the refined mesh's triangles", "the front follows the mesh",
     "E9, [dag.md](dag.md)", "dag", zc_fig9},
};

constexpr Element kGueziec[] = {
    {"Fig. 1", "a horse's LODs of 247, 665, 1,519 and 4,350 triangles switched interactively",
     "247, 665, 1,519, 4,350 triangles",
     "E10, [multilevel.md](multilevel.md): multilevel-fig1-MODEL.png; the page's LOD slider (docs/web.md)",
     "multilevel", gueziec_fig1},
    {"Fig. 2", "a forest of collapsed edges", "illustration", "`multilevel/build.cpp`; tests/multilevel", nullptr,
     nullptr},
    {"Fig. 3", "representatives and their path compression", "illustration",
     "`multilevel/representative_array.h`; tests/multilevel", nullptr, nullptr},
    {"Fig. 4", "levels of a simple mesh's vertices and triangles", "illustration",
     "`multilevel/build.cpp`; tests/multilevel", nullptr, nullptr},
    {"Fig. 5", "accessing a LOD through the representatives", "illustration",
     "`multilevel/mesh.cpp` (setLevel); E10's switch times", nullptr, nullptr},
    {"Fig. 6", "the ASCII file of a progressive multilevel mesh", "file layout",
     "docs/multilevel-format.md \"ASCII\"; `multilevel/ascii.cpp`", nullptr, nullptr},
    {"Fig. 7", "the VRML PROTO that streams and switches LODs", "code",
     "the browser page's multilevel mode (docs/web.md) on `client/multilevel_client.cpp`", nullptr, nullptr},
    {"Fig. 8", "a VRML file using it", "code", "the page's URL (model, mode, camera: docs/web.md)", nullptr,
     nullptr},
    {"Fig. 9", "a textured model at its highest and lowest LOD", "images",
     "texture coordinates are carried (docs/multilevel-format.md); textured rendering is the next wave's", nullptr,
     nullptr},
    {"Fig. 10", "a marble model with colours per vertex (50,000 triangles)", "image",
     "colours per vertex are carried and rendered (the demo's terrain); no marble model among ours", nullptr, nullptr},
    {"Fig. 11", "a non-manifold model's levels by clustering (64, 16, 4 triangles) and a geomorph", "images",
     "E10, [multilevel.md](multilevel.md): multilevel-fig11-MODEL.png, grid clusterings of our scans "
     "(`pmstream multilevel build --cluster`)",
     nullptr, nullptr},
    {"Fig. 12", "building levels from two vertex clusterings", "illustration",
     "`multilevel/cluster.cpp`; tests/multilevel", nullptr, nullptr},
    {"Fig. 13", "representatives of a non-manifold mesh's first two levels", "illustration",
     "`multilevel/cluster.cpp`; tests/multilevel", nullptr, nullptr},
    {"Fig. 14", "the DAG of edge collapses", "illustration", "`multilevel/dag.cpp`; tests/multilevel", nullptr,
     nullptr},
    {"Fig. 15", "selective refinement through the DAG", "images",
     "E10, [multilevel.md](multilevel.md): multilevel-fig15-MODEL.png; `multilevel/local.cpp`, "
     "`multilevel/region.cpp`, `pmstream multilevel level` (its local refinement); tests/multilevel", nullptr,
     nullptr},
    {"Fig. 16", "the forest split of progressive forest split compression", "illustration",
     "not built: the levels are coded per level instead (docs/multilevel-format.md \"Compressed levels\")",
     nullptr, nullptr},
};

constexpr Paper kPapers[] = {
    {"kim-lee-kobbelt 2005: view-dependent streaming with minimal latency",
     "Its bunny, horse, feline and skull are ours; Happy Buddha is not, so its figures run on dragon, our largest.",
     kKimLeeKobbelt},
    {"cheng-ooi 2008: receiver-driven view-dependent streaming",
     "It shows Happy Buddha only, which we do not have: its figures run on bunny, horse and dragon.", kChengOoi},
    {"zheng-chan 2006: traversal of a DAG multiresolution hierarchy",
     "Its Bunny and Dragon are ours, its Hand and Happy Buddha are not: its figures run on dragon.", kZhengChan},
    {"gueziec-taubin-horn-lazarus 1999: streaming geometry in VRML",
     "Its figures are mostly illustrations on small meshes; its horse is Rhythm & Hues' (ours is Stanford's "
     "scan), its marble and textured models are not ours.",
     kGueziec},
};

std::string ours_cell(const Groups& groups, const Element& e) {
  if (!e.ours) return "";
  if (!groups.get(e.group)) return "group `" + std::string(e.group) + "` not run here";
  try {
    return e.ours(groups);
  } catch (const json::exception& error) {  // a report from another version of the bench
    return std::string("not in this ") + e.group + ".json (" + error.what() + ")";
  }
}

}  // namespace

void write_paper_report(const fs::path& dir) {
  const Groups groups(dir);
  std::string s =
      "# The four papers' figures and tables\n\n"
      "Every figure and table of the four papers (../shared/seeds), in each paper's order: what it shows, the "
      "paper's own figure, ours from the bench's reports in this directory, and where it is made "
      "(docs/architecture.md, \"Experiments\", lists each experiment with its code). A diagram, an algorithm or a "
      "file layout has no measurement: its row names the code that implements it and the tests that check it. "
      "Rewritten by every `pmstream-bench` run from the GROUP.json files here; a group not run leaves its rows "
      "empty. The papers measured other machines and, for most figures, Happy Buddha, which we do not have: "
      "compare shapes and ratios, not seconds.\n";
  for (const Paper& paper : kPapers) {
    s += "\n## " + std::string(paper.title) + "\n\n" + paper.models + "\n\n";
    Table table({{"figure", false}, {"what it shows", false}, {"the paper", false}, {"ours", false},
                 {"where", false}});
    for (const Element& e : paper.elements) table.add_row({e.figure, e.shows, e.paper, ours_cell(groups, e), e.where});
    s += table.markdown();
  }
  write_text_file(dir / "report.md", s);
}

}  // namespace pms::bench
