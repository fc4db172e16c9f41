// docs/cli.md against the `pmstream` binary, both ways: every command, option and --json field the page
// lists exists in the binary, and every one the binary has is on the page (docs/cli.md, "Conventions").
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "child_process.h"
#include "cli_doc.h"
#include "test_support.h"

namespace pms {
namespace {

using nlohmann::json;
using Names = std::set<std::string>;

// The bench is a program of its own with its own section (pmstream-bench), not part of this binary's contract.
const std::string kBenchSection = "pmstream-bench";

std::map<std::string, test::DocumentedCommand> documented() {
  std::ifstream in(std::string(PMSTREAM_SOURCE_DIR) + "/docs/cli.md");
  EXPECT_TRUE(in) << "docs/cli.md";
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return test::parse_cli_doc(text, {kBenchSection});
}

// `pmstream help --json`'s tree as "multilevel build" -> its options.
void collect_commands(const json& node, const std::string& prefix, std::map<std::string, Names>& out) {
  for (const auto& [name, sub] : node.at("subcommands").items()) {
    const std::string command = prefix.empty() ? name : prefix + " " + name;
    out[command] = sub.at("options").get<Names>();
    collect_commands(sub, command, out);
  }
}

std::map<std::string, Names> binary_commands() {
  const test::CliRun help = test::run_pmstream("help --json");
  EXPECT_EQ(help.exit_code, 0) << help.err;
  std::map<std::string, Names> commands;
  collect_commands(json::parse(help.out), "", commands);
  return commands;
}

void expect_same(const Names& doc, const Names& binary, const std::string& what) {
  for (const std::string& name : doc)
    EXPECT_TRUE(binary.count(name)) << what << ": " << name << " is in docs/cli.md but not in the binary";
  for (const std::string& name : binary)
    EXPECT_TRUE(doc.count(name)) << what << ": " << name << " is in the binary but not in docs/cli.md";
}

Names keys(const std::map<std::string, Names>& map) {
  Names out;
  for (const auto& [key, value] : map) out.insert(key);
  return out;
}

TEST(CliDoc, CommandsAndOptionsAreTheBinarys) {
  const auto doc = documented();
  const auto binary = binary_commands();
  ASSERT_TRUE(binary.count("build") && binary.count("multilevel level")) << "the listing lost its commands";
  Names doc_commands;
  for (const auto& [command, content] : doc) doc_commands.insert(command);
  expect_same(doc_commands, keys(binary), "commands");
  for (const auto& [command, options] : binary)
    if (doc.count(command)) expect_same(doc.at(command).options, options, command);
}

// Runs `args` (which print one JSON object) and adds its fields to `command`'s.
void add_fields(std::map<std::string, Names>& fields, const std::string& command, const std::string& args) {
  const test::CliRun run = test::run_pmstream(args);
  ASSERT_EQ(run.exit_code, 0) << args << "\n" << run.err;
  for (const std::string& field : test::json_fields(json::parse(run.out))) fields[command].insert(field);
}

// serve's lines (listening, reloaded, stats, stopped) and a stream in each kind of mode against it: the sender-driven
// one over TCP and over the WebSocket, the receiver-driven one and the multilevel levels over HTTP.
void add_served_fields(std::map<std::string, Names>& fields, const std::string& dir) {
  using std::chrono::seconds;
  test::ChildProcess serve(PMSTREAM_BINARY, {"serve", dir + "/terrain.pms", dir + "/levels.pml", "--host", "127.0.0.1",
                                             "--port", "0", "--http-port", "0", "--json"});
  const std::string listening = serve.next_line(seconds(30));
  ASSERT_FALSE(listening.empty()) << "serve printed no listening line";
  const json ready = json::parse(listening);
  for (const std::string& field : test::json_fields(ready)) fields["serve"].insert(field);
  const std::string tcp = "127.0.0.1:" + std::to_string(ready.at("port").get<int>());
  const std::string http = "http://127.0.0.1:" + std::to_string(ready.at("http_port").get<int>());
  const std::string common = " --path " + dir + "/path.json --json --timeout-ms 20000";
  add_fields(fields, "stream", "stream --server " + tcp + " --model terrain" + common);
  add_fields(fields, "stream", "stream --server " + tcp + " --mode dag --model terrain" + common);
  add_fields(fields, "stream", "stream --server " + http + " --mode receiver --model terrain" + common);
  add_fields(fields, "stream", "stream --server ws" + http.substr(4) + "/ws --model terrain" + common);
  add_fields(fields, "stream", "stream --server " + http + " --mode multilevel --model levels" + common);
  for (const int signal : {SIGHUP, SIGUSR1, SIGTERM}) {
    serve.signal(signal);
    const std::string line = serve.next_line(seconds(30));
    ASSERT_FALSE(line.empty()) << "serve printed nothing on signal " << signal;
    for (const std::string& field : test::json_fields(json::parse(line))) fields["serve"].insert(field);
  }
  EXPECT_EQ(serve.wait(seconds(30)), 0);
}

TEST(CliDoc, JsonFieldsAreTheBinarys) {
  const std::string dir = test::temp_dir().string();
  std::map<std::string, Names> fields;
  add_fields(fields, "build", "build terrain:2000 -o " + dir + "/terrain.pms --json");
  add_fields(fields, "info", "info " + dir + "/terrain.pms --json");
  add_fields(fields, "multilevel build", "multilevel build terrain:2000 -o " + dir + "/levels.pml --json");
  add_fields(fields, "multilevel build",
             "multilevel build terrain:2000 -o " + dir + "/clustered.pml --cluster grid:16,4 --json");
  add_fields(fields, "multilevel info", "multilevel info " + dir + "/levels.pml --json");
  ASSERT_EQ(
      test::run_pmstream("path orbit --model " + dir + "/terrain.pms --frames 2 -o " + dir + "/path.json").exit_code,
      0);
  {
    std::ifstream path(dir + "/path.json");
    std::ofstream(dir + "/cam.json") << json::parse(path).at("frames").at(0).dump();
  }
  add_fields(fields, "refine", "refine " + dir + "/terrain.pms --splits 100 -o " + dir + "/coarse.ply --json");
  add_fields(fields, "compare",
             "compare " + dir + "/terrain.pms " + dir + "/coarse.ply --camera " + dir + "/cam.json --json");
  add_served_fields(fields, dir);

  const auto doc = documented();
  for (const auto& [command, options] : binary_commands())
    if (options.count("--json")) {
      EXPECT_TRUE(fields.count(command)) << command << " --json is not run here";
    }
  for (const auto& [command, printed] : fields) {
    ASSERT_TRUE(doc.count(command)) << command;
    expect_same(doc.at(command).fields, printed, command + " --json");
  }
}

}  // namespace
}  // namespace pms
