// `confpack report` (apps/cmd_report.cpp) with the real binary and fake gnuplots: a figure gnuplot
// fails on, or draws as an empty file, is named and not left behind; a report stopped by SIGTERM
// or SIGKILL while gnuplot hangs leaves the previous report whole; the run links and the tables,
// written in the staging folder, hold in the report's final folder.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "study/sweep.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/study_stubs.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using confpack::testing::ConfpackSession;
using confpack::testing::lineCount;
using confpack::testing::slurp;
using nlohmann::json;

namespace {

/// A finished sweep folder `dir` of four runs with made-up results (no physics: the report is
/// what is tested), enough for the phi(W) figures; boxes `height` high.
void makeSweep(const fs::path& dir, double height = 4.0) {
  json doc = json::parse(R"({
    "name": "fake", "base": { "box": { "length_x": 6 } },
    "vary": { "width": [4, 8], "replicas": 2, "backend": ["nscd"] } })");
  doc["base"]["box"]["height"] = height;
  const study::SweepSpec spec = study::parseSweepSpec(doc);
  auto runner = [](const core::RunConfig& cfg, const fs::path& runDir, const compaction::Deposit&,
                   const study::RunProgressFn&) {
    const double phi = 0.64 - 0.5 / cfg.box.width + 0.001 * static_cast<double>(cfg.seed);
    const json r = {{"n_grains", 100},
                    {"backend", cfg.backend},
                    {"seed", cfg.seed},
                    {"solid_fraction", phi},
                    {"coordination", {{"Z", 6.0 - 1.0 / cfg.box.width}}},
                    {"equilibrium", {{"reached", true}}},
                    {"timing", {{"wall_s", 1.0}, {"steps", 100}}}};
    std::ofstream(runDir / "result.json") << r.dump();
    return r;
  };
  study::SweepOptions o;
  o.quiet = true;
  study::runSweep(spec, dir, o, runner, testing::oneGrainDeposit);
}

/// An executable shell script standing in for gnuplot: `--version` succeeds, a script runs `body`.
fs::path fakeGnuplot(const fs::path& dir, const std::string& name, const std::string& body) {
  const fs::path p = dir / name;
  std::ofstream(p) << "#!/bin/sh\nif [ \"$1\" = --version ]; then echo 'gnuplot 0.0 fake'; exit 0; fi\n" << body;
  fs::permissions(p, fs::perms::owner_all);
  return p;
}

/// Entries of `dir` whose name starts with `prefix`.
std::vector<std::string> entriesStartingWith(const fs::path& dir, const std::string& prefix) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().starts_with(prefix)) found.push_back(e.path().filename().string());
  return found;
}

}  // namespace

TEST_CASE("report: a figure gnuplot fails on or draws as an empty file is named, and no SVG of it is kept") {
  ConfpackSession s("cmd_report_figures");
  makeSweep(s.dir / "sw");
  const std::vector<std::pair<std::string, std::string>> gnuplots = {
      {"exits 3", "echo 'cannot draw' >&2\nexit 3\n"},
      {"empty svg", ": > \"$(basename \"$1\" .gp).svg\"\nexit 0\n"},
      {"writes nothing", "exit 0\n"},
  };
  for (const auto& [name, body] : gnuplots) {
    INFO("gnuplot that " << name);
    const fs::path gnuplot = fakeGnuplot(s.dir, "gnuplot that " + name, body);
    const auto r = s.run("report sw --gnuplot '" + gnuplot.string() + "'");
    INFO("stderr: " << r.err);
    CHECK(r.code == 0);  // the report stands, each figure not drawn is said
    CHECK(r.err.find("confpack report: figure phi_vs_invW: gnuplot failed: ") != std::string::npos);
    CHECK(r.out.find("not drawn, see above") != std::string::npos);
    const fs::path figures = s.dir / "sw" / "report" / "figures";
    REQUIRE(fs::exists(figures / "phi_vs_invW.gp"));
    CHECK(entriesStartingWith(figures, "phi_vs_invW.svg").empty());
    for (const auto& e : fs::directory_iterator(figures)) CHECK(e.path().extension() != ".svg");
    CHECK(slurp(s.dir / "sw" / "report" / "report.html").find("gnuplot failed") != std::string::npos);
    CHECK(entriesStartingWith(s.dir / "sw", ".report.partial-").empty());
  }
}

