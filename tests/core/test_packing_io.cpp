// Packing file (docs/packing-format.md): exact round trip of every double, the documented keys, and
// one clear message naming element and field for each kind of bad input; and the atomic writes every
// output goes through.
#include <sys/resource.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "core/packing_io.hpp"
#include "core/random.hpp"
#include "tests/support/read_file.hpp"
#include "tests/support/scratch.hpp"

using namespace confpack::core;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using confpack::testing::slurp;

/// Names of the entries of a directory, sorted.
std::vector<std::string> filesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

/// A packing that exercises everything: spheres and pinacoids with awkward doubles, contacts
/// between grains and with each wall, with 1, 2 and 3 points.
Packing samplePacking() {
  Packing p;
  p.box.lengthX = 6.0;
  p.box.width = 4.0 / 3.0 + 3.0;  // not representable in decimal: exercises shortest round trip
  p.walls.friction = 0.3;
  p.box.height = 4.1;
  Rng rng(11, StreamId::Test);
  for (int i = 0; i < 12; ++i) {
    Grain g;
    g.shape = i % 3 == 2 ? ShapeKind::Pinacoid : ShapeKind::Sphere;
    g.size = 1.0 + 0.03 * rng.normal();
    if (g.shape == ShapeKind::Pinacoid) g.params = {0.9 + 0.1 * rng.uniform(), 0.8, 55.0 + rng.uniform()};
    g.position = Vec3(rng.uniform(0.0, p.box.lengthX), rng.uniform(0.0, p.box.width), rng.uniform(0.5, 4.0));
    g.orientation = rng.uniformQuaternion();
    p.grains.push_back(g);
  }
  p.grains[0].position.x() = 0.0;          // the closed end of [0, length_x)
  p.grains[1].position.y() = p.box.width;  // touching the far wall is allowed
  p.grains[3].position.z() = 1e-300;       // tiny but valid
  std::vector<Contact> cs;
  auto contact = [&](int a, int b, ContactType t, int points) {
    Contact c;
    c.a = a;
    c.b = b;
    c.type = t;
    c.normal = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
    for (int k = 0; k < points; ++k) {
      ContactPoint pt;
      pt.position = p.grains[a].position + 0.5 * Vec3(rng.normal(), rng.normal(), rng.normal());
      pt.normalForce = rng.uniform() / 3.0;
      pt.gap = -1e-4 * rng.uniform();
      if (isWall(b)) pt.tangentForce = Vec3(rng.normal(), 0.0, rng.normal()) * 0.1;
      c.points.push_back(pt);
    }
    cs.push_back(c);
  };
  contact(0, 1, ContactType::Simple, 1);
  contact(2, 5, ContactType::Double, 2);
  contact(5, 8, ContactType::Triple, 3);
  contact(3, -1, ContactType::Simple, 1);
  contact(4, -2, ContactType::Simple, 1);
  contact(1, -3, ContactType::Double, 2);
  p.contacts = cs;
  return p;
}

void requireSame(const Packing& a, const Packing& b) {
  REQUIRE(a.box.lengthX == b.box.lengthX);
  REQUIRE(a.box.width == b.box.width);
  REQUIRE(a.box.periodicY == b.box.periodicY);
  REQUIRE(a.walls.friction == b.walls.friction);
  REQUIRE(a.box.height == b.box.height);
  REQUIRE(a.grains.size() == b.grains.size());
  for (std::size_t i = 0; i < a.grains.size(); ++i) {
    const Grain &x = a.grains[i], &y = b.grains[i];
    CHECK(x.shape == y.shape);
    CHECK(x.size == y.size);
    if (x.shape == ShapeKind::Pinacoid) CHECK(x.params == y.params);
    CHECK(x.position == y.position);  // exact: doubles must survive text bit for bit
    CHECK(x.orientation.coeffs() == y.orientation.coeffs());
  }
  REQUIRE(a.contacts.has_value() == b.contacts.has_value());
  if (!a.contacts) return;
  REQUIRE(a.contacts->size() == b.contacts->size());
  for (std::size_t k = 0; k < a.contacts->size(); ++k) {
    const Contact &x = (*a.contacts)[k], &y = (*b.contacts)[k];
    CHECK(x.a == y.a);
    CHECK(x.b == y.b);
    CHECK(x.type == y.type);
    CHECK(x.normal == y.normal);
    REQUIRE(x.points.size() == y.points.size());
    for (std::size_t i = 0; i < x.points.size(); ++i) {
      CHECK(x.points[i].position == y.points[i].position);
      CHECK(x.points[i].normalForce == y.points[i].normalForce);
      CHECK(x.points[i].gap == y.points[i].gap);
      CHECK(x.points[i].tangentForce == y.points[i].tangentForce);
    }
  }
}

