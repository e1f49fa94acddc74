// Sweep engine: run-table expansion, slicing, resume after interruption, shared deposits.
// A fake runner (milliseconds per run) stands in for the physics; what is tested is the
// bookkeeping that makes a study survive kills and cluster slicing.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/json_input.hpp"
#include "core/packing_io.hpp"
#include "study/deposit_store.hpp"
#include "study/reproduce.hpp"
#include "study/sweep.hpp"
#include "tests/support/hash.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"

namespace fs = std::filesystem;
using namespace confpack;
using nlohmann::json;

namespace {

// 3 confinements x 2 seeds x 2 backends = 12 runs, 6 deposits.
json smallSweep() {
  return json::parse(R"({
    "format": "confpack-sweep", "version": 1, "name": "unit",
    "base": { "box": { "length_x": 6, "height": 4 } },
    "biperiodic_width": 6,
    "vary": { "width": [3, 5, "biperiodic"], "replicas": 2, "backend": ["nscd", "bullet"] }
  })");
}

// A deposit that depends on the configuration and seed only, inside the box.
compaction::Deposit fakeDeposit(const core::RunConfig& cfg) {
  compaction::Deposit d;
  for (int i = 0; i < 5; ++i) {
    core::Grain g;
    g.size = 1.0 + 0.01 * static_cast<double>((cfg.seed * 7 + i) % 5);
    g.position = core::Vec3(0.1 + 1.1 * i, 0.5 * cfg.box.width, 0.5 + 0.1 * static_cast<double>(cfg.seed) + 1.0 / 3.0);
    d.grains.push_back(g);
    d.placeholders.push_back(g.position);
  }
  d.placeholderDiameter = 1.1;
  d.pileHeight = 2.0 / 3.0 + static_cast<double>(cfg.seed);
  return d;
}

std::string depositDigest(const compaction::Deposit& d) {
  std::ostringstream s;
  s.precision(17);
  for (const core::Grain& g : d.grains) s << g.size << ' ' << g.position.transpose() << ';';
  s << d.pileHeight;
  return s.str();
}

// Records every call: run folder name -> number of calls, and the deposit each run received.
struct Recorder {
  std::mutex mutex;
  std::map<std::string, int> calls;
  std::map<std::string, std::string> deposits;
  int depositCalls = 0;
  std::set<std::string> throwOn;  // run names whose runner throws (an interruption)

  study::SweepRunFn runner() {
    return [this](const core::RunConfig& cfg, const fs::path& dir, const compaction::Deposit& dep,
                  const study::RunProgressFn& progress) {
      const std::string name = dir.filename().string();
      {
        std::lock_guard lock(mutex);
        ++calls[name];
        deposits[name] = depositDigest(dep);
      }
      if (progress) progress(0.5, "half");
      // Half a result is written before the interruption, as a real kill would leave it.
      json result = {{"solid_fraction", 0.6 + 0.001 * static_cast<double>(cfg.seed)}, {"backend", cfg.backend}};
      std::ofstream(dir / "result.json") << result.dump();
      {
        std::lock_guard lock(mutex);
        if (throwOn.count(name)) throw std::runtime_error("interrupted");
      }
      return result;
    };
  }
  study::SweepDepositFn depositor() {
    return [this](const core::RunConfig& cfg) {
      std::lock_guard lock(mutex);
      ++depositCalls;
      return fakeDeposit(cfg);
    };
  }
};

study::SweepOptions quietOptions(int jobs = 1) {
  study::SweepOptions o;
  o.jobs = jobs;
  o.quiet = true;
  return o;
}

}  // namespace

TEST_CASE("run table: counts, stable names, backend fastest, shared deposits") {
  const study::SweepSpec spec = study::parseSweepSpec(smallSweep());
  const auto runs = study::expandRuns(spec);
  REQUIRE(runs.size() == 12);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    CHECK(runs[i].index == i);
    char expected[8];
    std::snprintf(expected, sizeof expected, "r%04zu", i);
    CHECK(runs[i].name == expected);
    CHECK(runs[i].config.backend == (i % 2 == 0 ? "nscd" : "bullet"));
    CHECK(runs[i].depositIndex == i / 2);  // the two backends of one (config, seed) share a deposit
  }
  CHECK(runs[0].config.box.width == 3.0);
  CHECK_FALSE(runs[0].config.box.periodicY);
  CHECK(runs[0].config.seed == 1);
  CHECK(runs[2].config.seed == 2);
  CHECK(runs[11].config.box.periodicY);
  CHECK(runs[11].config.box.width == 6.0);
  CHECK(runs[11].config.box.lengthX == 6.0);  // base value kept

  // Expanding again gives the same table: names never depend on anything but the order.
  const auto again = study::expandRuns(study::parseSweepSpec(smallSweep()));
  for (std::size_t i = 0; i < runs.size(); ++i) {
    json a, b;
    core::to_json(a, runs[i].config);
    core::to_json(b, again[i].config);
    CHECK(a == b);
    CHECK(runs[i].name == again[i].name);
  }
}

TEST_CASE("run table: groups are unioned without duplicates, mu_w variants share the deposit") {
  const json doc = json::parse(R"({
    "groups": [
      { "width": [5, 10], "small_fraction": [0, 25], "backend": "nscd" },
      { "width": [5], "small_fraction": [0], "wall_friction": [0, 0.5], "backend": "nscd" }
    ]})");
  const auto runs = study::expandRuns(study::parseSweepSpec(doc));
  // 4 from the first group; the second adds only mu_w = 0.5 (mu_w = 0 duplicates r0000).
  REQUIRE(runs.size() == 5);
  CHECK(runs[4].config.walls.friction == 0.5);
  CHECK(runs[4].config.box.width == 5.0);
  CHECK(runs[4].config.population.smallFraction == 0.0);
  // Deposition is geometric and ignores mu_w: r0004 compacts r0000's deposit.
  CHECK(runs[4].depositIndex == runs[0].depositIndex);
  std::set<std::size_t> deposits;
  for (const auto& r : runs) deposits.insert(r.depositIndex);
  CHECK(deposits.size() == 4);
}

