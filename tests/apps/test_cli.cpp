// The `confpack` command line, run as a user runs it (the real binary, CONFPACK_BINARY), and the
// run configuration it writes back.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "backends/backend_factory.hpp"
#include "core/packing_io.hpp"
#include "core/run_config.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"

using namespace confpack;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using confpack::testing::CommandResult;
using confpack::testing::ConfpackSession;
using confpack::testing::lineCount;
using confpack::testing::slurp;

/// Runs each (arguments, what the message must mention) in `s` and requires the refusal the
/// README promises: exit 2, one line on stderr mentioning it, nothing on stdout.
void requireRefused(const ConfpackSession& s, const std::vector<std::pair<std::string, std::string>>& cases,
                    const std::function<void()>& nothingCreated) {
  for (const auto& [args, mention] : cases) {
    INFO("confpack " << args);
    const CommandResult r = s.run(args);
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(r.err.find(mention) != std::string::npos);
    CHECK(r.out.empty());
    nothingCreated();
  }
}

}  // namespace

TEST_CASE("every subcommand has --help") {
  ConfpackSession s("cli_help");
  const CommandResult root = s.run("--help");
  CHECK(root.code == 0);
  for (const char* sub : {"deposit", "run", "analyze", "sweep", "report", "reproduce"}) {
    INFO(sub);
    CHECK(root.out.find(sub) != std::string::npos);
    const CommandResult r = s.run(std::string(sub) + " --help");
    CHECK(r.code == 0);
    CHECK(r.out.find("Usage: confpack " + std::string(sub)) != std::string::npos);
  }
  const CommandResult deposit = s.run("deposit --help");
  for (const char* flag : {"--shape", "--length-x", "--width", "--periodic-y", "--height", "--small-fraction",
                           "--wall-friction", "--backend", "--seed", "--out", "--threads", "--quiet", "-v"})
    CHECK(deposit.out.find(flag) != std::string::npos);
  CHECK(s.entries().empty());
}

TEST_CASE("confpack --version names the version and the git revision the binary was built from") {
  ConfpackSession s("cli_version");
  const CommandResult r = s.run("--version");
  CHECK(r.code == 0);
  CHECK(r.err.empty());
  INFO(r.out);
  // A commit (12 hex digits), "-dirty" if tracked files differed from it; "unknown" outside git.
  CHECK(
      std::regex_match(r.out, std::regex(R"(confpack \d+\.\d+\.\d+ \(revision ([0-9a-f]{12}(-dirty)?|unknown)\)\n)")));
  CHECK(s.entries().empty());
}

TEST_CASE("range errors say the range in words, not the largest double in 300 digits") {
  ConfpackSession s("cli_ranges");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"reproduce --scale tiny --jobs 0 --out o", "--jobs: Value 0 not in range 1 to 4096"},
      {"analyze none.json --slice -1 --out o", "--slice: must be a positive number (got -1)"},
      {"analyze none.json --margin -1 --out o", "--margin: must be a number >= 0 (got -1)"},
  };
  for (const auto& [args, message] : cases) {
    INFO("confpack " << args);
    const CommandResult r = s.run(args);
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(message) != std::string::npos);
    CHECK(r.err.size() < 120);
    CHECK(s.empty());
  }
}