/// Expects packingFromJson to refuse `j` with a message containing `expected`.
void requireRefused(const json& j, const std::string& expected) {
  INFO("expected message containing: " << expected);
  try {
    (void)packingFromJson(j, "packing.json");
    FAIL("accepted a bad packing");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    INFO("got: " << what);
    CHECK(what.find(expected) != std::string::npos);
    CHECK(what.rfind("packing.json: ", 0) == 0);
    CHECK(what.find('\n') == std::string::npos);  // one line
  }
}

}  // namespace

TEST_CASE("a packing file round-trips every double exactly") {
  const fs::path dir = confpack::testing::freshDir("packing_io_roundtrip");
  const Packing p = samplePacking();
  writePacking(p, dir / "packing.json");
  const Packing q = readPacking(dir / "packing.json");
  requireSame(p, q);
  // Written a second time, the text is identical (stable, deterministic output).
  writePacking(q, dir / "again.json");
  std::ifstream a(dir / "packing.json"), b(dir / "again.json");
  const std::string ta((std::istreambuf_iterator<char>(a)), {}), tb((std::istreambuf_iterator<char>(b)), {});
  CHECK(ta == tb);
  // No temporary file is left next to the outputs.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++files;
  }
  CHECK(files == 2);
  fs::remove_all(dir);
}

TEST_CASE("a packing without contacts reads back without a contact list") {
  Packing p = samplePacking();
  p.contacts.reset();
  const json j = toJson(p);
  CHECK_FALSE(j.contains("contacts"));
  const Packing q = packingFromJson(j);
  CHECK_FALSE(q.contacts.has_value());
  requireSame(p, q);
  // An empty list is not the same as no list: it means "a run found no contacts".
  p.contacts.emplace();
  CHECK(packingFromJson(toJson(p)).contacts.has_value());
}

TEST_CASE("the packing document has exactly the documented keys") {
  const json j = toJson(samplePacking());
  CHECK(j.at("format") == "confpack-packing");
  CHECK(j.at("version") == 1);
  for (const char* k : {"length_x", "width", "periodic_y", "wall_friction", "height"}) CHECK(j.at("box").contains(k));
  CHECK(j.at("box").size() == 5);
  const json& sphere = j.at("grains")[0];
  CHECK(sphere.at("shape") == "sphere");
  CHECK_FALSE(sphere.contains("params"));
  CHECK(sphere.at("orientation").size() == 4);
  const json& pin = j.at("grains")[2];
  CHECK(pin.at("shape") == "pinacoid");
  CHECK(pin.at("params").contains("G"));
  CHECK(pin.at("params").contains("E"));
  CHECK(pin.at("params").contains("alpha_deg"));
  const json& c = j.at("contacts")[1];
  CHECK(c.at("type") == "double");
  CHECK(c.at("points").size() == 2);
  // normal_force is the sum over the points.
  CHECK(c.at("normal_force").get<double>() ==
        Approx(c.at("point_forces")[0].get<double>() + c.at("point_forces")[1].get<double>()));
  CHECK_FALSE(c.contains("tangent_force"));              // grain-grain: frictionless
  CHECK(j.at("contacts")[4].contains("tangent_force"));  // wall contact
}