TEST_CASE("report: the links to the run folders and the tables hold once the report is moved into place") {
  ConfpackSession s("cmd_report_links");
  makeSweep(s.dir / "sw");
  for (const std::string& out : {std::string("sw/report"), std::string("other/place/rep")}) {
    INFO(out);
    const std::string options = out == "sw/report" ? "" : " --out " + out;
    REQUIRE(s.run("report sw --no-figures" + options).code == 0);
    const fs::path report = s.dir / out;
    const std::string md = slurp(report / "report.md");
    std::size_t links = 0;
    for (std::size_t at = md.find("| [r"); at != std::string::npos; at = md.find("| [r", at + 1)) {
      const std::size_t open = md.find("](", at), close = md.find(')', open);
      const std::string name = md.substr(at + 3, open - at - 3), target = md.substr(open + 2, close - open - 2);
      INFO(name << " -> " << target);
      CHECK(fs::equivalent(report / target, s.dir / "sw" / "runs" / name));
      ++links;
    }
    CHECK(links == 4);
    CHECK(md.find("[tables/solid_fraction.csv](tables/solid_fraction.csv)") != std::string::npos);
    CHECK(fs::exists(report / "tables" / "solid_fraction.csv"));
    std::string staging = ".";  // appended, not "." + string: GCC 12 warns (-Wrestrict) on that
    staging += report.filename().string() + ".partial-";
    CHECK(entriesStartingWith(report.parent_path(), staging).empty());
  }
  // --no-run-links: the same run table with plain names, for a report published on its own.
  REQUIRE(s.run("report sw --no-figures --no-run-links --out published").code == 0);
  const std::string md = slurp(s.dir / "published" / "report.md");
  CHECK(md.find("| [r") == std::string::npos);
  CHECK(md.find("| r0000 |") != std::string::npos);
  CHECK(md.find("Sweep folder: sw (its run folders are not part of this report)") != std::string::npos);
}