TEST_CASE("sweep file: bad input is refused with a message naming the field") {
  auto message = [](const json& doc) {
    try {
      study::expandRuns(study::parseSweepSpec(doc, "s.json"));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  using Catch::Matchers::Contains;
  CHECK_THAT(message(json::parse(R"({"vary": {"width": [0]}})")), Contains("vary.width"));
  CHECK_THAT(message(json::parse(R"({"vary": {"width": ["wide"]}})")), Contains("vary.width"));
  CHECK_THAT(message(json::parse(R"({"vary": {"widht": [5]}})")), Contains("vary.widht"));
  CHECK_THAT(message(json::parse(R"({"vary": {"backend": ["ode"]}})")), Contains("vary.backend"));
  CHECK_THAT(message(json::parse(R"({"vary": {"small_fraction": [120]}})")), Contains("vary.small_fraction"));
  CHECK_THAT(message(json::parse(R"({"vary": {"shape": ["cube"]}})")), Contains("vary.shape"));
  CHECK_THAT(message(json::parse(R"({"vary": {"seed": [1], "replicas": 2}})")), Contains("replicas"));
  CHECK_THAT(message(json::parse(R"({"base": {"box": {"widht": 5}}, "vary": {}})")), Contains("base.box.widht"));
  CHECK_THAT(message(json::parse(R"({"base": {"box": {"length_x": -1}}, "vary": {}})")), Contains("length_x"));
  CHECK_THAT(message(json::parse(R"({"vary": {}, "groups": [{}]})")), Contains("vary"));
  CHECK_THAT(message(json::parse(R"({"vary": {}, "colour": 1})")), Contains("colour"));
  CHECK(message(json::parse(R"({"vary": {"width": [5, "biperiodic"]}})")) == "accepted");
  // The header is optional, and checked when given; every refusal is the full "file: field: what".
  CHECK(message(json::parse(R"({"format": "confpack-sweep", "version": 1, "vary": {}})")) == "accepted");
  CHECK(message(json::parse(R"({"format": "confpack-packing", "vary": {}})")) ==
        "s.json: format: must be \"confpack-sweep\" (got \"confpack-packing\")");
  CHECK(message(json::parse(R"({"version": 2, "vary": {}})")) ==
        "s.json: version: must be 1, the version this build reads (got 2)");
  CHECK(message(json::parse(R"({"vary": {}, "colour": 1})")) ==
        "s.json: colour: unknown key (known: format, version, name, description, base, biperiodic_width, vary, "
        "groups, settle_with, equal_time)");
  CHECK(message(json::parse("[]")) == "s.json: document: must be a JSON object (got array)");
  CHECK(message(json::parse(R"({"name": 3, "vary": {}})")) == "s.json: name: must be a string (got 3)");
  CHECK(message(json::parse(R"({"name": "", "vary": {}})")) == "s.json: name: must be a non-empty string (got \"\")");
  CHECK(message(json::parse(R"({"base": [], "vary": {}})")) == "s.json: base: must be a JSON object (got array)");
  CHECK(message(json::parse(R"({"base": {"box": {"widht": 5}}, "vary": {}})")) ==
        "s.json: base.box.widht: unknown key (known: height, length_x, periodic_y, width)");
  CHECK(message(json::parse(R"({"biperiodic_width": 0, "vary": {}})")) ==
        "s.json: biperiodic_width: must be > 0 (got 0)");
  CHECK(message(json::parse(R"({"vary": []})")) == "s.json: vary: must be a JSON object (got array)");
  CHECK(message(json::parse(R"({"groups": []})")) ==
        "s.json: groups: must hold at least one group (an object of value lists)");
  // Only nscd has the finisher that brings any pile to rest.
  CHECK_THAT(message(json::parse(R"({"vary": {}, "settle_with": "bullet"})")),
             Contains("s.json: settle_with: expected \"nscd\""));
  CHECK_THAT(message(json::parse(R"({"vary": {}, "settle_with": 1})")), Contains("settle_with"));
  CHECK(message(json::parse(R"({"vary": {}, "settle_with": "nscd"})")) == "accepted");
  CHECK(study::parseSweepSpec(json::parse(R"({"vary": {}, "settle_with": "nscd"})")).settleWith == "nscd");
}

TEST_CASE("a sweep listing more runs than the limit is refused before any run is listed") {
  // Issue 23, failure 6: "replicas": 100000000 needed more than 4 GB just to list the runs.
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(
      study::parseSweepSpec(json::parse(R"({"vary": {"width": [4, 5], "replicas": 100000000}})"), "s.json"),
      "s.json: vary: lists 2e+08 runs, more than the limit of 100000 (check the lists and replicas, "
      "or raise the limit with --max-runs)");
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(1));
  // The limit counts the product of a group's lists (replicas before they are listed), and the
  // groups' sum; duplicates count too.
  const json groups = json::parse(R"({"groups": [{"width": [4, 5], "seed": [1, 2, 3]},
                                                 {"width": [4], "backend": ["nscd", "bullet"], "replicas": 3}]})");
  CHECK_THROWS_WITH(study::parseSweepSpec(groups, "s.json", 5), Catch::StartsWith("s.json: groups[1]: lists 6 runs"));
  CHECK_THROWS_WITH(study::parseSweepSpec(groups, "s.json", 11), Catch::StartsWith("s.json: groups: lists 12 runs"));
  CHECK(study::expandRuns(study::parseSweepSpec(groups, "s.json", 12)).size() == 9);  // 3 duplicates dropped
}