TEST_CASE("a minimal hand-written packing is accepted and completed") {
  // What another tool might write: no optional box keys, unnormalised quaternion and normal,
  // only totals for the forces.
  const json j = json::parse(R"({
    "format": "confpack-packing", "version": 1,
    "box": {"length_x": 4, "width": 4},
    "grains": [ {"shape": "sphere", "size": 1, "position": [0.5, 0.5, 0.5], "orientation": [2, 0, 0, 0]},
                {"shape": "sphere", "size": 1, "position": [1.5, 0.5, 0.5], "orientation": [1, 0, 0, 0]} ],
    "contacts": [ {"a": 0, "b": 1, "type": "simple", "points": [[1, 0.5, 0.5]], "normal": [3, 0, 0], "normal_force": 0.5},
                  {"a": 0, "b": -2, "type": "double", "points": [[0.5, 0, 0.3], [0.5, 0, 0.7]],
                   "normal": [0, -1, 0], "normal_force": 2, "tangent_force": [0, 0, 0.6]} ]
  })");
  const Packing p = packingFromJson(j);
  CHECK_FALSE(p.box.periodicY);
  CHECK(p.walls.friction == 0.0);
  CHECK(p.box.height == Approx(1.0));  // top of the pile when the file does not say
  CHECK(p.grains[0].orientation.w() == Approx(1.0));
  CHECK(p.grains[0].orientation.norm() == Approx(1.0));
  const Contact& c0 = (*p.contacts)[0];
  CHECK(c0.normal.x() == Approx(1.0));
  CHECK(c0.normalForce() == Approx(0.5));
  const Contact& c1 = (*p.contacts)[1];
  CHECK(c1.points[0].normalForce == Approx(1.0));  // total shared equally
  // The friction total is shared in proportion to the normal forces: the resultant is exact.
  CHECK(c1.forceOnB().z() == Approx(0.6));
  CHECK(c1.forceOnB().y() == Approx(-2.0));
}

TEST_CASE("bad packing files are refused with the element and field named") {
  const json good = toJson(samplePacking());
  auto with = [&](auto edit) {
    json j = good;
    edit(j);
    return j;
  };
  requireRefused(with([](json& j) { j.erase("format"); }), "format: missing (expected \"confpack-packing\")");
  requireRefused(with([](json& j) { j["format"] = "xyz-packing"; }),
                 "format: must be \"confpack-packing\" (got \"xyz-packing\")");
  requireRefused(with([](json& j) { j["version"] = 2; }), "version: must be 1, the version this build reads (got 2)");
  requireRefused(with([](json& j) { j.erase("version"); }), "version: missing (expected 1)");
  requireRefused(with([](json& j) { j["grain"] = json::array(); }),
                 "grain: unknown key (known: format, version, box, grains, contacts, metadata)");
  requireRefused(with([](json& j) { j.erase("grains"); }), "grains: missing");
  requireRefused(with([](json& j) { j["grains"] = json::array(); }), "grains: must hold at least one grain");
  requireRefused(with([](json& j) { j["box"]["width"] = 0; }), "box.width: must be > 0 (got 0)");
  requireRefused(with([](json& j) { j["box"]["length_x"] = "20"; }), "box.length_x: must be a number (got \"20\")");
  requireRefused(with([](json& j) { j["box"]["periodic_y"] = 1; }), "box.periodic_y: must be true or false");
  requireRefused(with([](json& j) { j["grains"][7]["size"] = -1; }), "grains[7].size: must be > 0 (got -1)");
  requireRefused(with([](json& j) { j["grains"][7]["size"] = nullptr; }), "grains[7].size: must be a finite number");
  requireRefused(with([](json& j) { j["grains"][3]["shape"] = "cube"; }), "grains[3].shape: unknown shape 'cube'");
  requireRefused(with([](json& j) {
                   j["grains"][0]["params"] = {{"G", 1}, {"E", 1}, {"alpha_deg", 60}};
                 }),
                 "grains[0].params: only pinacoids have params");
  requireRefused(with([](json& j) { j["grains"][2].erase("params"); }), "grains[2].params: missing");
  requireRefused(with([](json& j) { j["grains"][2]["params"]["alpha_deg"] = 95; }), "grains[2].params");
  requireRefused(with([](json& j) {
                   j["grains"][4]["position"] = {1, 2};
                 }),
                 "grains[4].position: must be an array of 3");
  requireRefused(with([](json& j) { j["grains"][4]["position"][0] = 6.0; }),
                 "grains[4].position[0]: x must be in [0, length_x = 6)");
  requireRefused(with([](json& j) { j["grains"][4]["position"][0] = -0.1; }), "grains[4].position[0]");
  requireRefused(with([](json& j) { j["grains"][4]["position"][1] = -0.01; }),
                 "grains[4].position[1]: y must lie between the side walls");
  requireRefused(with([](json& j) { j["grains"][4]["position"][2] = -0.5; }), "grains[4].position[2]: z must be >= 0");
  requireRefused(with([](json& j) {
                   j["box"]["periodic_y"] = true;
                   j["contacts"] = json::array();
                   j["grains"][1]["position"][1] = j["box"]["width"];
                 }),
                 "grains[1].position[1]: y must be in [0, width");
  requireRefused(with([](json& j) {
                   j["grains"][5]["orientation"] = {0, 0, 0, 0};
                 }),
                 "grains[5].orientation: cannot be normalised");
  requireRefused(with([](json& j) {
                   j["grains"][5]["orientation"] = {1, 0, 0};
                 }),
                 "grains[5].orientation: must be [w, x, y, z]");
  requireRefused(with([](json& j) {
                   j["grains"][5]["orientaion"] = {1, 0, 0, 0};
                 }),
                 "grains[5].orientaion: unknown key (known: shape, size, params, position, orientation)");
  requireRefused(with([](json& j) { j["contacts"][0]["a"] = 12; }),
                 "contacts[0].a: must be a grain index in [0, 12) (got 12)");
  requireRefused(with([](json& j) { j["contacts"][0]["a"] = 1.5; }), "contacts[0].a: must be an integer");
  requireRefused(with([](json& j) { j["contacts"][0]["b"] = -4; }), "contacts[0].b: wall ids are -1");
  requireRefused(with([](json& j) { j["contacts"][0]["b"] = 0; }), "contacts[0].b: a grain cannot touch itself");
  requireRefused(with([](json& j) {
                   j["box"]["periodic_y"] = true;
                   j["grains"][1]["position"][1] = 1.0;
                 }),
                 "contacts[4].b: no side wall -2 in a box with periodic_y");
  requireRefused(with([](json& j) { j["contacts"][2]["type"] = "quadruple"; }),
                 "contacts[2].type: unknown contact type");
  requireRefused(with([](json& j) {
                   j["contacts"][2]["normal"] = {0, 0, 0};
                 }),
                 "contacts[2].normal: cannot be normalised");
  requireRefused(with([](json& j) { j["contacts"][2]["points"] = json::array(); }),
                 "contacts[2].points: must hold at least one point");
  requireRefused(with([](json& j) { j["contacts"][2]["point_forces"] = {1.0}; }),
                 "contacts[2].point_forces: must have one entry per point");
  requireRefused(with([](json& j) { j["contacts"][2]["normal_force"] = 99.0; }),
                 "contacts[2].normal_force: must equal the sum");
  requireRefused(with([](json& j) {
                   j["contacts"][0]["point_forces"] = {-1.0};
                   j["contacts"][0].erase("normal_force");
                 }),
                 "contacts[0].point_forces[0]: must be a finite force >= 0");
  requireRefused(json::array(), "document: must be a JSON object (got array)");
}

