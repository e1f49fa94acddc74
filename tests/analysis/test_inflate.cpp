// The inflated reading (analysis/inflate.hpp): two touching spheres inflated by S overlap by the
// analytic lens, the grain volume and phi scale as S^3, a pinacoid's vertices move away from its
// centroid by S; through analyze(), every block is of the inflated grains.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "analysis/analyze.hpp"
#include "analysis/inflate.hpp"
#include "analysis/interpenetration.hpp"
#include "analysis/solid_fraction.hpp"
#include "tests/support/lattices.hpp"
#include "tests/support/systems.hpp"

using namespace confpack;
using confpack::testing::pinacoid;
using confpack::testing::simpleCubic;
using confpack::testing::sphere;

namespace {

// The lens of two spheres of radius R whose centres are d apart (d < 2R): two caps of height
// (2R - d)/2, V = pi (4R + d)(2R - d)^2 / 12.
double lensVolume(double radius, double d) {
  return std::numbers::pi * (4 * radius + d) * (2 * radius - d) * (2 * radius - d) / 12.0;
}

}  // namespace

TEST_CASE("two touching spheres inflated by S overlap by the analytic lens, phi scales as S^3", "[analysis][inflate]") {
  core::Packing p;
  p.box.lengthX = 6.0;
  p.box.width = 4.0;
  p.grains = {sphere(1.0, core::Vec3(2.5, 2.0, 5.0)), sphere(1.0, core::Vec3(3.5, 2.0, 5.0))};
  const analysis::BulkRegion region{10.0, 3.0, 7.0};  // holds both spheres whole, inflated or not
  const analysis::SolidFraction phi1 = analysis::solidFraction(p, region);
  REQUIRE(analysis::interpenetration(p, region).overlapVolume == 0.0);
  for (double s : {1.01, 1.05, 1.2, 1.5}) {
    INFO("S = " << s);
    const core::Packing inflated = analysis::inflate(p, s);
    const auto r = analysis::interpenetration(inflated, region);
    const double lens = lensVolume(0.5 * s, 1.0);
    // The sphere lens is exact (two closed-form caps), so to rounding.
    CHECK(r.overlappingPairs == 1);
    CHECK(r.overlapVolume == Approx(lens).epsilon(1e-12));
    CHECK(r.maxSphereDepth == Approx(s - 1.0).epsilon(1e-12));
    const analysis::SolidFraction phi = analysis::solidFraction(inflated, region);
    CHECK(phi.grainVolume == Approx(s * s * s * phi1.grainVolume).epsilon(1e-12));
    CHECK(phi.phi == Approx(s * s * s * phi1.phi).epsilon(1e-12));
    CHECK(r.exactPercent == Approx(100.0 * lens / phi.grainVolume).epsilon(1e-12));
  }
}

TEST_CASE("an inflated pinacoid is its vertices scaled about the centroid", "[analysis][inflate]") {
  core::Packing p;
  p.box.lengthX = 6.0;
  p.box.width = 4.0;
  const core::Quat q(Eigen::AngleAxisd(0.7, core::Vec3(1, 2, 3).normalized()));
  p.grains = {pinacoid(0.8, core::Vec3(2.0, 2.0, 3.0), q)};
  p.contacts = std::vector<core::Contact>{};
  const double s = 1.3;
  const core::Packing inflated = analysis::inflate(p, s);
  const core::Grain& g = inflated.grains[0];
  CHECK(g.position == p.grains[0].position);
  CHECK(g.orientation.coeffs() == p.grains[0].orientation.coeffs());
  CHECK(g.params == p.grains[0].params);
  CHECK(g.volume() == Approx(s * s * s * p.grains[0].volume()).epsilon(1e-12));
  const auto before = p.grains[0].worldVertices(), after = g.worldVertices();
  REQUIRE(before.size() == after.size());
  for (std::size_t k = 0; k < before.size(); ++k)
    CHECK((after[k] - g.position - s * (before[k] - g.position)).norm() < 1e-12);
  // The contacts of the grains as they were are not those of the inflated grains.
  CHECK_FALSE(inflated.contacts.has_value());
}

TEST_CASE("an inflation below 1, above 1.5 or not finite is refused", "[analysis][inflate]") {
  const core::Packing p = simpleCubic(2, 2, 2);
  for (double s : {0.99, 0.0, -1.0, 1.51, std::nan(""), HUGE_VAL}) {
    INFO("S = " << s);
    CHECK_THROWS_AS(analysis::inflate(p, s), std::invalid_argument);
    analysis::AnalysisOptions o;
    o.inflate = s;
    CHECK_THROWS_WITH(o.validate(), Catch::Contains("inflate"));
  }
  CHECK(analysis::inflate(p, 1.0).grains[3].size == 1.0);
  CHECK(analysis::inflate(p, 1.5).grains[3].size == 1.5);
}

TEST_CASE("analyze with inflate: every block of the inflated grains, the equilibrium of the grains as they are",
          "[analysis][inflate][analyze]") {
  core::Packing p = simpleCubic(6, 5, 12);
  const double s = 1.2;  // below sqrt 2: only the six nearest neighbours overlap
  analysis::AnalysisOptions o;
  o.inflate = s;
  const analysis::Analysis exact = analysis::analyze(p);
  const analysis::Analysis a = analysis::analyze(p, o);
  CHECK(exact.inflate == 1.0);
  CHECK(a.inflate == s);
  CHECK(a.meanSize == Approx(s));
  CHECK(a.geometricContacts);
  CHECK(a.coordination.z == Approx(6.0));
  // Every overlap is one nearest-neighbour lens.
  REQUIRE(a.interpenetration.overlappingPairs > 0);
  CHECK(a.interpenetration.overlapVolume ==
        Approx(a.interpenetration.overlappingPairs * lensVolume(0.5 * s, 1.0)).epsilon(1e-12));
  // phi of the inflated grains: S^3 pi / 6 over whole lattice periods; the slab found on the
  // inflated pile (its free surface (S - 1) / 2 higher) is not a whole number of them: within a
  // percent (0.4 % here).
  CHECK(exact.solid.phi == Approx(std::numbers::pi / 6).epsilon(1e-12));
  CHECK(a.solid.phi == Approx(s * s * s * std::numbers::pi / 6).epsilon(0.01));
  const nlohmann::json j = analysis::toJson(a);
  CHECK(j["inflate"] == s);
  CHECK(analysis::toJson(exact)["inflate"] == 1.0);
  CHECK(j["coordination_band"].is_null());

  // A packing with forces: its contacts are not the inflated grains' (geometric contacts instead),
  // but the equilibrium test weighs its forces on the grains as they are.
  core::Contact c;
  c.a = 0;
  c.b = 1;
  c.normal = core::Vec3::UnitX();
  c.points.push_back({core::Vec3(1.0, 0.5, 0.5), 0.3});
  p.contacts = std::vector<core::Contact>{c};
  const analysis::Analysis withForces = analysis::analyze(p, o);
  CHECK(withForces.geometricContacts);
  CHECK(withForces.coordination.z == Approx(6.0));
  REQUIRE(withForces.equilibrium.has_value());
  CHECK(nlohmann::json(*withForces.equilibrium) == nlohmann::json(*analysis::analyze(p).equilibrium));
}