TEST_CASE("slicing covers every run exactly once and keeps deposit groups together") {
  const auto runs = study::expandRuns(study::parseSweepSpec(smallSweep()));
  for (std::size_t k = 1; k <= 7; ++k) {
    std::map<std::size_t, int> seen;
    std::map<std::size_t, std::size_t> taskOfDeposit;
    for (std::size_t t = 0; t < k; ++t)
      for (std::size_t i : study::sliceRuns(runs, t, k)) {
        ++seen[i];
        const auto [it, inserted] = taskOfDeposit.try_emplace(runs[i].depositIndex, t);
        CHECK(it->second == t);
      }
    CHECK(seen.size() == runs.size());
    for (const auto& [i, n] : seen) CHECK(n == 1);
  }
  CHECK_THROWS_AS(study::sliceRuns(runs, 3, 3), std::invalid_argument);
  CHECK_THROWS_AS(study::sliceRuns(runs, 0, 0), std::invalid_argument);
}

TEST_CASE("interrupted sweep resumes: finished runs are never redone, unfinished ones are") {
  const fs::path dir = confpack::testing::scratchPath("sweep_resume");
  const study::SweepSpec spec = study::parseSweepSpec(smallSweep());
  Recorder rec;
  rec.throwOn = {"r0003", "r0008"};
  const study::SweepSummary first = study::runSweep(spec, dir, quietOptions(), rec.runner(), rec.depositor());
  CHECK(first.total == 12);
  CHECK(first.ran == 10);
  CHECK(first.failed == 2);
  CHECK(study::runStatus(dir / "runs" / "r0003") == study::RunStatus::Failed);
  CHECK(study::runStatus(dir / "runs" / "r0000") == study::RunStatus::Done);
  // r0003 has a result.json but no done marker: it must not count as finished.
  CHECK(fs::exists(dir / "runs" / "r0003" / "result.json"));

  // A kill in the middle of a run leaves a folder with a result but no marker.
  fs::remove(dir / "runs" / "r0005" / study::kDoneMarker);
  CHECK(study::runStatus(dir / "runs" / "r0005") == study::RunStatus::Incomplete);

  rec.throwOn.clear();
  const study::SweepSummary second = study::runSweep(spec, dir, quietOptions(), rec.runner(), rec.depositor());
  CHECK(second.alreadyDone == 9);
  CHECK(second.ran == 3);
  CHECK(second.failed == 0);
  for (const auto& [name, n] : rec.calls) {
    INFO(name);
    CHECK(n == ((name == "r0003" || name == "r0005" || name == "r0008") ? 2 : 1));
  }
  CHECK(rec.calls.size() == 12);
  // Deposits were made once per group; the resumed runs read them back from disk.
  CHECK(rec.depositCalls == 6);

  // A third invocation finds nothing to do.
  const study::SweepSummary third = study::runSweep(spec, dir, quietOptions(), rec.runner(), rec.depositor());
  CHECK(third.ran == 0);
  CHECK(third.alreadyDone == 12);
  fs::remove_all(dir);
}

TEST_CASE("both backends of one (configuration, seed) compact the same deposit, also after a resume") {
  const fs::path dir = confpack::testing::scratchPath("sweep_deposit");
  const study::SweepSpec spec = study::parseSweepSpec(smallSweep());
  const auto runs = study::expandRuns(spec);
  Recorder rec;
  rec.throwOn = {"r0001"};  // bullet's run of deposit d0000 fails the first time
  study::runSweep(spec, dir, quietOptions(2), rec.runner(), rec.depositor());
  const std::string firstDigest = rec.deposits.at("r0000");
  rec.throwOn.clear();
  study::runSweep(spec, dir, quietOptions(2), rec.runner(), rec.depositor());
  // Read back from deposits/d0000.json bit for bit.
  CHECK(rec.deposits.at("r0001") == firstDigest);
  for (const auto& r : runs) {
    const auto& partner = runs[r.index ^ 1u];
    CHECK(rec.deposits.at(r.name) == rec.deposits.at(partner.name));
    CHECK(rec.deposits.at(r.name) == depositDigest(fakeDeposit(r.config)));
  }
  // Different seeds give different deposits (the digest is not trivially constant).
  CHECK(rec.deposits.at("r0000") != rec.deposits.at("r0002"));
  fs::remove_all(dir);
}

TEST_CASE("job-array slices run separately in one folder finish the study, parallel jobs run each once") {
  const fs::path dir = confpack::testing::scratchPath("sweep_slices");
  const study::SweepSpec spec = study::parseSweepSpec(smallSweep());
  Recorder rec;
  std::size_t ran = 0;
  for (std::size_t t = 0; t < 3; ++t) {
    study::SweepOptions o = quietOptions(2);
    o.taskIndex = t;
    o.taskCount = 3;
    const auto s = study::runSweep(spec, dir, o, rec.runner(), rec.depositor());
    CHECK(s.inSlice == 4);
    ran += s.ran;
  }
  CHECK(ran == 12);
  CHECK(rec.calls.size() == 12);
  for (const auto& [name, n] : rec.calls) CHECK(n == 1);
  const std::string listing = study::formatRunTable(study::readRunTable(dir), dir);
  CHECK(listing.find("pending") == std::string::npos);
  CHECK(listing.find("r0011") != std::string::npos);

  // The folder belongs to this sweep: another sweep file is refused there.
  json other = smallSweep();
  other["vary"]["width"] = json::array({4});
  CHECK_THROWS_AS(study::runSweep(study::parseSweepSpec(other), dir, quietOptions(), rec.runner(), rec.depositor()),
                  std::invalid_argument);
  fs::remove_all(dir);
}