TEST_CASE("bad input is refused with one line, exit 2 and no output directory") {
  ConfpackSession s("cli_bad");
  const std::string valid = "--length-x 6 --width 4 --height 4 --out out";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"deposit --bogus " + valid, "--bogus"},
      {"deposit --backend foo " + valid, "--backend"},
      {"deposit " + valid + " --width 0", "--width"},
      {"deposit " + valid + " --width -3", "--width"},
      {"deposit " + valid + " --small-fraction 120", "--small-fraction"},
      {"deposit " + valid + " --small-fraction -1", "--small-fraction"},
      {"deposit " + valid + " --length-x abc", "--length-x"},
      {"deposit " + valid + " --height nan", "--height"},
      {"deposit " + valid + " --wall-friction -0.1", "--wall-friction"},
      {"deposit " + valid + " --seed -1", "--seed"},
      {"deposit " + valid + " --threads 0", "--threads"},
      {"deposit " + valid + " --shape cube", "--shape"},
      {"deposit " + valid + " --pinacoid-alpha 90", "--pinacoid-alpha"},
      {"run " + valid + " --protocol static", "--protocol"},
      {"run " + valid + " --switch-kinetic-ratio 0", "--switch-kinetic-ratio"},
      {"run " + valid + " --time-limit 1e20", "time_limit"},  // once 0 steps and exit 0 (step count overflow)
      {"deposit --length-x 6", "--out"},                      // missing --out
      // about 6.9e12 grains: once allocated until "std::bad_alloc"; now refused before any work.
      {"deposit --length-x 1e6 --width 1e6 --height 6 --out out", "max_grains"},
      {"deposit " + valid + " --max-grains 10", "max_grains (10)"},
      {"deposit " + valid + " --grain-cap 5", "grain_cap: 5 grains"},         // would leave L_x under two grains
      {"deposit " + valid + " --shape pinacoid --pinacoid-E 3", "pinacoid"},  // no ridge: refused by validate()
      {"", "subcommand"},
      {"frobnicate", "frobnicate"},
  };
  requireRefused(s, cases, [&] { CHECK(s.entries().empty()); });  // not even the directory
  // An --out that is a file: refused as bad input, the file untouched.
  std::ofstream(s.dir / "file") << "keep";
  const CommandResult r = s.run("deposit --length-x 6 --width 4 --height 4 --out file");
  CHECK(r.code == 2);
  CHECK(lineCount(r.err) == 1);
  CHECK(slurp(s.dir / "file") == "keep");
}

TEST_CASE("every subcommand refuses an unknown flag with one line and exit 2") {
  // A placeholder answers "not implemented yet"; a real subcommand refuses the flag at parse time.
  // Either way nothing runs (no real work in this test: a default `run` would take minutes).
  ConfpackSession s("cli_unknown_flag");
  for (const char* sub : {"deposit", "run", "analyze", "sweep", "report", "reproduce"}) {
    INFO(sub);
    const CommandResult r = s.run(std::string(sub) + " --no-such-flag-for-tests");
    INFO("stderr: " << r.err);
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK(s.entries().empty());
  }
}

TEST_CASE("a deposit with a grain cap is made in a box shortened along x, which its packing and config carry") {
  ConfpackSession s("cli_grain_cap");
  // 6 x 4 x 4 at phi 0.6 holds about 110 spheres; capped at 50, L_x = 6 * 50 / 110, to the hundredth.
  const CommandResult r = s.run("deposit --length-x 6 --width 4 --height 4 --grain-cap 50 --out dep");
  INFO("stderr: " << r.err);
  REQUIRE(r.code == 0);
  const core::Packing p = core::readPacking(s.dir / "dep" / "packing.json");
  CHECK(p.box.lengthX < 3.0);
  CHECK(p.box.lengthX > 2.5);
  CHECK(p.grains.size() <= 55);  // about 50: the draw is by volume, with a 3 % size spread
  CHECK(p.grains.size() >= 40);
  const nlohmann::json cfg = nlohmann::json::parse(slurp(s.dir / "dep" / "config.json"));
  CHECK(cfg.at("box").at("length_x") == p.box.lengthX);
  CHECK(cfg.at("deposition").at("grain_cap") == 50);
}

