// The fabric tensor (analysis/fabric.hpp; docs/model.md, "Order"): its anisotropy estimator and a
// lattice's fabric.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "analysis/coordination.hpp"
#include "analysis/fabric.hpp"
#include "analysis/geometric_contacts.hpp"
#include "core/random.hpp"
#include "tests/support/lattices.hpp"

using namespace confpack;
using confpack::testing::simpleCubic;

TEST_CASE("fabric anisotropy estimator", "[analysis][fabric]") {
  core::Rng rng(3, core::StreamId::Test);
  auto isotropic = [&]() {
    core::Vec3 v(rng.normal(), rng.normal(), rng.normal());
    return core::Vec3(v.normalized());
  };
  const int n = 40000;
  std::vector<core::Vec3> iso;
  for (int k = 0; k < n; ++k) iso.push_back(isotropic());
  CHECK(std::abs(analysis::fabricOfDirections(iso).anisotropy) < 5.0 / std::sqrt(double(n)) * 2.5);
  CHECK(analysis::fabricOfDirections(iso).tensor.trace() == Approx(1.0));
  // Rejection sampling of P ~ 1 + a (3 cos^2 - 1) about z.
  for (double a : {0.2, 0.5}) {
    std::vector<core::Vec3> dirs;
    while (static_cast<int>(dirs.size()) < n) {
      const core::Vec3 v = isotropic();
      if (rng.uniform() * (1 + 2 * a) < 1 + a * (3 * v.z() * v.z() - 1)) dirs.push_back(v);
    }
    const auto f = analysis::fabricOfDirections(dirs);
    CHECK(f.anisotropy == Approx(a).margin(0.03));
    CHECK(std::abs(f.majorAxis.z()) > 0.99);
  }
  // Three orthogonal pairs: exactly isotropic, a = 0.
  CHECK(analysis::fabricOfDirections({core::Vec3::UnitX(), core::Vec3::UnitY(), core::Vec3::UnitZ()}).anisotropy ==
        Approx(0.0).margin(1e-14));
}

TEST_CASE("fabric of a simple cubic lattice", "[analysis][fabric]") {
  const core::Packing sc = simpleCubic(4, 4, 10);
  const analysis::BulkRegion region = analysis::bulkRegion(sc);
  const auto counted = analysis::forceCarryingContacts(sc, analysis::geometricContacts(sc), true);
  const auto f = analysis::fabric(sc, region, counted);
  // F = I/3 exactly for the six lattice directions.
  CHECK(f.anisotropy == Approx(0.0).margin(1e-12));
  // Normals: one third vertical (|n_z| = 1 in the last bin), two thirds horizontal (first bin).
  const auto& h = f.orientation[3];
  CHECK(h.count == f.contacts);
  CHECK(h.cosTheta.back() == Approx(10.0 / 3.0));
  CHECK(h.cosTheta.front() == Approx(20.0 / 3.0));
  // Azimuth of the horizontal ones: 0 and 90 degrees only.
  CHECK(h.azimuth[0] + h.azimuth[9] == Approx(18.0));
}