TEST_CASE("progress: one line per finished run in the documented form") {
  const fs::path dir = confpack::testing::scratchPath("sweep_progress");
  json doc = smallSweep();
  doc["vary"]["width"] = json::array({5});
  doc["vary"]["replicas"] = 1;
  Recorder rec;
  std::ostringstream log;
  study::SweepOptions o;
  o.log = &log;
  study::runSweep(study::parseSweepSpec(doc), dir, o, rec.runner(), rec.depositor());
  const std::string text = log.str();
  CHECK(text.find("[1/2] r0000 nscd W=5 phi=0.601") != std::string::npos);
  CHECK(text.find("[2/2] r0001 bullet W=5 phi=0.601") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("sweep files over the named axes alone give the run tables they gave before setting axes existed") {
  // The fingerprint of `--list` and of sweep.json (the run table with each run's label and
  // resolved configuration) for the study's three scales and the example of docs/sweeps.md,
  // recorded with the code before any configuration key could be an axis: those files must keep
  // naming the same runs, in the same folders, with the same labels. Recorded again when mu_w moved
  // from box.wall_friction to walls.friction: the sweep.json of the docs example was compared run
  // by run with the one of the code before, and differed by that move alone. Recorded again when
  // deposition.grain_cap came (0 in these files): the paper scale's sweep.json differed from the
  // one before in that key alone.
  const json docsExample = json::parse(R"({
    "format": "confpack-sweep", "version": 1, "name": "confinement",
    "base": { "box": { "length_x": 20, "height": 16 }, "compaction": { "time_limit": 400 }, "backend_options": { } },
    "biperiodic_width": 20,
    "groups": [
      { "shape": ["sphere"], "small_fraction": [0, 10, 25, 40], "width": [5, 10, 20, "biperiodic"],
        "wall_friction": [0], "replicas": 3, "backend": ["nscd", "bullet"] },
      { "shape": ["sphere"], "small_fraction": [0], "width": [5, 10, 20],
        "wall_friction": [0.3, 0.5, 1.0], "replicas": 3, "backend": ["nscd", "bullet"] } ] })");
  const std::vector<std::pair<std::string, json>> files = {{"tiny", study::reproductionSweep("tiny")},
                                                           {"quick", study::reproductionSweep("quick")},
                                                           {"paper", study::reproductionSweep("paper")},
                                                           {"docs", docsExample},
                                                           {"unit", smallSweep()}};
  const fs::path dir = confpack::testing::scratchPath("sweep_golden");
  confpack::testing::Fnv1a hash;
  for (const auto& [name, doc] : files) {
    const study::SweepSpec spec = study::parseSweepSpec(doc, name);
    const auto runs = study::expandRuns(spec);
    hash.mix(study::formatRunTable(runs));
    study::prepareSweepDir(dir / name, spec, runs);
    std::ifstream in(dir / name / study::kSweepTable);
    std::ostringstream text;
    text << in.rdbuf();
    hash.mix(text.str());
  }
  fs::remove_all(dir);
  CHECK(hash.value == 0x4cff47dadc0a25c0ull);
}

TEST_CASE("setting axes: any key of the run configuration, by its path, expanded after mu_w and before the seeds") {
  const json doc = json::parse(R"({
    "base": { "box": { "length_x": 6, "height": 4 }, "population": { "shape": "pinacoid" } },
    "vary": { "width": ["biperiodic"], "population.pinacoid.alpha_deg": [45, 60, 75], "population.pinacoid.E": [0.5],
              "compaction.protocol": ["dynamic", "quasi-static"], "backend_options.tolerance": 1e-8,
              "replicas": 2, "backend": "nscd" } })");
  const auto runs = study::expandRuns(study::parseSweepSpec(doc, "s.json"));
  // The axes nest in the order of their paths (backend_options, compaction, population.pinacoid.E,
  // population.pinacoid.alpha_deg), the first slowest, then the seeds: 2 x 3 x 2 runs.
  REQUIRE(runs.size() == 12);
  const std::vector<double> alpha = {45, 45, 60, 60, 75, 75};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    INFO(runs[i].name);
    const core::RunConfig& c = runs[i].config;
    CHECK(c.population.pinacoid.alphaDeg == alpha[i % 6]);
    CHECK(c.population.pinacoid.heightRatio == 0.5);
    CHECK(c.compaction.protocol == (i < 6 ? core::Protocol::Dynamic : core::Protocol::QuasiStatic));
    CHECK(c.backendOptions == json{{"tolerance", 1e-8}});
    CHECK(c.seed == 1 + i % 2);
    CHECK(c.box.periodicY);
    CHECK(c.box.lengthX == 6.0);  // the base's
  }
  // The protocol acts after the deposit: the runs that differ in it alone compact the same pile;
  // alpha changes the grains, and so the deposit.
  CHECK(runs[0].depositIndex == runs[6].depositIndex);
  CHECK(runs[0].depositIndex != runs[2].depositIndex);
  // What varies is named in the run table and the labels, under the shortest unambiguous names.
  const std::vector<std::string> varied = study::variedSettings(runs);
  CHECK(varied == std::vector<std::string>{"compaction.protocol", "population.pinacoid.alpha_deg"});
  CHECK(study::settingNames(varied) == std::vector<std::string>{"protocol", "alpha_deg"});
  CHECK(study::settingNames({"population.pinacoid.E", "deposition.E", "seed"}) ==
        std::vector<std::string>{"pinacoid.E", "deposition.E", "seed"});
  CHECK(runs[7].label(varied) == "MPP xS=0 W=bi20 mu=0 s2 nscd protocol=quasi-static alpha_deg=45");
  const std::string table = study::formatRunTable(runs);
  CHECK_THAT(table,
             Catch::StartsWith("run     deposit family   x_S        W  mu_w   seed backend protocol     alpha_deg\n"
                               "r0000   d0000   MPP        0     bi20     0      1 nscd    dynamic      45       \n"));
  CHECK_THAT(table,
             Catch::Contains("r0011   d0005   MPP        0     bi20     0      2 nscd    quasi-static 75       \n"));
  // A sweep over the named axes alone varies no other setting.
  CHECK(study::variedSettings(study::expandRuns(study::parseSweepSpec(smallSweep()))).empty());
}

