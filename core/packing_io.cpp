#include "core/packing_io.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include "core/input_document.hpp"
#include "core/json_input.hpp"
#include "core/settings_table.hpp"

namespace confpack::core {

namespace {

using nlohmann::json;

// Orientations and normals are stored as given when they are unit to this tolerance, so that
// written files read back bit for bit; anything else is normalised (a hand-written file with
// "[0.577, 0.577, 0.577]" is fine). Below kMinNorm a direction carries no information.
constexpr double kUnitTolerance = 1e-12;
constexpr double kMinNorm = 1e-6;
// point_forces must add up to normal_force; both are written from the same sum, so only a file
// edited by hand (or a foreign writer with its own rounding) can differ by more than this.
constexpr double kForceSumTolerance = 1e-9;

// A vector of three finite numbers, named `where` in full ("grains[4].position").
Vec3 toVec3(const ObjectReader& r, const json& v, const std::string& where) {
  if (!v.is_array() || v.size() != 3)
    refuseInput(r.source(), where, fmt::format("must be an array of 3 numbers (got {})", jsonExcerpt(v)));
  return Vec3(r.toNumber(v[0], where + "[0]"), r.toNumber(v[1], where + "[1]"), r.toNumber(v[2], where + "[2]"));
}

Vec3 vec3(const ObjectReader& r, std::string_view key) {
  return toVec3(r, r.at(key), r.field(key));
}

json toJsonVec(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

/// A direction (normal, quaternion) of unit length. Components near DBL_MAX overflow the plain
/// norm to infinity (dividing by it gave [0, 0, 0, 0], then refused as "norm 0"); the scaled
/// norm is only taken then, so that finite norms, and the bits of what they normalise, stay as
/// they were.
template <class Vector>
Vector unitOrFail(Vector v, std::string_view source, const std::string& where) {
  double n = v.norm();
  if (std::isinf(n)) n = v.stableNorm();
  if (!(n > kMinNorm)) refuseInput(source, where, fmt::format("cannot be normalised (norm {})", n));
  if (std::abs(n - 1.0) > kUnitTolerance) v /= n;
  return v;
}

Grain readGrain(const json& j, std::string_view source, std::size_t index) {
  ObjectReader r(j, source, fmt::format("grains[{}]", index));
  r.onlyKeys({"shape", "size", "params", "position", "orientation"});
  Grain g;
  const std::string shape = r.string("shape");
  if (shape == "sphere") {
    g.shape = ShapeKind::Sphere;
    if (r.has("params")) r.refuse("params", "only pinacoids have params");
  } else if (shape == "pinacoid") {
    g.shape = ShapeKind::Pinacoid;
    ObjectReader p(r.at("params"), source, r.field("params"));
    p.onlyKeys({"G", "E", "alpha_deg"});
    g.params.widthRatio = p.number("G");
    g.params.heightRatio = p.number("E");
    g.params.alphaDeg = p.number("alpha_deg");
  } else {
    r.refuse("shape", fmt::format("unknown shape '{}' (expected sphere or pinacoid)", shape));
  }
  g.size = r.number("size");
  g.position = vec3(r, "position");
  const json& q = r.at("orientation");
  if (!q.is_array() || q.size() != 4)
    r.refuse("orientation", fmt::format("must be [w, x, y, z] (got {})", jsonExcerpt(q)));
  const std::string qw = r.field("orientation");
  const Eigen::Vector4d c = unitOrFail(Eigen::Vector4d(r.toNumber(q[0], qw + "[0]"), r.toNumber(q[1], qw + "[1]"),
                                                       r.toNumber(q[2], qw + "[2]"), r.toNumber(q[3], qw + "[3]")),
                                       source, qw);
  g.orientation = Quat(c[0], c[1], c[2], c[3]);
  return g;
}

std::vector<double> readNumbers(const ObjectReader& r, std::string_view key, std::size_t count) {
  const json& a = r.array(key);
  if (a.size() != count) r.refuse(key, fmt::format("must have one entry per point ({}; got {})", count, a.size()));
  std::vector<double> out;
  for (std::size_t i = 0; i < a.size(); ++i) out.push_back(r.toNumber(a[i], fmt::format("{}[{}]", r.field(key), i)));
  return out;
}

// Normal forces: per point when given (they must add up to normal_force), else the total is
// shared equally between the points (the best guess when a writer only knows the sum); gaps.
void readNormalForces(const ObjectReader& r, Contact& c) {
  const std::size_t n = c.points.size();
  if (r.has("point_forces")) {
    const auto f = readNumbers(r, "point_forces", n);
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      c.points[i].normalForce = f[i];
      sum += f[i];
    }
    if (r.has("normal_force")) {
      const double total = r.number("normal_force");
      if (std::abs(total - sum) > kForceSumTolerance * std::max(1.0, std::abs(total)))
        r.refuse("normal_force", fmt::format("must equal the sum of point_forces ({}; got {})", sum, total));
    }
  } else {
    const double total = r.number("normal_force");
    for (auto& p : c.points) p.normalForce = total / static_cast<double>(n);
  }
  if (r.has("point_gaps")) {
    const auto g = readNumbers(r, "point_gaps", n);
    for (std::size_t i = 0; i < n; ++i) c.points[i].gap = g[i];
  }
}

// Friction: per point when given, else the total is shared in proportion to the normal forces
// (equally if they are all zero), which keeps the resultant exact.
void readTangentForces(const ObjectReader& r, Contact& c) {
  const std::size_t n = c.points.size();
  if (r.has("point_tangent_forces")) {
    const json& a = r.array("point_tangent_forces");
    if (a.size() != n)
      r.refuse("point_tangent_forces", fmt::format("must have one entry per point ({}; got {})", n, a.size()));
    Vec3 sum = Vec3::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      c.points[i].tangentForce = toVec3(r, a[i], fmt::format("{}[{}]", r.field("point_tangent_forces"), i));
      sum += c.points[i].tangentForce;
    }
    if (r.has("tangent_force")) {
      const Vec3 total = vec3(r, "tangent_force");
      if ((total - sum).norm() > kForceSumTolerance * std::max(1.0, total.norm()))
        r.refuse("tangent_force", "must equal the sum of point_tangent_forces");
    }
  } else if (r.has("tangent_force")) {
    const Vec3 total = vec3(r, "tangent_force");
    const double fn = c.normalForce();
    for (auto& p : c.points)
      p.tangentForce = fn > 0.0 ? Vec3(total * (p.normalForce / fn)) : Vec3(total / static_cast<double>(n));
  }
}

Contact readContact(const json& j, std::string_view source, std::size_t index) {
  ObjectReader r(j, source, fmt::format("contacts[{}]", index));
  r.onlyKeys({"a", "b", "type", "points", "normal", "normal_force", "point_forces", "point_gaps", "tangent_force",
              "point_tangent_forces"});
  Contact c;
  c.a = r.integer("a");
  c.b = r.integer("b");
  const std::string type = r.string("type");
  if (type == "simple")
    c.type = ContactType::Simple;
  else if (type == "double")
    c.type = ContactType::Double;
  else if (type == "triple")
    c.type = ContactType::Triple;
  else
    r.refuse("type", fmt::format("unknown contact type '{}' (expected simple, double or triple)", type));
  c.normal = unitOrFail(vec3(r, "normal"), source, r.field("normal"));

  const json& pts = r.array("points");
  if (pts.empty()) r.refuse("points", "must hold at least one point");
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ContactPoint p;
    p.position = toVec3(r, pts[i], fmt::format("{}[{}]", r.field("points"), i));
    c.points.push_back(p);
  }
  readNormalForces(r, c);
  readTangentForces(r, c);
  return c;
}