TEST_CASE("reading a broken or missing file gives one clear message") {
  const fs::path dir = confpack::testing::freshDir("packing_io_broken");
  {
    std::ofstream f(dir / "bad.json");
    f << R"({"format": "confpack-packing", "version": 1, "box": )";
  }
  CHECK_THROWS_WITH(readPacking(dir / "bad.json"), Catch::Contains("bad.json: not valid JSON"));
  CHECK_THROWS_WITH(readPacking(dir / "absent.json"), Catch::Contains("absent.json: cannot open"));
  CHECK_THROWS_WITH(readPacking(dir), Catch::Contains("is a folder, not a packing file"));
  {
    std::ofstream f(dir / "huge.json");
    f << R"({"format": "confpack-packing", "version": 1, "grains": [{"position": [1e400, 0, 0]}]})";
  }
  CHECK_THROWS_WITH(readPacking(dir / "huge.json"),
                    Catch::Contains("huge.json: grains[0].position[0]: a number out of the range of a double"));
  fs::remove_all(dir);
}

TEST_CASE("a refusal echoes a long key or a deeply nested value only in part") {
  // Issue 23, failure 8: a 10 MB unknown key was echoed in full; a value nested 100,000 deep was
  // written out by a recursive dump().
  json j = toJson(samplePacking());
  j[std::string(10'000'000, 'k')] = 1;
  std::string message;
  try {
    (void)packingFromJson(j, "packing.json");
  } catch (const std::invalid_argument& e) {
    message = e.what();
  }
  CHECK_THAT(message, Catch::StartsWith("packing.json: kkkk") && Catch::Contains("...: unknown key"));
  CHECK(message.size() < 300);
  json deep = 1;
  for (int i = 0; i < 100000; ++i) deep = json::array({std::move(deep)});
  j = toJson(samplePacking());
  j["box"]["width"] = std::move(deep);
  message.clear();
  try {
    (void)packingFromJson(j, "packing.json");
  } catch (const std::invalid_argument& e) {
    message = e.what();
  }
  CHECK_THAT(message, Catch::StartsWith("packing.json: box.width: must be a number (got [[[["));
  CHECK(message.size() < 200);
}

