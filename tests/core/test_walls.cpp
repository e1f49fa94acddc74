// The walls' material (core/walls.hpp): friction on the side walls only, its JSON round trip and
// its range.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "core/walls.hpp"

using namespace confpack::core;

TEST_CASE("the floor is frictionless and both side walls carry mu_w") {
  WallMaterial walls;
  walls.friction = 0.4;
  CHECK(walls.frictionOf(WallId::Floor) == 0.0);
  CHECK(walls.frictionOf(WallId::SideLow) == 0.4);
  CHECK(walls.frictionOf(WallId::SideHigh) == 0.4);
}

TEST_CASE("the walls' material round-trips through JSON and refuses a negative friction by name") {
  WallMaterial walls;
  walls.friction = 0.123456789;
  const nlohmann::json j = walls;
  CHECK(j == nlohmann::json::parse(R"({"friction": 0.123456789})"));
  CHECK(j.get<WallMaterial>() == walls);
  CHECK_THROWS_WITH(nlohmann::json::parse(R"({"friction": -0.1})").get<WallMaterial>(),
                    "walls.friction: must be >= 0 (got -0.1)");
  CHECK_THROWS_WITH(nlohmann::json::parse(R"({"mu": 0.1})").get<WallMaterial>(),
                    Catch::StartsWith("walls.mu: unknown key (known: friction)"));
}
