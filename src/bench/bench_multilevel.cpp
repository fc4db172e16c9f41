// E10 (gueziec et al. 1999): the progressive multilevel mesh's memory against a plain indexed mesh, the
// time of a LOD switch and of a geomorph frame, and the bytes to the first picture and to each level when
// the levels are loaded progressively (docs/architecture.md, "Experiments"; docs/internals.md,
// "Progressive multilevel meshes"). The mesh is built by a child `pmstream multilevel build`, then read
// and timed here on this one thread.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "bench/bench.h"
#include "bench/child_process.h"
#include "bench/multilevel_figures.h"
#include "bench/multilevel_sizes.h"
#include "bench/report.h"
#include "common/error.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"
#include "multilevel/mesh.h"

namespace pms::bench {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The fastest of `repeats` runs of fn (the machine is shared: the fastest is the least disturbed).
template <typename Fn>
double fastest_ms(int repeats, Fn&& fn) {
  double best = 1e300;
  for (int i = 0; i < repeats; ++i) {
    const auto start = Clock::now();
    fn();
    best = std::min(best, ms_since(start));
  }
  return best;
}

struct LodTimes {
  double switch_max_ms = 0, switch_to_finest_ms = 0, geomorph_max_ms = 0;
};

// A jump to level l costs O(n - n_l + t_l) whatever level it starts from (docs/internals.md, setLevel), so
// the jump to each level from the far end of the range is the worst switch to it; the maximum over the
// levels is the worst switch between any two.
LodTimes lod_times(const MultilevelMesh& m, int repeats) {
  LodTimes out;
  MultilevelLod lod(m);
  const uint32_t top = m.level_count() - 1;
  for (uint32_t l = 0; l <= top; ++l) {
    const uint32_t far = l > top / 2 ? 0 : top;
    double jump = 1e300;
    for (int i = 0; i < repeats; ++i) {
      lod.set_level(far);
      const auto start = Clock::now();
      lod.set_level(l);
      jump = std::min(jump, ms_since(start));
    }
    out.switch_max_ms = std::max(out.switch_max_ms, jump);
    if (l == 0) out.switch_to_finest_ms = jump;
    if (l < top) {
      lod.set_level(float(l) + 0.5f);  // connectivity and morph sources of this pair
      const double frame = fastest_ms(repeats, [&] { lod.set_level(float(l) + 0.37f); });
      out.geomorph_max_ms = std::max(out.geomorph_max_ms, frame);
    }
  }
  return out;
}

// Bytes of the structure's arrays (representatives as stored: 3 or 4 bytes each), and of the plain indexed
// mesh of the same positions and attributes.
uint64_t multilevel_bytes(const MultilevelMesh& m) {
  return 4 * (m.positions.size() + m.normals.size() + m.triangles.size()) + m.representative.bytes() + m.colors.size() +
         4 * (m.vertex_count.size() + m.triangle_count.size());
}
uint64_t plain_bytes(const MultilevelMesh& m) {
  return 4 * (m.positions.size() + m.normals.size() + m.triangles.size()) + m.colors.size();
}

}  // namespace