TEST_CASE("a small deposit writes a readable packing inside the box, its config and a ParaView series") {
  ConfpackSession s("cli_deposit");
  const CommandResult r = s.run("deposit --length-x 6 --width 4 --height 4 --seed 3 --wall-friction 0.3 --out a/dep");
  INFO("stderr: " << r.err);
  REQUIRE(r.code == 0);
  CHECK(lineCount(r.out) == 1);  // the one-line summary
  CHECK(r.out.find("grains") != std::string::npos);
  const fs::path dir = s.dir / "a" / "dep";

  const core::Packing p = core::readPacking(dir / "packing.json");
  CHECK_FALSE(p.contacts.has_value());  // a deposit has no forces yet
  CHECK(p.box.lengthX == 6.0);
  CHECK(p.box.width == 4.0);
  CHECK(p.walls.friction == 0.3);
  REQUIRE(p.grains.size() > 10);
  // Inside the box: x in [0, L_x), and the whole sphere between the walls and above the floor
  // (a deposit overlaps nothing, walls included; 1e-9 allows for rounding).
  for (const auto& g : p.grains) {
    CHECK(g.shape == core::ShapeKind::Sphere);
    CHECK(g.position.x() >= 0.0);
    CHECK(g.position.x() < 6.0);
    CHECK(g.position.y() - 0.5 * g.size >= -1e-9);
    CHECK(g.position.y() + 0.5 * g.size <= 4.0 + 1e-9);
    CHECK(g.position.z() - 0.5 * g.size >= -1e-9);
  }

  // config.json is the resolved configuration: the flags given, the defaults for the rest.
  const core::RunConfig cfg = json::parse(slurp(dir / "config.json")).get<core::RunConfig>();
  CHECK(cfg.box.lengthX == 6.0);
  CHECK(cfg.box.width == 4.0);
  CHECK(cfg.box.height == 4.0);
  CHECK(cfg.walls.friction == 0.3);
  CHECK(cfg.seed == 3);
  CHECK(cfg.backend == "nscd");
  CHECK(cfg.population.smallFraction == core::PopulationDef{}.smallFraction);

  CHECK(fs::exists(dir / "vtk" / "deposit_grains.pvd"));
  CHECK(fs::exists(dir / "vtk" / "deposit_grains_000000.vtp"));
  // No staging directory left next to the output.
  for (const auto& e : fs::directory_iterator(s.dir / "a")) CHECK(e.path().filename() == "dep");

  // Same seed, same pile, bit for bit; --quiet silences stderr; an existing --out is refreshed.
  const CommandResult again =
      s.run("deposit --length-x 6 --width 4 --height 4 --seed 3 --wall-friction 0.3 --quiet --out b");
  REQUIRE(again.code == 0);
  CHECK(again.err.empty());
  CHECK(slurp(s.dir / "b" / "packing.json") == slurp(dir / "packing.json"));
  const CommandResult other =
      s.run("deposit --length-x 6 --width 4 --height 4 --seed 4 --wall-friction 0.3 -q --out b");
  REQUIRE(other.code == 0);
  CHECK(slurp(s.dir / "b" / "packing.json") != slurp(dir / "packing.json"));
  CHECK(core::readPacking(s.dir / "b" / "packing.json").grains.size() > 10);
}

TEST_CASE("every subcommand refuses bad input with exit 2 (README, the exit-code table)") {
  ConfpackSession s("cli_exit_two");
  std::ofstream(s.dir / "file") << "not a folder";
  std::ofstream(s.dir / "typo.json") << R"({"name": "typo", "vary": {"widht": [4]}})";
  std::ofstream(s.dir / "options.json")
      << R"({"name": "options", "base": {"backend_options": {"no_such_option": 1}}, "vary": {"width": [4]}})";
  fs::create_directory(s.dir / "not-a-sweep");
  const std::string box = "--length-x 6 --width 4 --height 4";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"run " + box + " --out o --backend-options '{\"no_such_option\": 1}'", "no_such_option"},
      {"run " + box + " --backend bullet --out o --backend-options '{\"no_such_option\": 1}'", "no_such_option"},
      {"run " + box + " --out o --backend-options '{not json'", "parse error"},
      {"deposit " + box + " --out file", "'file' exists and is not a directory"},
      {"analyze missing.json --out o", "missing.json"},
      {"sweep typo.json --out o", "widht"},
      {"sweep options.json --out o", "no_such_option"},
      {"report not-a-sweep --out o", "not-a-sweep"},
      {"reproduce --scale tiny --out file", "'file' exists and is not a directory"},
  };
  requireRefused(s, cases, [&] { CHECK_FALSE(fs::exists(s.dir / "o")); });
  // Nothing else was created either: only the inputs are there.
  CHECK(s.entries().size() == 4);
}

