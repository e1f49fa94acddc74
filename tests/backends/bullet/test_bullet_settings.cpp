// Bullet settings (backends/bullet/bullet_settings.hpp): defaults round-trip, unknown keys and bad
// values are refused by name, and the backend reports the resolved settings.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "backends/backend_factory.hpp"
#include "backends/bullet/bullet_settings.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using testing::boxSystem;
using testing::sphere;

TEST_CASE("bullet settings: defaults round-trip, unknown keys and bad values are refused", "[bullet]") {
  const bullet::BulletSettings d;
  const nlohmann::json j = d;
  const bullet::BulletSettings back = bullet::bulletSettingsFromJson(j);
  CHECK(nlohmann::json(back) == j);
  CHECK_THROWS_WITH(bullet::bulletSettingsFromJson({{"iteratons", 10}}), Catch::Contains("iteratons"));
  CHECK_THROWS_WITH(bullet::bulletSettingsFromJson({{"iterations", 0}}), Catch::Contains("iterations"));
  CHECK_THROWS_WITH(bullet::bulletSettingsFromJson({{"erp2", 1.5}}), Catch::Contains("erp2"));
  CHECK_THROWS_WITH(bullet::bulletSettingsFromJson({{"split_impulse", 1}}), Catch::Contains("split_impulse"));
  CHECK_THROWS_WITH(bullet::bulletSettingsFromJson({{"split_impulse_penetration_threshold", 0.01}}),
                    Catch::Contains("split_impulse_penetration_threshold"));
  // The backend writes back the fully resolved settings, including the overridden key.
  auto s = boxSystem(5.0, 5.0, false, 0.0);
  s.grains = {sphere(1.0, {2.5, 2.5, 0.5})};
  auto b = backends::makeBackend("bullet", s, {{"iterations", 37}});
  CHECK(b->name() == "bullet");
  CHECK(b->settings().at("iterations") == 37);
  CHECK(b->settings().at("erp2") == d.erp2);
  CHECK(b->settings().size() == j.size());
}
