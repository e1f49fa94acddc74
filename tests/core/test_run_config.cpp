// RunConfig (core/run_config.hpp): the JSON round trip of every field and the refusal of bad
// values by field name.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/json_input.hpp"
#include "core/run_config.hpp"

using namespace confpack;
using nlohmann::json;

TEST_CASE("the run configuration round-trips through JSON") {
  core::RunConfig c;
  c.box.lengthX = 7.25;
  c.box.width = 1.0 / 3.0;
  c.box.periodicY = true;
  c.walls.friction = 0.5;
  c.population.shape = core::ShapeKind::Pinacoid;
  c.population.smallFraction = 40.0;
  c.population.pinacoid.alphaDeg = 55.5;
  c.deposition.expectedSolidFraction = 0.58;
  c.compaction.dt = 3.3e-4;
  c.compaction.adaptiveDt = true;
  c.compaction.timeLimit = 123.0;
  c.compaction.checkInterval = 77;
  c.compaction.frameInterval = 5;
  c.compaction.protocol = core::Protocol::QuasiStatic;
  c.compaction.trustRadius = 0.02;
  c.compaction.forceRatio = 2e-4;
  c.backend = "bullet";
  c.backendOptions = {{"iterations", 50}};
  c.seed = 18446744073709551615ULL;  // the largest seed survives (JSON unsigned, not a double)
  c.threads = 2;
  const json j = c;
  const core::RunConfig d = j.get<core::RunConfig>();
  CHECK(json(d) == j);
  CHECK(d.seed == c.seed);
  CHECK(d.box.width == c.box.width);
  CHECK(d.population.shape == core::ShapeKind::Pinacoid);
  CHECK(d.compaction.dt == c.compaction.dt);
  CHECK(d.compaction.checkInterval == 77);
  CHECK(d.compaction.adaptiveDt);
  CHECK(d.compaction.protocol == core::Protocol::QuasiStatic);
  CHECK(j.at("compaction").at("protocol") == "quasi-static");
  CHECK(d.compaction.trustRadius == 0.02);
  CHECK_NOTHROW(d.validate());
  // snake_case keys, as in the packing file.
  for (const char* k :
       {"box", "population", "deposition", "compaction", "backend", "backend_options", "seed", "threads"})
    CHECK(j.contains(k));
  for (const char* k : {"dt", "adaptive_dt", "time_limit", "fall_time_limit", "check_interval", "frame_interval",
                        "force_ratio", "moment_ratio", "kinetic_ratio", "protocol", "switch_kinetic_ratio",
                        "trust_radius", "settle_tolerance", "finisher_max_step", "finisher_max_steps"})
    CHECK(j.at("compaction").contains(k));
  // A partial document takes the defaults for the rest (sweeps override a base this way).
  const auto partial = json::parse(R"({"box": {"width": 5}, "seed": 9})").get<core::RunConfig>();
  CHECK(partial.box.width == 5.0);
  CHECK(partial.seed == 9);
  CHECK(partial.backend == "nscd");
  CHECK(partial.compaction.timeLimit == core::CompactionDef{}.timeLimit);
}