TEST_CASE("report: SIGTERM or SIGKILL while gnuplot hangs leaves the previous report whole") {
  ConfpackSession s("cmd_report_interrupted");
  makeSweep(s.dir / "sw");
  REQUIRE(s.run("report sw --no-figures").code == 0);
  const fs::path report = s.dir / "sw" / "report";
  const std::string before = slurp(report / "report.html");
  REQUIRE(before.find("</html>") != std::string::npos);

  // This gnuplot says it has started (its pid in `started`), then hangs.
  const fs::path started = s.dir / "started";
  const fs::path gnuplot =
      fakeGnuplot(s.dir, "hanging gnuplot", "echo $$ > '" + started.string() + "'\nexec sleep 30\n");
  for (const int signal : {SIGTERM, SIGKILL}) {
    INFO("signal " << signal);
    fs::remove(started);
    const fs::path err = s.dir.string() + ".err";
    const pid_t pid = testing::startConfpack(s.dir, {"report", "sw", "--gnuplot", gnuplot.string()}, err);
    REQUIRE(pid >= 0);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (slurp(started).empty() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const std::string gnuplotPid = slurp(started);
    REQUIRE(!gnuplotPid.empty());
    ::kill(pid, signal);
    int status = 0;
    ::waitpid(pid, &status, 0);
    const std::string message = slurp(err);
    fs::remove(err);
    INFO("stderr: " << message);
    if (signal == SIGTERM) {
      REQUIRE(WIFEXITED(status));
      CHECK(WEXITSTATUS(status) == 143);
      CHECK(lineCount(message) == 1);
      CHECK(message.find("confpack report: error: interrupted by SIGTERM while ") != std::string::npos);
      // confpack killed its gnuplot on the way out, and removed its staging folder.
      CHECK(::kill(std::stoi(gnuplotPid), 0) != 0);
      CHECK(entriesStartingWith(s.dir / "sw", ".report.partial-").empty());
    } else {
      CHECK(WIFSIGNALED(status));
      ::kill(std::stoi(gnuplotPid), SIGKILL);  // orphaned by the kill: ours to end
    }
    // Either way the previous report is still there, whole and unchanged.
    CHECK(slurp(report / "report.html") == before);
    CHECK(entriesStartingWith(report / "figures", "phi_vs_invW.svg").empty());
  }
  // The next report removes the folder the SIGKILL left behind.
  REQUIRE(s.run("report sw --no-figures").code == 0);
  CHECK(entriesStartingWith(s.dir / "sw", ".report.partial-").empty());
}

TEST_CASE("report --reference: a bad reference file is refused by its field, exit 2, one line, nothing written") {
  ConfpackSession s("cmd_report_reference");
  makeSweep(s.dir / "sw");
  std::ofstream(s.dir / "typo.json") << R"json({"families": {"MSP": {"phi_bulk": {"value": 0.64, "uncertainty": 0.01,
    "citation": "Scott and Kilgour (1969)"}, "Zbulk": {"value": 6, "uncertainty": 0, "citation": "x"}}}})json";
  const auto r = s.run("report sw --no-figures --reference typo.json");
  CHECK(r.code == 2);
  CHECK(lineCount(r.err) == 1);
  CHECK(r.err ==
        "confpack report: error: typo.json: families.MSP.Zbulk: unknown key (known: x_S, mu_w, phi_bulk, C, Z_bulk, "
        "C_Z, lambda_L_over_d_avg)\n");
  CHECK_FALSE(fs::exists(s.dir / "sw" / "report"));
  const auto missing = s.run("report sw --no-figures --reference nowhere.json");
  CHECK(missing.code == 2);
  CHECK(missing.err ==
        "confpack report: error: nowhere.json: cannot open the reference file (No such file or directory)\n");
  CHECK_FALSE(fs::exists(s.dir / "sw" / "report"));

  // The example of the docs is accepted, and its values are in the summary.
  const fs::path example = fs::path(CONFPACK_SOURCE_DIR) / "docs" / "examples" / "reference-values.json";
  REQUIRE(s.run("report sw --no-figures --reference '" + example.string() + "'").code == 0);
  const std::string md = slurp(s.dir / "sw" / "report" / "report.md");
  CHECK(md.find("| phi_bulk | phi_bulk reference | C |") != std::string::npos);
  CHECK(md.find("| 0.64 ± 0.01 [1] |") != std::string::npos);
  CHECK(md.find("- [1] random close packing: G. D. Scott and D. M. Kilgour") != std::string::npos);
}

TEST_CASE("report: a hand-edited sweep.json that no longer holds is refused by field, exit 2, nothing written") {
  ConfpackSession s("cmd_report_bad_table");
  makeSweep(s.dir / "sweep");
  const fs::path table = s.dir / "sweep" / "sweep.json";
  json doc = json::parse(slurp(table));
  // Once "confpack report: error: stoul" (the deposit) and, without the sweep file, exit 1 after
  // the staging folder was made.
  doc["runs"][1]["deposit"] = "dx";
  std::ofstream(table) << doc.dump();
  const auto deposit = s.run("report sweep --no-figures");
  CHECK(deposit.code == 2);
  CHECK(deposit.err ==
        "confpack report: error: sweep/sweep.json: runs[1].deposit: expected \"d\" and the index of a "
        "deposit below the number of runs (got \"dx\")\n");
  doc["runs"][1]["deposit"] = "d0000";
  doc.erase("sweep");
  std::ofstream(table) << doc.dump();
  const auto sweep = s.run("report sweep --no-figures");
  CHECK(sweep.code == 2);
  CHECK(sweep.err == "confpack report: error: sweep/sweep.json: sweep: missing (the sweep file that made the table)\n");
  CHECK_FALSE(fs::exists(s.dir / "sweep" / "report"));
}

