// `confpack analyze` (apps/cmd_analyze.cpp) end to end: a packing file with a known answer in,
// result.json and the CSV profiles out; a bad file refused with exit code 2 and nothing written.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/packing_io.hpp"
#include "tests/support/confpack_binary.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
namespace fs = std::filesystem;
using confpack::testing::ConfpackSession;

TEST_CASE("confpack analyze writes result.json and profiles", "[apps][cli]") {
  const ConfpackSession s("cmd_analyze");
  const fs::path& dir = s.dir;
  core::Packing p = confpack::testing::simpleCubic(5, 4, 10);
  p.box.periodicY = false;
  // Contacts with forces: then the equilibrium block is evaluated (zero velocities). Gravity is
  // not balanced by these forces, so it must say "not reached".
  core::Contact c;
  c.a = 0;
  c.b = 1;
  c.normal = core::Vec3::UnitX();
  c.points.push_back({core::Vec3(1.0, 0.5, 0.5), 0.3});
  p.contacts = std::vector<core::Contact>{c};
  core::writePacking(p, dir / "packing.json");

  REQUIRE(s.run("analyze packing.json --out res --quiet").code == 0);
  std::ifstream in(dir / "res" / "result.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  CHECK(j["n_grains"] == 200);
  CHECK(j["solid_fraction"].get<double>() == Approx(std::numbers::pi / 6).epsilon(1e-12));
  CHECK(j["coordination"]["geometric_contacts"] == false);
  CHECK(j["equilibrium"]["reached"] == false);
  CHECK(j["equilibrium"]["velocities"] == "assumed_zero");
  CHECK(j["nematic"]["bulk"].is_null());
  for (const char* f : {"phi_y.csv", "z_y.csv", "homogeneity_z.csv", "homogeneity_y.csv", "orientation_cos.csv",
                        "orientation_azimuth.csv"})
    CHECK(fs::exists(dir / "res" / f));

  // Bad input: exit 2, no output directory.
  {
    std::ofstream bad(dir / "bad.json");
    bad << R"({"format": "confpack-packing", "version": 1, "box": {"length_x": -1}, "grains": []})";
  }
  CHECK(s.run("analyze bad.json --out bad_out").code == 2);
  CHECK_FALSE(fs::exists(dir / "bad_out"));
  CHECK(s.run("analyze missing.json --out missing_out").code == 2);
  CHECK_FALSE(fs::exists(dir / "missing_out"));
  CHECK(s.run("analyze packing.json --out neg --slice -1").code == 2);
  CHECK_FALSE(fs::exists(dir / "neg"));
}
