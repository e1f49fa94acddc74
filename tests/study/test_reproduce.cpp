// The confinement study (docs/model.md, "The study and its report") at its three scales
// (study/reproduce.hpp), as the run tables they expand to. `confpack reproduce` itself, with the
// real binary, is tested in tests/apps/test_cmd_reproduce.cpp.
#include <catch2/catch.hpp>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include "study/reproduce.hpp"
#include "study/sweep.hpp"

using namespace confpack;

TEST_CASE("reproduce: the paper scale is the full study") {
  const auto runs = study::expandRuns(study::parseSweepSpec(study::reproductionSweep("paper")));
  // Spheres x_S x {5, 10, 20, bi}: 4 x 4; MSP wall friction {0.3, 0.5, 1} x {5, 10, 20}: 9;
  // pinacoids x {5, 10, 20, bi}: 4. Each with 3 seeds and 2 backends.
  CHECK(runs.size() == (16 + 9 + 4) * 3 * 2);
  std::set<double> widths, fractions, frictions;
  std::map<std::size_t, std::set<std::string>> backendsOfDeposit;
  for (const auto& r : runs) {
    CHECK(r.config.box.lengthX == 20.0);
    CHECK(r.config.box.height == 16.0);
    if (!r.config.box.periodicY)
      widths.insert(r.config.box.width);
    else
      CHECK(r.config.box.width == 20.0);
    fractions.insert(r.config.population.smallFraction);
    frictions.insert(r.config.walls.friction);
    if (r.config.walls.friction > 0.0) {
      CHECK(r.config.population.shape == core::ShapeKind::Sphere);
      CHECK(r.config.population.smallFraction == 0.0);
    }
    if (r.config.population.shape == core::ShapeKind::Pinacoid) CHECK(r.config.population.smallFraction == 0.0);
    backendsOfDeposit[r.depositIndex].insert(r.config.backend);
  }
  CHECK(widths == std::set<double>{5.0, 10.0, 20.0});
  CHECK(fractions == std::set<double>{0.0, 10.0, 25.0, 40.0});
  CHECK(frictions == std::set<double>{0.0, 0.3, 0.5, 1.0});
  for (const auto& [d, b] : backendsOfDeposit) CHECK(b == std::set<std::string>{"nscd", "bullet"});
  // quick and tiny are smaller studies of the same kinds; an unknown scale is refused.
  const auto quick = study::expandRuns(study::parseSweepSpec(study::reproductionSweep("quick")));
  CHECK(quick.size() < runs.size());
  // The quick study brings its nscd runs to rest with the finisher (docs/model.md).
  for (const study::SweepRun& r : quick) CHECK(r.config.compaction.protocol == core::Protocol::QuasiStatic);
  CHECK(study::expandRuns(study::parseSweepSpec(study::reproductionSweep("tiny"))).size() == 6);
  CHECK_THROWS_AS(study::reproductionSweep("huge"), std::invalid_argument);
}

TEST_CASE(
    "reproduce: the medium scale is the paper's study in a box of 830 to 4,300 monodisperse grains, at most 5,000") {
  const auto runs = study::expandRuns(study::parseSweepSpec(study::reproductionSweep("medium")));
  CHECK(runs.size() == (16 + 9 + 4) * 3 * 2);  // the paper's families, widths, seeds and backends
  std::set<double> widths;
  std::set<std::string> shortened;
  for (const study::SweepRun& r : runs) {
    const core::RunConfig& c = r.config;
    if (!c.box.periodicY) widths.insert(c.box.width);
    CHECK(c.compaction.protocol == core::Protocol::QuasiStatic);
    // The piles fall on the adaptive step until all but at rest; Bullet stops at 20 t0.
    CHECK(c.compaction.adaptiveDt);
    CHECK(c.compaction.switchKineticRatio == 1e-8);
    CHECK(c.compaction.fallTimeLimit == 300.0);
    CHECK(c.compaction.timeLimit == 20.0);
    // Its finisher stops at moves of 1e-5 d, ten times the default: on its 1,064-pinacoid pile,
    // the same packing in half the run's time.
    CHECK(c.compaction.settleTolerance == 1e-5);
    // Grains at the expected solid fraction: 830 (spheres, W = 5) to 4,300 (pinacoids, W = 20)
    // monodisperse in the 12 x W x 12 box; a box that would hold more than 5,000 (the small
    // grains of x_S = 40 would make 12,500 at W = 20) is shortened along x to hold 5,000.
    const double grains = c.estimatedGrainCount();
    CHECK(grains <= 5000.0);
    if (c.box.lengthX < 12.0) {
      CHECK(grains > 0.99 * 5000.0);
      CHECK(c.box.lengthX > 4.5);  // still several grains long, its periodic images apart
      shortened.insert(r.label());
    }
    if (c.population.smallFraction == 0.0) {
      CHECK(grains > 800.0);
      CHECK(grains < 4400.0);
      // The bulk region (3 d_L from the floor and from the free surface) holds several hundred grains.
      CHECK(grains * (c.box.height - 6.0) / c.box.height > 400.0);
    }
  }
  CHECK(widths == std::set<double>{5.0, 10.0, 20.0});
  // x_S = 10 at W = 20; x_S = 25 at W = 20 and biperiodic; x_S = 40 at W = 10, 20 and biperiodic:
  // 6 configurations, 3 seeds, 2 backends.
  CHECK(shortened.size() == 6 * 3 * 2);
}

TEST_CASE("reproduce: docs/examples/paper-scale.json is the paper scale's sweep file, as docs/cluster.md uses it") {
  std::ifstream in(std::string(CONFPACK_SOURCE_DIR) + "/docs/examples/paper-scale.json");
  REQUIRE(in);
  CHECK(nlohmann::json::parse(in) == study::reproductionSweep("paper"));
}
