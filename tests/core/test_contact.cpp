// Contact (core/contact.hpp): contact type names, and the total force on b of a multi-point
// contact.
#include <catch2/catch.hpp>
#include <stdexcept>

#include "core/contact.hpp"

using namespace confpack::core;

TEST_CASE("contact types round-trip through their names, and an unknown name is refused") {
  for (const ContactType t : {ContactType::Simple, ContactType::Double, ContactType::Triple})
    CHECK(contactTypeFromString(toString(t)) == t);
  CHECK(toString(ContactType::Triple) == "triple");
  CHECK_THROWS_AS(contactTypeFromString("quadruple"), std::invalid_argument);
  CHECK_THROWS_AS(contactTypeFromString("Simple"), std::invalid_argument);
}

TEST_CASE("the force on b sums the points' normal forces along the normal and their tangential forces") {
  // A wall contact with three points: normal (0, 0, -1), normal forces 1, 2 and 0.5, and
  // tangential forces in the wall plane. Force on b = (sum f_n) n + sum f_t; on a it is opposite.
  Contact c;
  c.a = 4;
  c.b = -1;
  c.type = ContactType::Triple;
  c.normal = Vec3(0.0, 0.0, -1.0);
  c.points = {{Vec3(0, 0, 0), 1.0, Vec3(0.1, 0.0, 0.0), -1e-3},
              {Vec3(1, 0, 0), 2.0, Vec3(0.0, -0.2, 0.0), 0.0},
              {Vec3(0, 1, 0), 0.5, Vec3(0.3, 0.4, 0.0), 2e-4}};
  CHECK(c.normalForce() == 3.5);
  const Vec3 f = c.forceOnB();
  CHECK(f.x() == Approx(0.4).epsilon(1e-15));
  CHECK(f.y() == Approx(0.2).epsilon(1e-15));
  CHECK(f.z() == -3.5);
  CHECK(f.dot(c.normal) == 3.5);  // the tangential forces are orthogonal to the normal
  CHECK(Contact{}.normalForce() == 0.0);
  CHECK(Contact{}.forceOnB() == Vec3::Zero());
}