TEST_CASE("a sweep with a grain cap fits each run's box, and the fitted length is no setting of its own") {
  const json doc = json::parse(R"({
    "format": "confpack-sweep", "version": 1, "name": "capped",
    "base": { "box": { "length_x": 12, "height": 12 }, "deposition": { "grain_cap": 3000 } },
    "vary": { "width": [5, 20], "small_fraction": [0, 40], "backend": ["nscd"] }
  })");
  const auto runs = study::expandRuns(study::parseSweepSpec(doc));
  REQUIRE(runs.size() == 4);
  for (const study::SweepRun& r : runs) {
    INFO(r.name);
    CHECK(r.config.estimatedGrainCount() <= 3000.0);
    // Only a box that would hold more is shortened: monodisperse at W = 5 holds about 820.
    const bool over = r.config.box.width == 20.0 || r.config.population.smallFraction > 0.0;
    CHECK((r.config.box.lengthX < 12.0) == over);
    if (over) CHECK(r.config.estimatedGrainCount() > 0.99 * 3000.0);
  }
  // L_x follows from W and x_S, which have their own columns: the report groups by those alone.
  CHECK(study::variedSettings(runs).empty());
  // Where the cap itself varies, so does the length, and both are named.
  json two = doc;
  two["base"] = {{"box", {{"length_x", 12}, {"height", 12}}}};
  two["vary"] = {{"width", {20}}, {"deposition.grain_cap", {3000, 4000}}, {"backend", {"nscd"}}};
  CHECK(study::variedSettings(study::expandRuns(study::parseSweepSpec(two))) ==
        std::vector<std::string>{"box.length_x", "deposition.grain_cap"});
}

