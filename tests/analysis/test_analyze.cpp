// The aggregate analysis (result.json blocks, docs/model.md "Results") and its CSV profiles.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "analysis/analyze.hpp"
#include "compaction/deposition.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/read_file.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;

namespace {

using confpack::testing::slurp;
}  // namespace

TEST_CASE("a pile too low for a bulk region reports its bulk quantities as null, not zero", "[analysis][analyze]") {
  // Four layers: the free surface is at 4, below the 3 + 3 d_L margins of the bulk region.
  const nlohmann::json j = analysis::analyzePacking(simpleCubic(6, 5, 4));
  CHECK(j["free_surface"].get<double>() == Approx(4.0));
  CHECK(j["solid_fraction"].is_null());
  CHECK(j["interpenetration_percent"]["exact"].is_null());
  CHECK(j["coordination"]["Z"].is_null());
}

TEST_CASE("analysis of a simple cubic lattice between walls", "[analysis][analyze]") {
  core::Packing p = simpleCubic(6, 5, 12);
  p.box.periodicY = false;  // spheres at y = 0.5 ... 4.5 touch both walls
  const analysis::Analysis a = analysis::analyze(p);
  const nlohmann::json j = analysis::toJson(a);
  CHECK(j["n_grains"] == 360);
  CHECK(j["solid_fraction"].get<double>() == Approx(std::numbers::pi / 6).epsilon(1e-12));
  CHECK(j["free_surface"].get<double>() == Approx(12.0));
  // The two outer columns of five touch a wall instead of a sixth sphere: Z = (3 x 6 + 2 x 5)/5.
  CHECK(j["coordination"]["Z"].get<double>() == Approx(5.6));
  CHECK(j["coordination"]["simple"].get<double>() == Approx(5.6));
  CHECK(j["coordination"]["double"].get<double>() == 0.0);
  CHECK(j["coordination"]["rattler_fraction"].get<double>() == 0.0);
  CHECK(j["coordination"]["wall"].get<double>() == Approx(2.0 / 5.0));
  CHECK(j["coordination"]["geometric_contacts"] == true);
  CHECK(j["coordination"]["hyperstaticity"].is_null());
  CHECK(j["interpenetration_percent"]["exact"].get<double>() == 0.0);
  CHECK(j["interpenetration_percent"]["lattice_min"].is_null());
  CHECK(j["interpenetration_percent"]["lattice_max"].is_null());
  // Fabric: per grain 2 contacts along x and z, 1.6 along y: a = (5/2)(2 - 1.6)/5.6.
  CHECK(j["anisotropy"].get<double>() == Approx(2.5 * 0.4 / 5.6));
  CHECK(j["nematic"]["bulk"].is_null());
  CHECK(j["nematic"]["boundary"].is_null());
  CHECK(j["equilibrium"].is_null());
  REQUIRE(j.contains("profile_fit"));
  CHECK(j["profile_fit"].contains("lambda_L"));
  CHECK(j["profile_fit"].contains("phi_bulk"));
  // The folded profile of touching layers: its mean over the half width is pi/6.
  double mean = 0.0;
  for (double v : a.phiProfile.phi) mean += v;
  mean /= a.phiProfile.phi.size();
  CHECK(mean == Approx(std::numbers::pi / 6).epsilon(1e-9));

  const auto dir = std::filesystem::temp_directory_path() / "confpack_test_analyze_profiles";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  analysis::writeProfiles(dir, a, {{"seed", 7}, {"backend", "none"}, {"version", "test"}});
  for (const char* name : {"phi_y.csv", "z_y.csv", "homogeneity_z.csv", "homogeneity_y.csv", "orientation_cos.csv",
                           "orientation_azimuth.csv"}) {
    INFO(name);
    const std::string text = slurp(dir / name);
    CHECK(text.rfind("# confpack", 0) == 0);
    CHECK(text.find("# seed: 7\n") != std::string::npos);
    CHECK(text.find("# backend: none\n") != std::string::npos);
  }
  const std::string phi = slurp(dir / "phi_y.csv");
  CHECK(phi.find("\ny,phi\n") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("analysis of a small pinacoid deposit", "[analysis][analyze][pinacoid]") {
  core::BoxDef box;
  box.lengthX = 5;
  box.width = 6;
  box.height = 9;
  core::PopulationDef pop;
  pop.shape = core::ShapeKind::Pinacoid;
  core::DepositionDef def;
  def.grainCount = 180;
  core::Packing p;
  p.box = box;
  p.grains = compaction::deposit(box, pop, def, 3).grains;
  const nlohmann::json j = analysis::analyzePacking(p);
  INFO(j.dump(1));
  CHECK(j["n_grains"] == 180);
  CHECK(j["nematic"]["bulk"].is_number());
  CHECK(j["nematic"]["boundary"].is_number());
  CHECK(j["solid_fraction"].get<double>() > 0.1);
  CHECK(j["solid_fraction"].get<double>() < 0.7);
  // The deposit has no overlaps (grains sit inside non-overlapping placeholders).
  CHECK(j["interpenetration_percent"]["exact"].get<double>() == 0.0);
  CHECK(j["interpenetration_percent"]["lattice_min"].get<double>() == 0.0);
  CHECK(j["interpenetration_percent"]["lattice_max"].get<double>() == 0.0);
  // Pinacoids substituted into circumscribing placeholders touch nothing: all rattlers, and the
  // hyperstaticity (over non-rattlers) is then undefined.
  CHECK(j["coordination"]["rattler_fraction"].get<double>() == 1.0);
  CHECK(j["coordination"]["hyperstaticity"].is_null());
  // A contact naming a grain that does not exist is refused with a message, not a crash.
  core::Contact bad;
  bad.a = 0;
  bad.b = 5000;
  p.contacts = std::vector<core::Contact>{bad};
  CHECK_THROWS_AS(analysis::analyzePacking(p), std::invalid_argument);
}

TEST_CASE("an analysis with far more cells than max_cells is refused before any work", "[analysis][analyze]") {
  // Issue 23, failure 6: `analyze --slice 1e-7` on 170 grains ran over 10 minutes at 3.7 GB.
  const core::Packing p = simpleCubic(5, 4, 10);  // 200 grains, W = 4
  analysis::AnalysisOptions o;
  std::string what;
  // Defaults: 200 grains x 200 phi(y) slices of 0.02 across W = 4.
  CHECK(analysis::estimatedCells(p, o, &what) == 200.0 * 200.0);
  CHECK(what == "200 grains x phi(y) slices of 0.02 d_L");
  o.profile.slice = 1e-7;
  CHECK(analysis::estimatedCells(p, o) == Approx(200.0 * 4e7));
  o.coordination.slice = 1e-10;  // 4e10 Z(y) slices: now the largest
  CHECK(analysis::estimatedCells(p, o, &what) == Approx(4e10));
  CHECK(what == "Z(y) slices of 1e-10 d_L");
  o = {};
  o.region.cellSize = 1e-4;  // (5 / 1e-4) x (4 / 1e-4) = 2e9 free-surface cells
  CHECK(analysis::estimatedCells(p, o, &what) == Approx(2e9));
  CHECK(what == "free-surface cells of 0.0001 d_L");

  o = {};
  o.profile.slice = 1e-7;
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(analysis::analyze(p, o),
                    "analysis: about 8e+09 cells (200 grains x phi(y) slices of 1e-07 d_L), more than max_cells "
                    "(2e+08); check the slice or cell size, or raise the limit with --max-cells");
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(1));
  // 4e8 cells, minutes of work that the old limit (1e9, itself 6.4 min) let through.
  o.profile.slice = 2e-6;
  CHECK_THROWS_WITH(analysis::analyze(p, o), Catch::StartsWith("analysis: about 4e+08 cells"));
  CHECK(analysis::AnalysisOptions{}.maxCells == 2e8);
  // The limit is the options' own: lowered, it refuses the default analysis; at the estimate, it
  // lets it through.
  o = {};
  o.maxCells = 39999;
  CHECK_THROWS_WITH(analysis::analyze(p, o), Catch::StartsWith("analysis: about 4e+04 cells"));
  o.maxCells = 40000;
  CHECK(analysis::analyze(p, o).grains == 200);
}

TEST_CASE("type_band adds coordination_band beside the exact coordination, which it leaves alone",
          "[analysis][analyze][coordination]") {
  const core::Packing p = simpleCubic(6, 5, 12);
  analysis::AnalysisOptions o;
  o.typeBand = 0.1;
  const nlohmann::json exact = analysis::analyzePacking(p);
  const nlohmann::json j = analysis::analyzePacking(p, o);
  CHECK(exact["coordination_band"].is_null());
  CHECK(j["coordination"] == exact["coordination"]);
  // Spheres touch at a point whatever the band: the band's types are the exact ones.
  const nlohmann::json& b = j["coordination_band"];
  CHECK(b["band"] == 0.1);
  CHECK(b["Z"].get<double>() == Approx(6.0));
  CHECK(b["simple"].get<double>() == Approx(6.0));
  CHECK(b["double"].get<double>() == 0.0);
  CHECK(b["triple"].get<double>() == 0.0);
  CHECK(b["constraints"].get<double>() == Approx(6.0));
  CHECK(b["hyperstaticity"].is_null());
  for (double band : {-0.1, 0.500001, std::nan(""), HUGE_VAL}) {
    INFO("type_band = " << band);
    o.typeBand = band;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("type_band"));
  }
  o.typeBand = 0.5;
  CHECK_NOTHROW(o.validate());
}