void run_multilevel_group(BenchContext& context) {
  const std::string section = "E10: progressive multilevel meshes";
  if (skipped_without_models(context, section)) return;
  std::vector<std::string> models = context.options.models;
  if (models.empty())
    models = context.options.quick ? std::vector<std::string>{"bunny"} : std::vector<std::string>{"bunny", "dragon"};
  const int repeats = context.options.quick ? 3 : 5;
  Table table({{"model", false},
               {"levels"},
               {"vertices"},
               {"triangles"},
               {"multilevel B"},
               {"plain B"},
               {"ratio"},
               {"switch max ms"},
               {"to finest ms"},
               {"geomorph max ms"},
               {"first picture B"},
               {"first picture triangles"},
               {"all levels B"}});
  Table sizes({{"model", false},
               {"compressed B"},
               {"bits / vertex"},
               {"bits / triangle"},
               {"first picture B"},
               {"binary B"},
               {"binary gzip B"},
               {"ASCII B"},
               {"ASCII gzip B"},
               {"meshopt v + i B"}});
  // The compressed form's bits per input vertex by part, and the time a client takes to decode it.
  Table part_table({{"model", false},
               {"connectivity"},
               {"positions"},
               {"representatives"},
               {"header"},
               {"secondary"},
               {"all levels"},
               {"decode ms"}});
  std::printf("\n## %s\n\n%s\n", section.c_str(), table.header().c_str());
  nlohmann::json rows = nlohmann::json::array();
  std::vector<std::string> size_rows, part_rows;
  std::string pictures;
  for (const std::string& name : models) {
    const std::string input = find_model(context.models_dir, name).string();
    const std::string output = (context.temp_dir / (name + ".pml")).string();
    const ChildResult build =
        run_child({context.pmstream_exe, "multilevel", "build", input, "-o", output, "--json"}, {});
    if (!build.ok()) {
      context.failures.push_back("multilevel " + name + ": build " + build.failure());
      continue;
    }
    const MultilevelMesh m = read_multilevel(output);
    const LodTimes times = lod_times(m, repeats);
    pictures += multilevel_figures(context.options.out_dir, name, m);
    // Progressive loading: the head, then each level's section, coarsest first (the HTTP bodies).
    const MultilevelParts parts = multilevel_parts(m);
    nlohmann::json per_level = nlohmann::json::array();
    uint64_t bytes = parts.head.size();
    for (size_t i = 0; i < parts.levels.size(); ++i) {
      bytes += parts.levels[i].size();
      const uint32_t level = m.level_count() - 1 - uint32_t(i);
      per_level.push_back({{"level", level},
                           {"bytes", parts.levels[i].size()},
                           {"cumulative_bytes", bytes},
                           {"lod_triangles", m.triangle_count[level]},
                           {"lod_vertices", m.vertex_count[level]}});
    }
    const uint64_t first = parts.head.size() + parts.levels.front().size();
    const uint64_t ml = multilevel_bytes(m), plain = plain_bytes(m);
    std::printf("%s\n", table
                            .add_row({name, thousands(m.level_count()), thousands(m.vertices()), thousands(m.faces()),
                                      thousands(ml), thousands(plain), fixed(double(ml) / double(plain), 3),
                                      fixed(times.switch_max_ms, 2), fixed(times.switch_to_finest_ms, 2),
                                      fixed(times.geomorph_max_ms, 3), thousands(first),
                                      thousands(m.triangle_count.back()), thousands(bytes)})
                            .c_str());
    nlohmann::json levels_compressed;
    const MultilevelSizes z = multilevel_sizes(m, kDefaultPositionBits, levels_compressed);
    const uint64_t first_z =
        multilevel_compressed_parts(m).head.size() + levels_compressed[0]["compressed_bytes"].get<uint64_t>();
    size_rows.push_back(sizes.add_row({name, thousands(z.compressed), fixed(double(z.vertex_bits) / m.vertices(), 2),
                                       fixed(double(z.triangle_bits) / m.faces(), 2), thousands(first_z),
                                       thousands(z.binary), thousands(z.binary_gzip), thousands(z.ascii),
                                       thousands(z.ascii_gzip), thousands(z.meshopt_vertex + z.meshopt_index)}));
    const auto per_vertex = [&](uint64_t bits) { return fixed(double(bits) / m.vertices(), 2); };
    part_rows.push_back(part_table.add_row({name, per_vertex(z.parts.triangles), per_vertex(z.parts.vertices),
                                       per_vertex(z.parts.representatives), per_vertex(z.parts.header),
                                       per_vertex(z.parts.changed), per_vertex(z.parts.total()),
                                       fixed(z.decode_ms, 2)}));
    rows.push_back({{"model", name},
                    {"levels", m.level_count()},
                    {"vertices", m.vertices()},
                    {"triangles", m.faces()},
                    {"representatives", m.stored_representatives()},
                    {"multilevel_bytes", ml},
                    {"plain_bytes", plain},
                    {"memory_ratio", double(ml) / double(plain)},
                    {"switch_max_ms", times.switch_max_ms},
                    {"switch_to_finest_ms", times.switch_to_finest_ms},
                    {"geomorph_max_ms", times.geomorph_max_ms},
                    {"first_picture_bytes", first},
                    {"levels_bytes", per_level},
                    {"build_seconds", build.wall_seconds},
                    {"compressed",
                     {{"position_bits", kDefaultPositionBits},
                      {"bytes", z.compressed},
                      {"first_picture_bytes", first_z},
                      {"vertex_bits", z.vertex_bits},
                      {"triangle_bits", z.triangle_bits},
                      {"binary_bytes", z.binary},
                      {"binary_gzip_bytes", z.binary_gzip},
                      {"ascii_bytes", z.ascii},
                      {"ascii_gzip_bytes", z.ascii_gzip},
                      {"meshopt_vertex_bytes", z.meshopt_vertex},
                      {"meshopt_index_bytes", z.meshopt_index},
                      {"bits_by_part",
                       {{"connectivity", z.parts.triangles},
                        {"positions", z.parts.vertices},
                        {"representatives", z.parts.representatives},
                        {"header", z.parts.header},
                        {"secondary", z.parts.changed}}},
                      {"decode_ms", z.decode_ms},
                      {"levels", levels_compressed}}}});
  }
  std::printf("\nTransmission, every level on its own (positions on a %u-bit grid):\n\n%s\n", kDefaultPositionBits,
              sizes.header().c_str());
  for (const std::string& row : size_rows) std::printf("%s\n", row.c_str());
  std::printf("\nCompressed form, bits per input vertex by part, and decode time:\n\n%s\n", part_table.header().c_str());
  for (const std::string& row : part_rows) std::printf("%s\n", row.c_str());
  context.report += "\n## " + section +
                    "\n\nTargets: memory ≤ 1.1× the plain indexed mesh, a switch between any "
                    "two LODs ≤ 10 ms, a geomorph frame ≤ 5 ms on one core. Switch: the fastest of " +
                    std::to_string(repeats) +
                    " jumps to each level from the far end (a jump's cost depends only on "
                    "its target), the maximum over the levels. Bytes: HTTP bodies (head + levels), headers aside.\n\n" +
                    table.markdown() +
                    "\nTransmission: every level on its own, summed; the compressed form's bits per vertex (positions) "
                    "and per triangle (connectivity and representatives), each level's header and code tables shared "
                    "out between them; gzip -9 of each level's binary section and ASCII batches; meshoptimizer's "
                    "vertex codec and index-sequence codec per level on the same grid.\n\n" +
                    sizes.markdown() +
                    "\nThe compressed form's bits per input vertex by part over every level (positions include "
                    "normals, colours and texture coordinates; header: each level's counts and the coder's flush), "
                    "and the time a client's loader takes to decode every level (each level's fastest of 5 loads, summed).\n\n" +
                    part_table.markdown() + "\n" + pictures;
  write_text_file(context.options.out_dir / "multilevel.json",
                  nlohmann::json{{"machine", machine_json()}, {"models", rows}}.dump(2) + "\n");
}

}  // namespace pms::bench