TEST_CASE("setting axes: an unknown path or a value the configuration's readers refuse is refused by name") {
  auto message = [](const std::string& vary) {
    try {
      study::expandRuns(study::parseSweepSpec(json::parse(R"({"vary": )" + vary + "}"), "s.json"));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  CHECK(message(R"({"population.pinacoid.alpha": [45]})") ==
        "s.json: vary.population.pinacoid.alpha: unknown configuration path: population.pinacoid has no key alpha "
        "(its keys: E, G, alpha_deg)");
  CHECK(message(R"({"colour": [1]})") ==
        "s.json: vary.colour: unknown key (known: width, shape, small_fraction, wall_friction, seed, replicas, "
        "backend, or a path of the run configuration under backend, backend_options, box, compaction, deposition, "
        "population, seed, threads, walls)");
  CHECK(message(R"({"box.width.x": [1]})") ==
        "s.json: vary.box.width.x: unknown configuration path: box.width is a setting, not a section");
  CHECK(message(R"({"population.pinacoid": [{"E": 1}]})") ==
        "s.json: vary.population.pinacoid: population.pinacoid is a section, not a setting: give one of its keys (E, "
        "G, alpha_deg)");
  CHECK(message(R"({"population..shape": ["sphere"]})") ==
        "s.json: vary.population..shape: not a configuration path (keys of config.json joined by '.', e.g. "
        "population.pinacoid.alpha_deg)");
  CHECK(message(R"({"compaction.protocol": ["fast"]})") ==
        "s.json: vary.compaction.protocol: compaction.protocol: must be \"dynamic\" or \"quasi-static\" (got "
        "\"fast\")");
  CHECK(message(R"({"compaction.time_limit": [-1]})") ==
        "s.json: vary.compaction.time_limit: compaction.time_limit: must be in (0, 1e+09] (got -1)");
  CHECK(message(R"({"population.pinacoid.alpha_deg": ["sixty"]})") ==
        "s.json: vary.population.pinacoid.alpha_deg: expected a number (got \"sixty\")");
  CHECK(message(R"({"compaction.adaptive_dt": [1]})") ==
        "s.json: vary.compaction.adaptive_dt: expected true or false (got 1)");
  CHECK(message(R"({"population.pinacoid.alpha": []})") == "s.json: vary.population.pinacoid.alpha: empty list");
  // Backend options: a key one of the backends knows, a value it accepts; a run whose own backend
  // does not know the key is refused with the run named.
  CHECK_THAT(message(R"({"backend_options.tolerence": [1e-8]})"),
             Catch::StartsWith("s.json: vary.backend_options.tolerence: ") && Catch::Contains("unknown key"));
  CHECK_THAT(message(R"({"backend_options.tolerance": [-1]})"),
             Catch::StartsWith("s.json: vary.backend_options.tolerance: nscd.tolerance: must be"));
  CHECK(message(R"({"backend_options.tolerance.x": [1]})") ==
        "s.json: vary.backend_options.tolerance.x: a backend option is one key deep: backend_options.KEY (confpack "
        "options nscd, or bullet)");
  CHECK(message(R"({"backend_options.tolerance": [1e-8], "backend": ["nscd"]})") == "accepted");
  CHECK_THAT(message(R"({"backend_options.tolerance": [1e-8], "backend": ["nscd", "bullet"]})"),
             Catch::StartsWith(
                 "sweep run r0001 (MSP xS=0 W=10 mu=0 s1 bullet): bullet.tolerance: a setting of nscd, not of bullet"));
  // A named axis and its path in one group would fight over the setting.
  CHECK(message(R"({"small_fraction": [0], "population.small_fraction": [10]})") ==
        "s.json: vary.population.small_fraction: small_fraction and population.small_fraction vary the same setting: "
        "give one of them");
  // A combination the configuration cannot build is the run's to refuse: alpha = 45 degrees leaves
  // no ridge on a pinacoid as tall as it is long (E = 1), and is fine with E = 0.5.
  CHECK(message(R"({"shape": "pinacoid", "population.pinacoid.alpha_deg": [45], "population.pinacoid.E": [0.5]})") ==
        "accepted");
  CHECK_THAT(message(R"({"shape": "pinacoid", "population.pinacoid.alpha_deg": [45, 60]})"),
             Catch::StartsWith("sweep run r0000 (MPP xS=0 W=10 mu=0 s1 nscd alpha_deg=45): pinacoid: with E=1 and "
                               "alpha=45 deg the ridge half-length"));
}

// A study folder started before the walls had their own object holds mu_w as box.wall_friction
// in its sweep.json: the same sweep file still resumes it, another one is still refused.
TEST_CASE("sweep table: a folder whose table spells mu_w the earlier way resumes, a different sweep does not") {
  const study::SweepSpec spec = study::parseSweepSpec(json::parse(R"({"name": "mu", "base": {"box": {"length_x": 3}},
    "vary": {"width": [3], "wall_friction": [0, 0.5], "backend": "nscd"}})"));
  const std::vector<study::SweepRun> runs = study::expandRuns(spec);
  const fs::path dir = confpack::testing::scratchPath("sweep_legacy_table");
  fs::remove_all(dir);
  study::prepareSweepDir(dir, spec, runs);
  json table = json::parse(confpack::testing::slurp(dir / study::kSweepTable));
  for (json& r : table["runs"]) {
    r["config"]["box"]["wall_friction"] = r["config"]["walls"]["friction"];
    r["config"].erase("walls");
  }
  CHECK(table["runs"][1]["config"]["box"]["wall_friction"] == 0.5);
  std::ofstream(dir / study::kSweepTable) << table.dump(1);
  CHECK_NOTHROW(study::prepareSweepDir(dir, spec, runs));
  table["runs"][1]["config"]["box"]["wall_friction"] = 0.3;  // not the sweep this file makes
  std::ofstream(dir / study::kSweepTable) << table.dump(1);
  CHECK_THROWS_WITH(study::prepareSweepDir(dir, spec, runs), Catch::Contains("holds a different sweep"));
  fs::remove_all(dir);
}

TEST_CASE("sweep table: what prepareSweepDir writes reads back, and a hand-edited table is refused by field") {
  const study::SweepSpec spec = study::parseSweepSpec(smallSweep());
  const std::vector<study::SweepRun> runs = study::expandRuns(spec);
  const json doc = study::runTableDocument(spec, runs);
  study::SweepSpec back;
  const std::vector<study::SweepRun> read = study::parseRunTable(doc, "t/sweep.json", &back);
  CHECK(study::runTableDocument(back, read) == doc);
  REQUIRE(read.size() == runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    CHECK(read[i].name == runs[i].name);
    CHECK(read[i].depositIndex == runs[i].depositIndex);
    CHECK(json(read[i].config) == json(runs[i].config));
  }
  // Each edit once came out as nlohmann's or the standard library's words without the file (key
  // 'deposit' not found, stoul, basic_string::substr), or was taken: a name that leaves runs/,
  // two runs of one name (the report counted the folder twice), a box key misspelt.
  const std::vector<std::pair<std::function<void(json&)>, std::string>> edits = {
      {[](json& d) { d["runs"][0].erase("deposit"); }, "t/sweep.json: runs[0].deposit: missing"},
      {[](json& d) { d["runs"][0]["deposit"] = ""; }, "t/sweep.json: runs[0].deposit: expected \"d\""},
      {[](json& d) { d["runs"][0]["deposit"] = "dx"; }, "t/sweep.json: runs[0].deposit: expected \"d\""},
      {[](json& d) { d["runs"][0]["deposit"] = "d0099"; }, "t/sweep.json: runs[0].deposit: expected \"d\""},
      {[](json& d) { d["runs"][1]["name"] = 3; }, "t/sweep.json: runs[1].name: expected a run folder's name"},
      {[](json& d) { d["runs"][1]["name"] = "../../x"; }, "t/sweep.json: runs[1].name: expected a run folder's name"},
      {[](json& d) { d["runs"][1]["name"] = "r0000"; }, "t/sweep.json: runs[1].name: \"r0000\" names two runs"},
      {[](json& d) { d["runs"][2] = "hello"; }, "t/sweep.json: runs[2]: must be a JSON object (got string)"},
      {[](json& d) { d["runs"][2]["colour"] = 1; },
       "t/sweep.json: runs[2].colour: unknown key (known: name, deposit, label, config)"},
      {[](json& d) { d["runs"][2]["config"]["box"]["widht"] = 3; },
       "t/sweep.json: runs[2].config: box.widht: unknown key"},
      {[](json& d) { d["runs"][2]["config"]["box"]["width"] = -3; }, "t/sweep.json: runs[2].config: "},
      {[](json& d) { d.erase("sweep"); }, "t/sweep.json: sweep: missing (the sweep file that made the table)"},
      {[](json& d) { d["sweep"] = 5; }, "t/sweep.json: sweep: document: must be a JSON object (got number)"},
      {[](json& d) { d["runs"] = json::object(); }, "t/sweep.json: runs: must be an array (got object)"},
      {[](json& d) { d.erase("format"); }, "t/sweep.json: format: missing (expected \"confpack-sweep-table\")"},
      {[](json& d) { d["version"] = 2; }, "t/sweep.json: version: must be 1, the version this build reads (got 2)"},
      {[](json& d) { d["colour"] = 1; },
       "t/sweep.json: colour: unknown key (known: format, version, name, sweep, runs)"},
      {[](json& d) { d["format"] = "confpack-sweep"; },
       "t/sweep.json: format: must be \"confpack-sweep-table\" (got \"confpack-sweep\")"},
  };
  for (const auto& [edit, message] : edits) {
    json edited = doc;
    edit(edited);
    INFO(message);
    CHECK_THROWS_WITH(study::parseRunTable(edited, "t/sweep.json"), Catch::StartsWith(message));
  }
  // The version may be left out (the format may not).
  json noVersion = doc;
  noVersion.erase("version");
  CHECK_NOTHROW(study::parseRunTable(noVersion, "t/sweep.json"));
}

TEST_CASE("the sweep.json seeds of the fuzz corpus are accepted tables") {
  int seeds = 0;
  for (const auto& entry : fs::directory_iterator(CONFPACK_SOURCE_DIR "/fuzz/corpus/sweep_table")) {
    INFO(entry.path());
    study::SweepSpec spec;
    const auto runs = study::parseRunTable(core::readJsonFile(entry.path(), "sweep table"), "seed", &spec);
    CHECK(!runs.empty());
    ++seeds;
  }
  CHECK(seeds >= 4);
}

TEST_CASE("a run claimed by another live process is left to it, a dead holder's claim is taken over") {
  const fs::path dir = confpack::testing::scratchPath("sweep_claims");
  const study::SweepSpec spec = study::parseSweepSpec(smallSweep());
  const auto runs = study::expandRuns(spec);
  fs::create_directories(study::claimsDir(dir));
  // r0002 is held by a live holder elsewhere, r0005 by one that died; the test's judge says which.
  study::ClaimHolder live{"node7", 100, 0, "41_2", "live-token", "2024-01-01T00:00:00Z"};
  study::ClaimHolder dead{"node8", 200, 0, "40_5", "dead-token", "2024-01-01T00:00:00Z"};
  std::ofstream(study::claimsDir(dir) / "r0002") << study::toJson(live).dump();
  std::ofstream(study::claimsDir(dir) / "r0005") << study::toJson(dead).dump();
  study::SweepOptions o = quietOptions(2);
  o.runs = {0, 2, 4, 5};
  o.alive = [](const study::ClaimHolder& h) {
    return h.token == "dead-token" ? study::Liveness::Dead : study::Liveness::Alive;
  };
  Recorder rec;
  const study::SweepSummary s = study::runSweep(spec, dir, o, rec.runner(), rec.depositor());
  CHECK(s.inSlice == 4);
  CHECK(s.ran == 3);
  CHECK(s.heldElsewhere == 1);
  CHECK(rec.calls == std::map<std::string, int>{{"r0000", 1}, {"r0004", 1}, {"r0005", 1}});
  CHECK_FALSE(fs::exists(dir / "runs" / "r0002"));
  CHECK(study::runStatus(dir / "runs" / "r0005") == study::RunStatus::Done);
  // The live holder's claim is untouched; the runs done here gave up their claims.
  REQUIRE(study::readClaim(study::claimsDir(dir), "r0002"));
  CHECK(study::readClaim(study::claimsDir(dir), "r0002")->token == "live-token");
  for (const char* r : {"r0000", "r0004", "r0005"}) CHECK_FALSE(study::readClaim(study::claimsDir(dir), r));
  fs::remove_all(dir);
}

// A sweep file written before the walls had their own object sets mu_w as base.box.wall_friction.
TEST_CASE("a sweep file's base with box.wall_friction sets walls.friction, and both given are refused") {
  const study::SweepSpec spec =
      study::parseSweepSpec(json::parse(R"({"name": "old", "base": {"box": {"wall_friction": 0.3}},
    "vary": {"width": [5], "backend": "nscd"}})"));
  const auto runs = study::expandRuns(spec);
  REQUIRE(runs.size() == 1);
  CHECK(runs[0].config.walls.friction == 0.3);
  CHECK_THROWS_WITH(study::parseSweepSpec(json::parse(R"({"name": "both",
    "base": {"box": {"wall_friction": 0.3}, "walls": {"friction": 0.3}}, "vary": {"width": [5]}})")),
                    Catch::Contains("base: box.wall_friction: given twice"));
}

namespace {

// A sweep of both backends with equal_time, Bullet first in the table (its runs must still wait
// for nscd's): 2 widths x 2 seeds x 2 backends = 8 runs.
json equalTimeSweep() {
  return json::parse(R"({
    "format": "confpack-sweep", "version": 1, "name": "equal",
    "base": { "box": { "length_x": 6, "height": 4 }, "compaction": { "time_limit": 20 } },
    "biperiodic_width": 6, "equal_time": "nscd",
    "vary": { "width": [3, "biperiodic"], "replicas": 2, "backend": ["bullet", "nscd"] }
  })");
}

// nscd's fall time on a run's deposit in the fake runner: distinct for every (width, seed) [t0].
double fakeFallTime(const core::RunConfig& cfg) {
  return 7.0 + static_cast<double>(cfg.seed) + 0.25 * cfg.box.width;
}

// Runs of the fake physics, recording each run's time limit and the order the runs started in;
// nscd's result gives fakeFallTime as its fall's time, and runs named in `failOn` throw.
struct TimeRecorder {
  std::mutex mutex;
  std::map<std::string, double> timeLimit;
  std::vector<std::string> order;
  std::set<std::string> failOn;

  study::SweepRunFn runner() {
    return [this](const core::RunConfig& cfg, const fs::path& dir, const compaction::Deposit&,
                  const study::RunProgressFn&) {
      const std::string name = dir.filename().string();
      {
        std::lock_guard lock(mutex);
        timeLimit[name] = cfg.compaction.timeLimit;
        order.push_back(name);
        if (failOn.count(name)) throw std::runtime_error("the fall blew up");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));  // a partner still running is waited for
      const double t = cfg.backend == "nscd" ? fakeFallTime(cfg) : cfg.compaction.timeLimit;
      json result = {{"solid_fraction", 0.6}, {"timing", {{"stages", {{"dynamic", {{"simulated_time", t}}}}}}}};
      std::ofstream(dir / "result.json") << result.dump();
      return result;
    };
  }
};

}  // namespace

