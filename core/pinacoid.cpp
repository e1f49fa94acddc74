#include "core/pinacoid.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "core/settings_table.hpp"

namespace confpack::core {

const SettingsTable<PinacoidParams>& pinacoidTable() {
  using P = PinacoidParams;
  static const SettingsTable<P> table = [] {
    SettingsTable<P> t("pinacoid");
    t.number("G", &P::widthRatio, Range::positive(), "L", "width G (body y) relative to the length L")
        .number("E", &P::heightRatio, Range::positive(), "L", "height E (body z) relative to the length L")
        .number("alpha_deg", &P::alphaDeg, Range::open(0.0, 90.0), "degrees", "inclination of the triangular end faces")
        .rule([](const P& p) {
          const double l = pinacoidRidgeHalfLength(1.0, p);
          if (!(l > 0.0))
            throw std::invalid_argument(fmt::format(
                "pinacoid: with E={} and alpha={} deg the ridge half-length l = L/2 - (E/2)/tan(alpha) is {} <= 0",
                p.heightRatio, p.alphaDeg, l));
        });
    return t;
  }();
  return table;
}

void PinacoidParams::validate() const {
  pinacoidTable().validate(*this);
}

void to_json(nlohmann::json& j, const PinacoidParams& p) {
  j = pinacoidTable().write(p);
}

void from_json(const nlohmann::json& j, PinacoidParams& p) {
  p = PinacoidParams{};
  pinacoidTable().read(j, p);
}

double pinacoidRidgeHalfLength(double length, const PinacoidParams& p) {
  const double e = p.heightRatio * length;
  return 0.5 * length - 0.5 * e / std::tan(p.alphaDeg * std::numbers::pi / 180.0);
}

ConvexPolyhedron makePinacoid(double length, const PinacoidParams& p) {
  p.validate();
  const double a = 0.5 * length;
  const double g = 0.5 * p.widthRatio * length;
  const double e = 0.5 * p.heightRatio * length;
  const double l = pinacoidRidgeHalfLength(length, p);
  // 0..3: mid-plane rectangle, 4..7: ridge ends (top ridge 4,5; bottom ridge 6,7).
  std::vector<Vec3> v = {{a, g, 0}, {-a, g, 0}, {-a, -g, 0}, {a, -g, 0},
                         {l, 0, e}, {-l, 0, e}, {l, 0, -e},  {-l, 0, -e}};
  std::vector<std::vector<int>> f = {
      {0, 1, 5, 4},  // top trapezoid, y > 0
      {2, 3, 4, 5},  // top trapezoid, y < 0
      {1, 0, 6, 7},  // bottom trapezoid, y > 0
      {3, 2, 7, 6},  // bottom trapezoid, y < 0
      {3, 0, 4},     // top triangle, x > 0
      {1, 2, 5},     // top triangle, x < 0
      {0, 3, 6},     // bottom triangle, x > 0
      {2, 1, 7},     // bottom triangle, x < 0
  };
  return ConvexPolyhedron(std::move(v), std::move(f));
}

MassProperties pinacoidMassProperties(double length, const PinacoidParams& p) {
  // docs/model.md, "Pinacoids", with A = L/2, B = L/2 - l, g = G/2.
  const double L = length;
  const double G = p.widthRatio * L;
  const double E = p.heightRatio * L;
  const double l = pinacoidRidgeHalfLength(L, p);
  const double A = 0.5 * L, B = 0.5 * L - l, g = 0.5 * G;
  MassProperties mp;
  mp.volume = E * G * (L + l) / 3.0;
  const double xx = 4.0 / 3.0 * E * g * (A * A * A / 2 - A * A * B / 2 + A * B * B / 4 - B * B * B / 20);
  const double yy = 4.0 / 3.0 * E * g * g * g * (A / 4 - B / 20);
  const double zz = E * E * E * g * (A / 12 - B / 20);
  mp.secondMoment = Vec3(xx, yy, zz).asDiagonal();
  return mp;
}

}  // namespace confpack::core
