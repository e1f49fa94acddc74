// The two contact laws of nscd (backends/nscd/nscd_settings.hpp, "contact_law") and the
// common-plane detection through the backend: a pinacoid resting face down on the floor, started
// touching or overlapping, and one on another pinacoid's face.
#include <catch2/catch.hpp>
#include <numbers>
#include <string>

#include "backends/nscd/nscd_backend.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using core::Vec3;
using testing::boxSystem;
using testing::pinacoid;
using testing::topOf;
using testing::withBottomAt;

namespace {

// A trapezoid face straight down (45 degrees about x turns its normal (0, -1, -1)/sqrt2 to -z).
const core::Quat kOnFace(Eigen::AngleAxisd(std::numbers::pi / 4.0, Vec3::UnitX()));

double floorForce(const core::ContactBackend& b) {
  double f = 0.0;
  for (const auto& c : b.contacts())
    if (c.b < 0) f += c.normalForce();
  return f;
}

}  // namespace

TEST_CASE("nscd contact law: a pinacoid face down on the floor rests there under both laws", "[nscd]") {
  const std::string law = GENERATE("gap", "velocity");
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, kOnFace), 0.0));
  const double z0 = s.grains[0].position.z();
  auto b = nscd::makeNscdBackend(s, {{"contact_law", law}});
  for (int k = 0; k < 500; ++k) b->step(1e-3);
  INFO(law);
  CHECK(b->states()[0].position.z() == Approx(z0).margin(1e-10));
  CHECK(b->states()[0].velocity.norm() < 1e-10);
  CHECK(floorForce(*b) == Approx(s.grains[0].volume()).epsilon(1e-8));  // m g, rho = g = 1
  CHECK(b->settings()["contact_law"] == law);
}

TEST_CASE("nscd contact law: an overlap with the floor is pushed out under \"gap\" and held under \"velocity\"",
          "[nscd]") {
  const double depth = 0.01;
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, kOnFace), -depth));
  const double z0 = s.grains[0].position.z();
  SECTION("gap: removed at most at max_correction_velocity, then at rest on the floor") {
    auto b = nscd::makeNscdBackend(s, {{"contact_law", "gap"}});
    for (int k = 0; k < 1000; ++k) b->step(1e-3);
    CHECK(b->states()[0].position.z() == Approx(z0 + depth).margin(1e-9));
    CHECK(b->states()[0].velocity.norm() < 1e-9);
  }
  SECTION("velocity: held where it was, carrying its weight") {
    auto b = nscd::makeNscdBackend(s, {{"contact_law", "velocity"}});
    for (int k = 0; k < 1000; ++k) b->step(1e-3);
    CHECK(b->states()[0].position.z() == Approx(z0).margin(1e-10));
    CHECK(b->states()[0].velocity.norm() < 1e-10);
    CHECK(floorForce(*b) == Approx(s.grains[0].volume()).epsilon(1e-8));
  }
}

TEST_CASE("nscd common plane: a pinacoid face down on another rests on 4 points, with the weight through the pair",
          "[nscd]") {
  const std::string detection = GENERATE("exact", "common_plane");
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, kOnFace), 0.0));
  s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, kOnFace), topOf(s.grains[0])));
  const double z1 = s.grains[1].position.z();
  auto b = nscd::makeNscdBackend(s, {{"contact_detection", detection}});
  for (int k = 0; k < 200; ++k) b->step(1e-3);
  const core::Contact* pair = nullptr;
  for (const auto& c : b->contacts())
    if (c.b == 1) pair = &c;
  REQUIRE(pair != nullptr);
  INFO(detection);
  CHECK(pair->type == core::ContactType::Triple);
  if (detection == "common_plane") CHECK(pair->points.size() == 4);
  CHECK(pair->normalForce() == Approx(s.grains[1].volume()).epsilon(1e-6));
  CHECK(b->states()[1].position.z() == Approx(z1).margin(1e-9));
}

TEST_CASE("nscd contact model: bad values are refused by name", "[nscd]") {
  core::SystemDef s = boxSystem(20.0, 10.0, false, 0.0);
  s.grains.push_back(withBottomAt(pinacoid(1.0, {10.0, 5.0, 0.0}, kOnFace), 0.0));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"contact_law", "iqs"}}), Catch::Contains("contact_law"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"contact_detection", "cundall"}}), Catch::Contains("contact_detection"));
  CHECK_THROWS_WITH(nscd::makeNscdBackend(s, {{"common_plane_band", 0.0}}), Catch::Contains("common_plane_band"));
  const auto resolved = nscd::makeNscdBackend(s, nlohmann::json::object())->settings();
  CHECK(resolved["contact_law"] == "gap");
  CHECK(resolved["contact_detection"] == "exact");
  CHECK(resolved["common_plane_band"] == 0.1);
}