TEST_CASE("a direction whose components overflow the norm is normalised, not called \"norm 0\"") {
  // Issue 23, failure 8: [1e308, 1e308, 0, 0] has a norm beyond DBL_MAX; dividing by the
  // infinite norm gave [0, 0, 0, 0], refused as "must be a unit quaternion (norm 0)".
  json j = toJson(samplePacking());
  j["grains"][0]["orientation"] = {1e308, 1e308, 0.0, 0.0};
  const Packing p = packingFromJson(j);
  CHECK(p.grains[0].orientation.w() == Approx(std::sqrt(0.5)));
  CHECK(p.grains[0].orientation.x() == Approx(std::sqrt(0.5)));
  CHECK(p.grains[0].orientation.norm() == Approx(1.0));
  j["grains"][0]["orientation"] = {0.0, 0.0, 0.0, 0.0};
  requireRefused(j, "grains[0].orientation: cannot be normalised (norm 0)");
}

TEST_CASE("writing refuses a packing that would not read back and leaves nothing behind") {
  const fs::path dir = confpack::testing::freshDir("packing_io_refuse");
  Packing p = samplePacking();
  p.grains[2].position.x() = p.box.lengthX;  // outside [0, length_x)
  CHECK_THROWS_WITH(writePacking(p, dir / "p.json"), Catch::Contains("grains[2].position[0]"));
  p.grains[2].position.x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(writePacking(p, dir / "p.json"), std::invalid_argument);
  CHECK(fs::is_empty(dir));
  // A directory that does not exist: runtime error, and no stray temporary anywhere.
  CHECK_THROWS_AS(writePacking(samplePacking(), dir / "missing" / "p.json"), std::runtime_error);
  CHECK(fs::is_empty(dir));
  fs::remove_all(dir);
}

TEST_CASE("an atomic write replaces the old file as a whole") {
  const fs::path dir = confpack::testing::freshDir("packing_io_atomic");
  writeFileAtomically(dir / "f.txt", "first version, longer than the second\n");
  writeFileAtomically(dir / "f.txt", "second\n");
  CHECK(slurp(dir / "f.txt") == "second\n");
  CHECK(filesIn(dir) == std::vector<std::string>{"f.txt"});
  fs::remove_all(dir);
}

namespace {

/// Caps the size of any file this process writes at `bytes` while it lives: a write past the cap
/// fails with EFBIG (SIGXFSZ ignored), as on a full disk or over a quota. Restores both on exit.
class FileSizeCap {
 public:
  explicit FileSizeCap(rlim_t bytes) {
    REQUIRE(::getrlimit(RLIMIT_FSIZE, &saved_) == 0);
    previousHandler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit capped = saved_;
    capped.rlim_cur = bytes;
    REQUIRE(::setrlimit(RLIMIT_FSIZE, &capped) == 0);
  }
  ~FileSizeCap() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previousHandler_);
  }
  FileSizeCap(const FileSizeCap&) = delete;
  FileSizeCap& operator=(const FileSizeCap&) = delete;

 private:
  rlimit saved_{};
  void (*previousHandler_)(int) = SIG_DFL;
};

}  // namespace

TEST_CASE("an atomic write that fails part-way leaves the old file whole and no temporary behind") {
  // The write fails after 4 KiB of the new text reached the disk. A plain truncating write would
  // have destroyed the old file by then and left 4 KiB of the new one in its place.
  const fs::path dir = confpack::testing::freshDir("packing_io_atomic_failure");
  const std::string old = "the old file, which a failed write must leave as it was\n";
  writeFileAtomically(dir / "f.txt", old);
  const std::string text(64 * 1024, 'x');
  {
    const FileSizeCap cap(4096);
    // The failure this guards against: the message said "write failed" without why (disk full, quota, here
    // the file size limit).
    CHECK_THROWS_WITH(writeFileAtomically(dir / "f.txt", text),
                      (dir / "f.txt").string() + ": write failed (" + std::strerror(EFBIG) + ")");
  }
  const std::string after = slurp(dir / "f.txt");
  INFO("f.txt now holds " << after.size() << " bytes, starting '" << after.substr(0, 16) << "'");
  CHECK((after == old));
  CHECK(filesIn(dir) == std::vector<std::string>{"f.txt"});
  // With the cap lifted the same write goes through: the failure above was the cap's.
  writeFileAtomically(dir / "f.txt", text);
  CHECK((slurp(dir / "f.txt") == text));
  fs::remove_all(dir);
}