TEST_CASE(
    "report --compare: a key without two values is refused by name, exit 2, nothing written, and one with two "
    "is compared") {
  ConfpackSession s("cmd_report_compare");
  makeSweep(s.dir / "sw");  // nscd alone, seeds 1 and 2
  const auto one = s.run("report sw --no-figures --compare backend");
  CHECK(one.code == 2);
  CHECK(one.err ==
        "confpack report: error: --compare backend: the runs have 1 value of backend (nscd); a comparison needs "
        "exactly two\n");
  CHECK_FALSE(fs::exists(s.dir / "sw" / "report"));
  const auto none = s.run("report sw --no-figures --compare backend_options.solver");
  CHECK(none.code == 2);
  CHECK(lineCount(none.err) == 1);
  CHECK(none.err.find("no run's configuration has backend_options.solver") != std::string::npos);
  CHECK_FALSE(fs::exists(s.dir / "sw" / "report"));
  // The two seeds are two values: legal, if not a comparison anyone needs.
  REQUIRE(s.run("report sw --no-figures --compare seed").code == 0);
  const std::string md = slurp(s.dir / "sw" / "report" / "report.md");
  CHECK(md.find("| family | seed | runs at equilibrium / total |") != std::string::npos);
  CHECK(md.find("## Verdict: 1 against 2") != std::string::npos);
}

TEST_CASE(
    "report --lambda-from: a sweep of other configurations is refused by run and setting, exit 2, nothing written") {
  ConfpackSession s("cmd_report_lambda_from");
  makeSweep(s.dir / "sw");
  makeSweep(s.dir / "taller", 5.0);
  const auto r = s.run("report sw --no-figures --lambda-from taller");
  CHECK(r.code == 2);
  CHECK(r.err ==
        "confpack report: error: --lambda-from taller: run r0000 (MSP xS=0 W=4 mu=0 s1 nscd) is none of the study's "
        "configurations apart from its seed (first difference: box/height)\n");
  CHECK_FALSE(fs::exists(s.dir / "sw" / "report"));
  // A folder of the study's configurations is taken, the sweep folder after the option; these
  // made-up runs have no profile at the lambda width, so the report says the folder gave none.
  makeSweep(s.dir / "same");
  const auto same = s.run("report --no-figures --lambda-from same sw");
  REQUIRE(same.code == 0);
  CHECK_THAT(
      same.err,
      Catch::Contains("confpack report: --lambda-from same: no family's replicas at its lambda width, not used\n"));
}

TEST_CASE(
    "report --tables-from: a folder without report tables is refused, exit 2, nothing written, and one unused is "
    "said") {
  ConfpackSession s("cmd_report_tables_from");
  makeSweep(s.dir / "sw");
  fs::create_directories(s.dir / "empty");
  std::ofstream(s.dir / "empty" / "notes.csv") << "a,b\n1,2\n";  // a CSV, not a report's table
  const auto r = s.run("report sw --no-figures --tables-from empty");
  CHECK(r.code == 2);
  CHECK(lineCount(r.err) == 1);
  CHECK_THAT(r.err, Catch::StartsWith("confpack report: error: --tables-from empty: no report table in it"));
  CHECK_FALSE(fs::exists(s.dir / "sw" / "report"));
  const auto nowhere = s.run("report sw --no-figures --tables-from nowhere");
  CHECK(nowhere.code == 2);
  CHECK(nowhere.err == "confpack report: error: --tables-from nowhere: not a folder\n");
  // Every run of this sweep finished: a report's own tables have nothing to stand in for.
  REQUIRE(s.run("report sw --no-figures --out first").code == 0);
  const auto unused = s.run("report sw --no-figures --tables-from first/tables");
  REQUIRE(unused.code == 0);
  CHECK_THAT(unused.err, Catch::Contains("confpack report: --tables-from first/tables: every configuration of the "
                                         "sweep has finished runs of each side, or none of the tables' rows is one "
                                         "of them: not used\n"));
}
