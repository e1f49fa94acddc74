// makeBackend (backends/backend_factory.hpp): every listed name builds that backend, options go
// through to it, an unknown name is refused naming the known ones, and the run configuration
// (which cannot see backends/) accepts the same names.
#include <catch2/catch.hpp>
#include <stdexcept>
#include <string>

#include "backends/backend_factory.hpp"
#include "core/run_config.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;

TEST_CASE("makeBackend builds each listed backend by name, passes its options, refuses other names") {
  auto s = testing::boxSystem(5.0, 5.0, false, 0.0);
  s.grains = {testing::sphere(1.0, {2.5, 2.5, 0.5})};
  REQUIRE(backends::backendNames().size() == 2);
  for (const std::string_view name : backends::backendNames()) {
    INFO(name);
    const auto b = backends::makeBackend(name, s);
    CHECK(b->name() == name);
    CHECK(b->states().size() == 1);
    // An unknown option is refused by the backend it was meant for.
    CHECK_THROWS_WITH(backends::makeBackend(name, s, {{"no_such_option", 1}}), Catch::Contains("no_such_option"));
  }
  CHECK_THROWS_WITH(backends::makeBackend("ode", s),
                    Catch::Contains("unknown backend 'ode'") && Catch::Contains("nscd") && Catch::Contains("bullet"));
  CHECK_THROWS_AS(backends::makeBackend("NSCD", s), std::invalid_argument);
}

TEST_CASE("the run configuration accepts exactly the factory's backend names") {
  // core keeps its own list of backend names (it cannot see backends/): it must match the factory.
  for (auto name : backends::backendNames()) {
    core::RunConfig c;
    c.backend = std::string(name);
    CHECK_NOTHROW(c.validate());
  }
  core::RunConfig c;
  c.backend = "ode";
  CHECK_THROWS_WITH(c.validate(), Catch::Contains("backend"));
}

TEST_CASE("checkBackendOptions names a key of the other backend as such, and an unknown key with the known ones") {
  using backends::checkBackendOptions;
  CHECK_NOTHROW(checkBackendOptions("nscd", {{"alert_distance", 0.1}}));
  CHECK_NOTHROW(checkBackendOptions("bullet", {{"iterations", 30}}));
  // A config.json of an nscd run whose "backend" was changed to bullet.
  CHECK_THROWS_WITH(checkBackendOptions("bullet", {{"iterations", 30}, {"alert_distance", 0.1}}),
                    "bullet.alert_distance: a setting of nscd, not of bullet (backend_options holds the run's "
                    "backend's settings only: drop it when changing a config.json's backend)");
  CHECK_THROWS_WITH(checkBackendOptions("nscd", {{"erp", 0.2}}), Catch::Contains("nscd.erp: a setting of bullet"));
  CHECK_THROWS_WITH(checkBackendOptions("nscd", {{"bogus", 1}}),
                    Catch::StartsWith("nscd.bogus: unknown key (known: theta"));
  CHECK_THROWS_WITH(checkBackendOptions("nscd", nlohmann::json::array()), Catch::Contains("must be a JSON object"));
}