TEST_CASE("the run configuration refuses bad values naming the field") {
  auto refused = [](auto edit, const std::string& field) {
    core::RunConfig c;
    edit(c);
    INFO(field);
    CHECK_THROWS_WITH(c.validate(), Catch::Contains(field));
  };
  refused([](core::RunConfig& c) { c.backend = "foo"; }, "backend");
  refused([](core::RunConfig& c) { c.threads = 0; }, "threads");
  refused([](core::RunConfig& c) { c.box.width = -1; }, "width");
  refused([](core::RunConfig& c) { c.population.smallFraction = 101; }, "population.small_fraction");
  refused([](core::RunConfig& c) { c.compaction.timeLimit = 0; }, "compaction.time_limit");
  // 1e20 t0 once overflowed the step count and ran 0 steps with exit 0.
  refused([](core::RunConfig& c) { c.compaction.timeLimit = 1e20; },
          "compaction.time_limit: must be in (0, 1e+09] (got 1e+20)");
  refused([](core::RunConfig& c) { c.compaction.dt = -1e-3; }, "compaction.dt");
  refused([](core::RunConfig& c) { c.compaction.checkInterval = 0; }, "compaction.check_interval");
  refused([](core::RunConfig& c) { c.compaction.kineticRatio = -1; }, "compaction.kinetic_ratio");
  refused([](core::RunConfig& c) { c.compaction.switchKineticRatio = 0; }, "compaction.switch_kinetic_ratio");
  refused([](core::RunConfig& c) { c.compaction.trustRadius = 0; }, "compaction.trust_radius");
  refused([](core::RunConfig& c) { c.compaction.trustRadius = 0.9; }, "compaction.trust_radius");
  refused([](core::RunConfig& c) { c.compaction.settleTolerance = -1e-6; }, "compaction.settle_tolerance");
  refused([](core::RunConfig& c) { c.compaction.finisherMaxStep = 0; }, "compaction.finisher_max_step");
  refused([](core::RunConfig& c) { c.compaction.finisherMaxSteps = 0; }, "compaction.finisher_max_steps");
  CHECK_THROWS_WITH(json::parse(R"({"compaction": {"protocol": "static"}})").get<core::RunConfig>(),
                    Catch::Contains("compaction.protocol: must be \"dynamic\" or \"quasi-static\" (got \"static\")"));
  refused([](core::RunConfig& c) { c.deposition.expectedSolidFraction = 1.2; }, "deposition.expected_solid_fraction");
  // One range, checked once: a solid fraction of 1 leaves no room to deposit into.
  refused([](core::RunConfig& c) { c.deposition.expectedSolidFraction = 1.0; },
          "deposition.expected_solid_fraction: must be in (0, 1) (got 1)");
  refused([](core::RunConfig& c) { c.backendOptions = json::array(); }, "backend_options");
  CHECK_THROWS_WITH(json::parse(R"({"sed": 3})").get<core::RunConfig>(), Catch::Contains("config.sed: unknown key"));
  CHECK_THROWS_WITH(json::parse(R"({"seed": -3})").get<core::RunConfig>(), Catch::Contains("config.seed"));
  CHECK_THROWS_WITH(json::parse(R"({"threads": "two"})").get<core::RunConfig>(), Catch::Contains("config.threads"));
  CHECK_THROWS_WITH(json::parse(R"({"compaction": {"adaptive_dt": "yes"}})").get<core::RunConfig>(),
                    Catch::Contains("compaction.adaptive_dt"));
  CHECK_THROWS_WITH(json::parse(R"({"compaction": {"time_limt": 3}})").get<core::RunConfig>(),
                    Catch::Contains("compaction.time_limt: unknown key"));
  // The box and the population are read key by key: a typo there once ran with the default.
  CHECK_THROWS_WITH(json::parse(R"({"box": {"widht": 3}})").get<core::RunConfig>(),
                    "box.widht: unknown key (known: length_x, width, periodic_y, height)");
  CHECK_THROWS_WITH(json::parse(R"({"population": {"small_fractoin": 30}})").get<core::RunConfig>(),
                    Catch::StartsWith("population.small_fractoin: unknown key"));
  CHECK_THROWS_WITH(json::parse(R"({"population": {"pinacoid": {"alpha": 50}}})").get<core::RunConfig>(),
                    Catch::StartsWith("pinacoid.alpha: unknown key"));
}

TEST_CASE("the run configuration refuses a deposit larger than max_grains, from the box's volume") {
  core::RunConfig c;
  c.box.lengthX = 20.0;
  c.box.width = 10.0;
  c.box.height = 16.0;
  // phi L_x W h / (pi d^3 / 6): 3,667 spheres of unit diameter (the size spread adds 0.3 %).
  CHECK(c.estimatedGrainCount() == Approx(0.6 * 20.0 * 10.0 * 16.0 / (M_PI / 6.0)).epsilon(0.005));
  c.box.lengthX = c.box.width = 1e6;
  CHECK_THROWS_WITH(c.validate(), Catch::Contains("more than max_grains (1000000)"));
  c.deposition.maxGrains = std::size_t{1} << 62;
  CHECK_NOTHROW(c.validate());
  c.deposition.grainCount = 50;  // an explicit count is what is checked
  c.deposition.maxGrains = 49;
  CHECK_THROWS_WITH(c.validate(), Catch::Contains("about 50 grains"));
}