TEST_CASE("values that can be refused before any work are: exit 2, one line, the subcommand's prefix") {
  // The failure this guards against: these failed after work had started (exit 1), --dt 5 as "z must be >= 0"
  // and --dt 1e300 after printing a 300-digit time.
  ConfpackSession s("cli_refused_up_front");
  const std::string out = " --out out";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"deposit --length-x 6 --height 4 --width 0.5" + out,
       "confpack deposit: error: box.width: 0.5 d_L is less than a grain's circumscribed diameter (1.1 d_L): no grain "
       "fits"},
      {"run --length-x 0.5 --width 4 --height 4" + out, "confpack run: error: box.length_x: 0.5 d_L is less than"},
      {"deposit --length-x 6 --width 4 --height 1e-9" + out,
       "confpack deposit: error: box.height: a box of 6 x 4 x 1e-09 d_L at expected_solid_fraction 0.6 holds no "
       "grain"},
      {"run --length-x 6 --width 4 --height 4 --dt 1e-300" + out,
       "confpack run: error: compaction.dt: 1e-300 is below"},
      {"run --length-x 6 --width 4 --height 4 --dt 5" + out,
       "confpack run: error: --dt: must be 0 or a time step of at most 0.1 t0 (got 5) (see --help)"},
      {"run --length-x 6 --width 4 --height 4 --dt 1e300" + out, "confpack run: error: --dt: must be 0 or a time step"},
      // The parser's own errors carry the subcommand too, as every other error of it does.
      {"run --length-x 6 --width 4 --height 4 --no-such-flag" + out, "confpack run: error: "},
      {"analyze", "confpack analyze: error: "},
  };
  requireRefused(s, cases, [&] { CHECK(s.entries().empty()); });
  // The --compaction-options and --config route to dt is refused the same way.
  const CommandResult viaJson = s.run("run --length-x 6 --width 4 --height 4 --compaction-options '{\"dt\": 5}'" + out);
  CHECK(viaJson.code == 2);
  CHECK_THAT(viaJson.err, Catch::StartsWith("confpack run: error: ") && Catch::Contains("dt"));
  CHECK(s.entries().empty());
}

TEST_CASE("the output rule from the command line: the root and a folder of other files are refused untouched") {
  // The failure this guards against: `run --out /` exited 0 having written into the file system's root, and a
  // folder of the user's was filled.
  ConfpackSession s("cli_out_rule");
  const std::string box = "--length-x 3 --width 3 --height 2 -q";
  const CommandResult root = s.run("deposit " + box + " --out /");
  CHECK(root.code == 2);
  CHECK(root.err == "confpack deposit: error: --out: '/' is the file system's root; give a new or empty folder\n");
  CHECK_FALSE(fs::exists("/packing.json"));
  fs::create_directory(s.dir / "mine");
  std::ofstream(s.dir / "mine" / "notes.txt") << "mine";
  for (const char* sub : {"deposit", "run"}) {
    INFO(sub);
    const CommandResult r = s.run(std::string(sub) + " " + box + " --out mine");
    CHECK(r.code == 2);
    CHECK(lineCount(r.err) == 1);
    CHECK_THAT(r.err, Catch::Contains("'mine' is a folder with files confpack did not write"));
  }
  CHECK(fs::directory_iterator(s.dir / "mine")->path().filename() == "notes.txt");
  CHECK(std::distance(fs::directory_iterator(s.dir / "mine"), fs::directory_iterator()) == 1);
  // An empty folder is taken, and what confpack wrote there it may write again.
  fs::create_directory(s.dir / "empty");
  REQUIRE(s.run("deposit " + box + " --out empty").code == 0);
  CHECK(fs::exists(s.dir / "empty" / ".confpack-output"));
  CHECK(s.run("deposit " + box + " --out empty").code == 0);
}