TEST_CASE("equal_time: each Bullet run runs for the time of its nscd partner's fall, on one or two workers") {
  const study::SweepSpec spec = study::parseSweepSpec(equalTimeSweep());
  const std::vector<study::SweepRun> runs = study::expandRuns(spec);
  REQUIRE(runs.size() == 8);
  REQUIRE(runs[0].config.backend == "bullet");
  const int jobs = GENERATE(1, 2);
  INFO("jobs " << jobs);
  const confpack::testing::ScratchDir scratch("sweep_equal_time");
  const fs::path& dir = scratch.path();
  TimeRecorder rec;
  const study::SweepSummary s = study::runSweep(spec, dir, quietOptions(jobs), rec.runner(), fakeDeposit);
  CHECK(s.ran == 8);
  CHECK(s.failed == 0);
  const auto partners = study::equalTimePartners(runs, "nscd");
  for (const study::SweepRun& r : runs) {
    INFO(r.name);
    if (r.config.backend == "nscd") {
      CHECK_FALSE(partners[r.index]);
      CHECK(rec.timeLimit[r.name] == 20.0);  // its own limit: the fall ends at rest long before
      continue;
    }
    REQUIRE(partners[r.index]);
    const study::SweepRun& p = runs[*partners[r.index]];
    CHECK(p.config.backend == "nscd");
    CHECK(p.depositIndex == r.depositIndex);
    CHECK(rec.timeLimit[r.name] == fakeFallTime(r.config));
    // Written into the run's config.json, so that `confpack run --config` reruns it.
    const json cfg = core::readJsonFile(dir / "runs" / r.name / "config.json", "config");
    CHECK(cfg["compaction"]["time_limit"].get<double>() == fakeFallTime(r.config));
    const auto at = [&](const std::string& n) { return std::find(rec.order.begin(), rec.order.end(), n); };
    CHECK(at(p.name) < at(r.name));
  }
}

