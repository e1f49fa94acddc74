// `confpack analyze` end to end: a packing file with a known answer in, result.json and the CSV
// profiles out; a bad file refused with exit code 2 and nothing written.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/packing_io.hpp"
#include "lattices.hpp"

using namespace confpack;
namespace fs = std::filesystem;

namespace {
int run(const std::string& args) {
  const std::string cmd = std::string("\"") + CONFPACK_BINARY + "\" " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
}  // namespace

TEST_CASE("confpack analyze writes result.json and profiles", "[analysis][cli]") {
  const fs::path dir = fs::temp_directory_path() / "confpack_test_cmd_analyze";
  fs::remove_all(dir);
  fs::create_directories(dir);
  core::Packing p = analysis::testing::simpleCubic(5, 4, 10);
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

  REQUIRE(run("analyze \"" + (dir / "packing.json").string() + "\" --out \"" + (dir / "res").string() + "\" --quiet") ==
          0);
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
  CHECK(run("analyze \"" + (dir / "bad.json").string() + "\" --out \"" + (dir / "bad_out").string() + "\"") == 2);
  CHECK_FALSE(fs::exists(dir / "bad_out"));
  CHECK(run("analyze \"" + (dir / "missing.json").string() + "\" --out \"" + (dir / "missing_out").string() + "\"") ==
        2);
  CHECK_FALSE(fs::exists(dir / "missing_out"));
  CHECK(run("analyze \"" + (dir / "packing.json").string() + "\" --out \"" + (dir / "neg").string() +
            "\" --slice -1") == 2);
  CHECK_FALSE(fs::exists(dir / "neg"));
  fs::remove_all(dir);
}