TEST_CASE("a grain cap shortens the box along x until it holds about that many grains, and only then") {
  core::RunConfig c;
  c.box.lengthX = 12.0;
  c.box.width = 20.0;
  c.box.height = 12.0;
  c.population.smallFraction = 40.0;  // 40 % of the volume in spheres of half the size: 8 times as many a volume
  const double full = c.estimatedGrainCount();
  // phi L_x W h ((1 - x) / v_L + x / v_S), v_S = v_L / 8: about 12,500 grains.
  CHECK(full == Approx(0.6 * 12.0 * 20.0 * 12.0 * (0.6 + 0.4 * 8.0) / (M_PI / 6.0)).epsilon(0.01));
  c.fitLengthToGrainCap();  // no cap: nothing changes
  CHECK(c.box.lengthX == 12.0);

  c.deposition.grainCap = 5000;
  c.fitLengthToGrainCap();
  // The count is proportional to L_x: 12 * 5000 / full, rounded down to the hundredth.
  CHECK(c.box.lengthX == Approx(std::floor(1200.0 * 5000.0 / full) / 100.0));
  CHECK(c.estimatedGrainCount() <= 5000.0);
  CHECK(c.estimatedGrainCount() > 0.99 * 5000.0);
  const double fitted = c.box.lengthX;
  c.fitLengthToGrainCap();  // a fitted box fits again unchanged, and never grows
  CHECK(c.box.lengthX == fitted);
  c.deposition.grainCap = 1'000'000;
  c.fitLengthToGrainCap();
  CHECK(c.box.lengthX == fitted);

  // A box under the cap, or a deposit of an explicit count, keeps its length.
  core::RunConfig small;
  small.box.lengthX = 12.0;
  small.box.width = 5.0;
  small.box.height = 12.0;
  small.deposition.grainCap = 5000;
  small.fitLengthToGrainCap();
  CHECK(small.box.lengthX == 12.0);
  c.box.lengthX = 12.0;
  c.deposition.grainCap = 5000;
  c.deposition.grainCount = 8000;
  c.fitLengthToGrainCap();
  CHECK(c.box.lengthX == 12.0);

  // A cap that leaves less than two grains' length is refused, not met by a box grains cannot fit.
  c.deposition.grainCount = 0;
  c.deposition.grainCap = 10;
  CHECK_THROWS_WITH(c.fitLengthToGrainCap(), Catch::Contains("deposition.grain_cap: 10 grains"));
  CHECK(c.box.lengthX == 12.0);
}

TEST_CASE("the config.json seeds of the fuzz corpus are accepted configurations") {
  // Seeds the reader refuses exercise only its refusal: a seed copied from an older run's
  // config.json (with the backend_settings key it no longer writes) would go stale unnoticed.
  int seeds = 0;
  for (const auto& entry : std::filesystem::directory_iterator(CONFPACK_SOURCE_DIR "/fuzz/corpus/run_config")) {
    INFO(entry.path());
    const core::RunConfig c = core::readJsonFile(entry.path(), "run configuration").get<core::RunConfig>();
    CHECK_NOTHROW(c.validate());
    ++seeds;
  }
  CHECK(seeds >= 5);
}

TEST_CASE("an unknown backend name is quoted cut short, not echoed in full") {
  // fuzz_run_config: a 4 KB "backend" string made a refusal longer than 1,500 characters.
  core::RunConfig c;
  c.backend = std::string(4000, 'n');
  try {
    c.validate();
    FAIL("accepted");
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    CHECK(message.size() < 200);
    CHECK_THAT(message, Catch::StartsWith("backend: unknown backend 'nnnn"));
    CHECK_THAT(message, Catch::EndsWith("(expected nscd or bullet)"));
  }
}

// mu_w lived in the box before the walls had their own object: such a config.json (a run folder or
// a sweep table of that time) still reads, with the friction where it now belongs.
TEST_CASE("a config.json with box.wall_friction reads it as walls.friction, and refuses it given twice") {
  const auto c = json::parse(R"({"box": {"width": 5, "wall_friction": 0.4}})").get<core::RunConfig>();
  CHECK(c.walls.friction == 0.4);
  CHECK(c.box.width == 5.0);
  CHECK(json(c)["box"].contains("wall_friction") == false);
  CHECK(json(c)["walls"]["friction"] == 0.4);
  CHECK_THROWS_WITH(
      json::parse(R"({"box": {"wall_friction": 0.4}, "walls": {"friction": 0.4}})").get<core::RunConfig>(),
      Catch::StartsWith("box.wall_friction: given twice"));
  CHECK_THROWS_WITH(json::parse(R"({"box": {"wall_friction": -1}})").get<core::RunConfig>(),
                    "box.wall_friction: must be >= 0 (got -1)");
  // Read in place, never copied: a value nested 100,000 deep (a recursive copy overflowed the
  // stack under AddressSanitizer) is refused in a short message.
  json deep = 1;
  for (int i = 0; i < 100000; ++i) deep = json::array({std::move(deep)});
  json legacy = json::parse(R"({"box": {"wall_friction": 0.1}})");
  legacy["compaction"] = std::move(deep);
  CHECK_THROWS_WITH(legacy.get<core::RunConfig>(), Catch::StartsWith("compaction: must be a JSON object (got array)"));
}