TEST_CASE("equal_time: a Bullet run whose nscd partner has not run, or failed, fails and runs once it has") {
  const study::SweepSpec spec = study::parseSweepSpec(equalTimeSweep());
  const std::vector<study::SweepRun> runs = study::expandRuns(spec);
  const confpack::testing::ScratchDir scratch("sweep_equal_time_alone");
  const fs::path& dir = scratch.path();
  TimeRecorder rec;
  const auto failure = [&](const std::string& run) {
    return core::readJsonFile(dir / "runs" / run / study::kFailedMarker, "marker")["error"].get<std::string>();
  };
  // r0000 (Bullet) alone: its partner r0001 is neither done nor in this invocation's work.
  study::SweepOptions alone = quietOptions();
  alone.runs = {0};
  CHECK(study::runSweep(spec, dir, alone, rec.runner(), fakeDeposit).failed == 1);
  CHECK(failure("r0000") == "equal_time: its nscd run r0001 has not finished: run it, then run this one again");
  CHECK_FALSE(rec.timeLimit.count("r0000"));  // refused before it ran
  // A partner that fails fails its Bullet run with it.
  rec.failOn = {"r0003"};
  study::SweepOptions pair = quietOptions();
  pair.runs = {2, 3};
  CHECK(study::runSweep(spec, dir, pair, rec.runner(), fakeDeposit).failed == 2);
  CHECK(failure("r0002") == "equal_time: its nscd run r0003 failed");
  // Run again, everything left runs, each Bullet run after its partner and for its fall's time.
  rec.failOn.clear();
  const study::SweepSummary again = study::runSweep(spec, dir, quietOptions(), rec.runner(), fakeDeposit);
  CHECK(again.ran == 8);
  CHECK(rec.timeLimit["r0000"] == fakeFallTime(runs[0].config));
  CHECK(rec.timeLimit["r0002"] == fakeFallTime(runs[2].config));
}

TEST_CASE(
    "equal_time: a value other than nscd, or a run without its nscd partner, is refused before anything is written") {
  json doc = equalTimeSweep();
  doc["equal_time"] = "bullet";
  CHECK_THROWS_WITH(study::parseSweepSpec(doc, "e.json"),
                    Catch::Contains("equal_time") && Catch::Contains("expected \"nscd\""));
  // A Bullet run of a width that nscd does not run: it has no fall to take its time from.
  doc = equalTimeSweep();
  doc.erase("vary");
  doc["groups"] = json::parse(R"([{ "width": [3], "replicas": 1, "backend": ["nscd", "bullet"] },
                                  { "width": [5], "replicas": 1, "backend": ["bullet"] }])");
  const study::SweepSpec spec = study::parseSweepSpec(doc);
  const std::vector<study::SweepRun> runs = study::expandRuns(spec);
  CHECK_THROWS_WITH(study::equalTimePartners(runs, "nscd"),
                    Catch::StartsWith("equal_time: run r0002 (") && Catch::Contains("has no nscd run"));
  const fs::path dir = confpack::testing::scratchPath("sweep_equal_time_refused");
  TimeRecorder rec;
  CHECK_THROWS_AS(study::runSweep(spec, dir, quietOptions(), rec.runner(), fakeDeposit), std::invalid_argument);
  CHECK_FALSE(fs::exists(dir));
  // Without equal_time no run has a partner.
  for (const auto& p : study::equalTimePartners(runs, "")) CHECK_FALSE(p);
}