// The box's own keys and ranges (boxTable), and the walls' friction the file keeps in its box
// object; a packing must state its size.
void readBox(const json& box, std::string_view source, Packing& p) {
  try {
    boxTable().require(box, {"length_x", "width"});
    for (const auto& [key, value] : box.items())
      if (key == "wall_friction")
        readLegacyWallFriction(value, p.walls);
      else
        boxTable().readKey(key, value, p.box);
    boxTable().validate(p.box);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{}: {}", source, e.what()));
  }
}

/// Top-level layout: the header keys on their own lines, one grain or contact per line. Written by
/// hand because json::dump either puts everything on one line or every number on its own line;
/// the numbers themselves still come from nlohmann's shortest round-trip formatting.
std::string layout(const json& j) {
  std::string out = "{\n";
  const char* order[] = {"format", "version", "box", "grains", "contacts"};
  bool first = true;
  for (const char* key : order) {
    if (!j.contains(key)) continue;
    if (!first) out += ",\n";
    first = false;
    const json& v = j.at(key);
    out += fmt::format(" \"{}\": ", key);
    if (v.is_array()) {
      out += "[";
      for (std::size_t i = 0; i < v.size(); ++i) out += fmt::format("{}\n  {}", i ? "," : "", v[i].dump());
      out += v.empty() ? "]" : "\n ]";
    } else {
      out += v.dump();
    }
  }
  out += "\n}\n";
  return out;
}

