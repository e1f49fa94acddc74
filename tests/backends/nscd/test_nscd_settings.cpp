// nscd settings (backends/nscd/nscd_settings.hpp), read through the backend that resolves them:
// every default is resolved and round-trips, and unknown keys and bad values are refused by name.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "backends/nscd/nscd_backend.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using core::Vec3;
using testing::boxSystem;
using testing::sphere;

TEST_CASE("nscd options: defaults resolved, unknown keys and bad values refused by name", "[nscd]") {
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(sphere(1.0, Vec3(10.0, 5.0, 0.5)));
  const nlohmann::json resolved = nscd::makeNscdBackend(s, nlohmann::json::object())->settings();
  for (const char* key :
       {"theta", "expansion", "preconditioner", "tolerance", "max_iterations", "min_iterations", "alert_distance",
        "gap_correction", "max_correction_velocity", "damping", "damping_speed", "finisher_solver", "fall_tolerance"})
    CHECK(resolved.contains(key));
  CHECK(resolved["finisher_solver"] == "auto");
  CHECK(resolved["fall_tolerance"] == "auto");
  CHECK(nscd::makeNscdBackend(s, {{"fall_tolerance", 1e-6}})->settings()["fall_tolerance"] == 1e-6);
  CHECK(resolved["theta"] == 0.5);
  CHECK(resolved["tolerance"].get<double>() <= 1e-4);
  // The resolved settings round-trip: feeding them back gives the same settings.
  CHECK(nscd::makeNscdBackend(s, resolved)->settings() == resolved);
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"tolerence", 1e-6}}), Catch::Contains("tolerence"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"theta", 0.3}}), Catch::Contains("theta"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"max_iterations", 0}}), Catch::Contains("max_iterations"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"gap_correction", 1.5}}), Catch::Contains("gap_correction"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"damping", -0.1}}), Catch::Contains("damping"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"damping_speed", 0.0}}), Catch::Contains("damping_speed"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"tolerance", "small"}}), Catch::Contains("tolerance"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"fall_tolerance", 0.0}}),
                    Catch::Contains("fall_tolerance: must be > 0"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"fall_tolerance", "loose"}}),
                    Catch::Contains("fall_tolerance: must be a number or \"auto\""));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"expansion", "cg"}}), Catch::Contains("expansion"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"preconditioner", "ic"}}), Catch::Contains("preconditioner"));
  // Gauss-Seidel cannot reach the finisher's accuracy: not offered for it.
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"finisher_solver", "nlgs"}}), Catch::Contains("finisher_solver"));
  CHECK_THROWS_AS(nscd::makeNscdBackend(s, nlohmann::json::array()), std::invalid_argument);
  // Threads come from the run configuration (SystemDef), once, not from the options.
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"threads", 2}}), Catch::Contains("nscd.threads: unknown key"));
  CHECK_FALSE(resolved.contains("threads"));
  core::SystemDef none = s;
  none.threads = 0;
  CHECK_THROWS_WITH(nscd::makeNscdBackend(none, {}), Catch::Contains("threads"));
  // A box too short for the grains' periodic images is refused, not silently wrong.
  core::SystemDef tiny = boxSystem(1.5, 10.0, false, 0.0);
  tiny.grains.push_back(sphere(1.0, Vec3(0.5, 5.0, 0.5)));
  CHECK_THROWS_AS(nscd::makeNscdBackend(tiny, {}), std::invalid_argument);
  auto b = nscd::makeNscdBackend(s, {});
  CHECK_THROWS_AS(b->step(0.0), std::invalid_argument);
}