TEST_CASE("the output rule on a read-only mount: a new or a confpack --out is refused before any work") {
  // A real read-only file system, a tmpfs mounted in a mount namespace of its own (unshare -rm:
  // user namespaces, or root; util-linux), holding an earlier confpack output. The failure this
  // guards against: replacing that output did the whole run and then failed (exit 1) on the
  // staging folder beside it. Fails, never skips, where no namespace can be made.
  ConfpackSession s("cli_out_read_only", "/usr/bin/unshare");
  const std::string confpack = std::string("'") + CONFPACK_BINARY + "'";
  const std::string run = confpack + " run --length-x 3 --width 3 --height 3 --time-limit 1 -q --out ";
  std::ofstream(s.dir / "mount.sh") << "set -e\nmkdir ro\nmount -t tmpfs -o size=8m tmpfs ro\n"
                                    << run << "ro/pile\nmount -o remount,ro ro\nset +e\n"
                                    << run << "ro/new 2> new.err; echo $? > new.code\n"
                                    << run << "ro/pile 2> again.err; echo $? > again.code\n"
                                    << confpack << " analyze ro/pile/packing.json -q --out ro/pile 2> an.err; "
                                    << "echo $? > an.code\nls -A ro/pile > left.txt\n";
  const CommandResult r = s.run("-rm sh mount.sh");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto text = [&](const char* name) { return slurp(s.dir / name); };
  CHECK(text("new.code") == "2\n");
  CHECK_THAT(text("new.err"), Catch::StartsWith("confpack run: error: --out: cannot create '") &&
                                  Catch::EndsWith("ro/new': Read-only file system\n"));
  CHECK(text("again.code") == "2\n");
  CHECK_THAT(text("again.err"), Catch::StartsWith("confpack run: error: --out: cannot replace '") &&
                                    Catch::EndsWith("ro/pile': Read-only file system\n"));
  CHECK(text("an.code") == "2\n");
  CHECK(lineCount(text("an.err")) == 1);
  // The earlier output is whole: its marker, its packing and its result.
  const std::string left = text("left.txt");
  for (const char* name : {".confpack-output", "packing.json", "result.json", "config.json"})
    CHECK_THAT(left, Catch::Contains(std::string(name) + "\n"));
}

namespace {

/// Runs confpack with `args` in `dir` under an address-space limit of `limitMiB` (RLIMIT_AS):
/// its exit code (-1 if a signal ended it) and stderr.
CommandResult runWithMemoryLimit(const fs::path& dir, std::size_t limitMiB, std::vector<std::string> args) {
  const fs::path err = dir.string() + ".err";
  const pid_t pid = confpack::testing::startConfpack(dir, std::move(args), err, limitMiB);
  REQUIRE(pid >= 0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  CommandResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err);
  fs::remove(err);
  return r;
}

}  // namespace

TEST_CASE("out of memory: one line naming the step, exit 1, and neither the output nor its staging left") {
  // A deposit of 68,000 grains needs about 150 MB of address space (most of it the packing's JSON
  // document); 80 MB lets the program start and fails the work, in about a second. Before: an
  // abort (SIGABRT) while the JSON document was destroyed during the unwinding, the staging
  // folder left behind.
  ConfpackSession s("cli_out_of_memory");
  const auto start = std::chrono::steady_clock::now();
  const CommandResult deposit = runWithMemoryLimit(
      s.dir, 80, {"deposit", "--length-x", "100", "--width", "100", "--height", "6", "--out", "X", "-q"});
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  INFO("stderr: " << deposit.err);
  CHECK(deposit.code == 1);
  CHECK(deposit.err.find("confpack deposit: out of memory while ") != std::string::npos);
  CHECK(lineCount(deposit.err) == 1);
  CHECK(s.empty());  // neither X nor .X.partial-PID
  WARN("out of memory after " << seconds << " s");

  // Reading that packing (10 MB of JSON) for analysis: once refused as bad input (exit 2).
  REQUIRE(s.run("deposit --length-x 100 --width 100 --height 6 --out X -q").code == 0);
  const CommandResult analyze = runWithMemoryLimit(s.dir, 80, {"analyze", "X/packing.json", "--out", "A", "-q"});
  INFO("stderr: " << analyze.err);
  CHECK(analyze.code == 1);
  CHECK(analyze.err == "confpack analyze: out of memory while reading the packing file\n");
  CHECK_FALSE(fs::exists(s.dir / "A"));
}