// The invariants of grain `i` (named grains[i]) in `box`.
void validateGrain(const Grain& g, std::size_t i, const BoxDef& box, std::string_view source) {
  const std::string where = fmt::format("grains[{}]", i);
  if (!std::isfinite(g.size) || !(g.size > 0.0))
    refuseInput(source, where + ".size", fmt::format("must be > 0 (got {})", g.size));
  if (g.shape == ShapeKind::Pinacoid) {
    try {
      g.params.validate();
    } catch (const std::invalid_argument& e) {
      refuseInput(source, where + ".params", e.what());
    }
  }
  const Vec3& x = g.position;
  if (!x.allFinite()) refuseInput(source, where + ".position", "must be finite");
  if (!(x.x() >= 0.0 && x.x() < box.lengthX))
    refuseInput(source, where + ".position[0]",
                fmt::format("x must be in [0, length_x = {}) (got {})", box.lengthX, x.x()));
  if (box.periodicY) {
    if (!(x.y() >= 0.0 && x.y() < box.width))
      refuseInput(source, where + ".position[1]",
                  fmt::format("y must be in [0, width = {}) with periodic_y (got {})", box.width, x.y()));
  } else if (!(x.y() >= 0.0 && x.y() <= box.width)) {
    refuseInput(source, where + ".position[1]",
                fmt::format("y must lie between the side walls, in [0, width = {}] (got {})", box.width, x.y()));
  }
  // A centre below the floor would mean a grain more than half sunk into it.
  if (!(x.z() >= 0.0))
    refuseInput(source, where + ".position[2]", fmt::format("z must be >= 0, above the floor (got {})", x.z()));
  const double qn = g.orientation.coeffs().norm();
  if (!std::isfinite(qn) || std::abs(qn - 1.0) > 1e-9)
    refuseInput(source, where + ".orientation", fmt::format("must be a unit quaternion (norm {})", qn));
}

// The invariants of contact `k` (named contacts[k]) between `n` grains and the walls of `box`.
void validateContact(const Contact& c, std::size_t k, int n, const BoxDef& box, std::string_view source) {
  const std::string where = fmt::format("contacts[{}]", k);
  if (!(c.a >= 0 && c.a < n))
    refuseInput(source, where + ".a", fmt::format("must be a grain index in [0, {}) (got {})", n, c.a));
  const bool wall = isWall(c.b);
  if (wall) {
    if (c.b < -3)
      refuseInput(source, where + ".b", fmt::format("wall ids are -1 (floor), -2 (y = 0), -3 (y = W) (got {})", c.b));
    if (box.periodicY && c.b != static_cast<int>(WallId::Floor))
      refuseInput(source, where + ".b", fmt::format("no side wall {} in a box with periodic_y", c.b));
  } else {
    if (c.b >= n)
      refuseInput(source, where + ".b", fmt::format("must be a grain index in [0, {}) or a wall id (got {})", n, c.b));
    if (c.b == c.a) refuseInput(source, where + ".b", fmt::format("a grain cannot touch itself (a = b = {})", c.a));
  }
  if (!c.normal.allFinite() || std::abs(c.normal.norm() - 1.0) > 1e-9)
    refuseInput(source, where + ".normal", fmt::format("must be a unit vector (norm {})", c.normal.norm()));
  if (c.points.empty()) refuseInput(source, where + ".points", "must hold at least one point");
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const ContactPoint& pt = c.points[i];
    if (!pt.position.allFinite()) refuseInput(source, fmt::format("{}.points[{}]", where, i), "must be finite");
    if (!std::isfinite(pt.normalForce) || pt.normalForce < 0.0)
      refuseInput(source, fmt::format("{}.point_forces[{}]", where, i),
                  fmt::format("must be a finite force >= 0 (got {})", pt.normalForce));
    if (!std::isfinite(pt.gap)) refuseInput(source, fmt::format("{}.point_gaps[{}]", where, i), "must be finite");
    if (!pt.tangentForce.allFinite())
      refuseInput(source, fmt::format("{}.point_tangent_forces[{}]", where, i), "must be finite");
  }
}

}  // namespace

void validatePacking(const Packing& p, std::string_view source) {
  try {
    p.box.validate();
    p.walls.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{}: {}", source, e.what()));
  }
  if (p.grains.empty()) refuseInput(source, "grains", "must hold at least one grain");
  for (std::size_t i = 0; i < p.grains.size(); ++i) validateGrain(p.grains[i], i, p.box, source);
  if (!p.contacts) return;
  const int n = static_cast<int>(p.grains.size());
  for (std::size_t k = 0; k < p.contacts->size(); ++k) validateContact((*p.contacts)[k], k, n, p.box, source);
}

json toJson(const Packing& p) {
  validatePacking(p, "packing");
  json j;
  j["format"] = std::string(kPackingFormat);
  j["version"] = kPackingVersion;
  // The file keeps the walls' friction in its box object (docs/packing-format.md).
  j["box"] = p.box;
  j["box"]["wall_friction"] = p.walls.friction;
  json grains = json::array();
  for (const Grain& g : p.grains) {
    json e = {
        {"shape", std::string(toString(g.shape))},
        {"size", g.size},
        {"position", toJsonVec(g.position)},
        {"orientation", json::array({g.orientation.w(), g.orientation.x(), g.orientation.y(), g.orientation.z()})}};
    if (g.shape == ShapeKind::Pinacoid) e["params"] = g.params;
    grains.push_back(std::move(e));
  }
  j["grains"] = std::move(grains);
  if (p.contacts) {
    json contacts = json::array();
    for (const Contact& c : *p.contacts) {
      json points = json::array(), forces = json::array(), gaps = json::array(), tangents = json::array();
      Vec3 tangent = Vec3::Zero();
      for (const ContactPoint& pt : c.points) {
        points.push_back(toJsonVec(pt.position));
        forces.push_back(pt.normalForce);
        gaps.push_back(pt.gap);
        tangents.push_back(toJsonVec(pt.tangentForce));
        tangent += pt.tangentForce;
      }
      json e = {{"a", c.a},
                {"b", c.b},
                {"type", std::string(toString(c.type))},
                {"points", std::move(points)},
                {"normal", toJsonVec(c.normal)},
                {"normal_force", c.normalForce()},
                {"point_forces", std::move(forces)},
                {"point_gaps", std::move(gaps)}};
      // Grain-grain contacts are frictionless (docs/model.md, "Mixtures"): only wall contacts carry
      // a tangent force.
      if (isWall(c.b)) {
        e["tangent_force"] = toJsonVec(tangent);
        e["point_tangent_forces"] = std::move(tangents);
      }
      contacts.push_back(std::move(e));
    }
    j["contacts"] = std::move(contacts);
  }
  return j;
}

Packing packingFromJson(const json& j, std::string_view source) {
  const ObjectReader top = readDocument(j, source, {kPackingFormat, kPackingVersion},
                                        {"format", "version", "box", "grains", "contacts", "metadata"});
  Packing p;
  const json& box = top.at("box");
  readBox(box, source, p);
  const json& grains = top.array("grains");
  for (std::size_t i = 0; i < grains.size(); ++i) p.grains.push_back(readGrain(grains[i], source, i));

  if (!box.contains("height")) {
    // A foreign writer may not know the target height: use the top of the pile.
    double pileTop = 0.0;
    for (const Grain& g : p.grains) pileTop = std::max(pileTop, g.position.z() + g.boundingRadius());
    p.box.height = pileTop;
  }

  if (top.has("contacts")) {
    const json& contacts = top.array("contacts");
    p.contacts.emplace();
    for (std::size_t k = 0; k < contacts.size(); ++k) p.contacts->push_back(readContact(contacts[k], source, k));
  }
  validatePacking(p, source);
  return p;
}

void writePacking(const Packing& packing, const std::filesystem::path& path) {
  writeFileAtomically(path, layout(toJson(packing)));
}

Packing readPacking(const std::filesystem::path& path) {
  return packingFromJson(readJsonFile(path, "packing file"), path.string());
}

std::string hostName() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown-host";
  return buf;
}

std::filesystem::path privateFileName(const std::filesystem::path& dir, std::string_view stem) {
  static std::atomic<unsigned> counter{0};
  static const std::string host = hostName();
  return dir / fmt::format(".{}.{}.{}.{}", stem, host, ::getpid(), counter++);
}

namespace {
std::atomic<WriteFault> writeFault{nullptr};
}  // namespace

void setWriteFault(WriteFault fault) {
  writeFault = fault;
}

void writeFileAtomically(const std::filesystem::path& path, std::string_view text) {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  // Named after this host and process: tasks on several nodes write into one shared sweep folder.
  const std::filesystem::path tmp = privateFileName(dir, path.filename().string() + ".tmp");
  // No fsync: rename() already guarantees that readers see the old file or the whole new one,
  // which is the property we need; durability across a power cut is not worth a disk flush per
  // VTK frame.
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error(fmt::format("{}: cannot create ({})", tmp.string(), std::strerror(errno)));
  // The reason (disk full, quota) is errno of the call that failed, before anything else sets it.
  const WriteFault fault = writeFault.load();
  const int injected = fault != nullptr ? fault(path) : 0;
  const bool written = injected == 0 && std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const int writeError = injected != 0 ? injected : written ? 0 : errno;
  const bool closed = std::fclose(f) == 0;
  const int reason = writeError != 0 ? writeError : closed ? 0 : errno;  // 0: the C library gave none
  std::error_code ec;
  if (!written || !closed) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(
        fmt::format("{}: write failed ({})", path.string(), reason != 0 ? std::strerror(reason) : "no reason given"));
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw std::runtime_error(fmt::format("{}: cannot rename the temporary file ({})", path.string(), ec.message()));
  }
}

}  // namespace confpack::core
