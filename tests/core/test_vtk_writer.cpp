// ParaView output (core/vtk_writer.hpp; docs/model.md, "ParaView"): the files are well-formed XML
// whose declared counts match both the arrays they contain and the packing they were written from.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "core/random.hpp"
#include "core/vtk_writer.hpp"
#include "tests/support/scratch.hpp"

using namespace confpack::core;
namespace fs = std::filesystem;

namespace {

/// A deliberately small XML reader, enough to check what we write (no python at test time):
/// tags must nest and close, and every DataArray's text must be numbers.
struct Element {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::vector<double> numbers;  ///< text content parsed as numbers (DataArray)
  std::string parent;
};

std::vector<Element> parseXml(const std::string& text) {
  std::vector<Element> elements;
  std::vector<std::string> stack;
  std::size_t pos = 0;
  while ((pos = text.find('<', pos)) != std::string::npos) {
    const std::size_t end = text.find('>', pos);
    REQUIRE(end != std::string::npos);
    std::string tag = text.substr(pos + 1, end - pos - 1);
    pos = end + 1;
    if (tag.starts_with("?")) {
      REQUIRE(tag.ends_with("?"));
      continue;
    }
    if (tag.starts_with("/")) {
      REQUIRE_FALSE(stack.empty());
      REQUIRE(stack.back() == tag.substr(1));
      stack.pop_back();
      continue;
    }
    const bool selfClosing = tag.ends_with("/");
    if (selfClosing) tag.pop_back();
    Element e;
    std::istringstream in(tag);
    in >> e.name;
    e.parent = stack.empty() ? "" : stack.back();
    // Attributes: name="value" pairs.
    std::size_t a = tag.find(' ');
    while (a != std::string::npos && (a = tag.find_first_not_of(' ', a)) != std::string::npos) {
      const std::size_t eq = tag.find('=', a);
      REQUIRE(eq != std::string::npos);
      REQUIRE(tag[eq + 1] == '"');
      const std::size_t close = tag.find('"', eq + 2);
      REQUIRE(close != std::string::npos);
      e.attributes[tag.substr(a, eq - a)] = tag.substr(eq + 2, close - eq - 2);
      a = close + 1;
    }
    if (e.name == "DataArray") {
      const std::size_t next = text.find('<', pos);
      std::istringstream values(text.substr(pos, next - pos));
      std::string token;
      while (values >> token) {
        char* stop = nullptr;
        const double v = std::strtod(token.c_str(), &stop);
        INFO("token " << token);
        REQUIRE(*stop == '\0');
        e.numbers.push_back(v);
      }
    }
    elements.push_back(e);
    if (!selfClosing) stack.push_back(e.name);
  }
  REQUIRE(stack.empty());  // every tag closed
  return elements;
}

std::vector<Element> parseFile(const fs::path& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::stringstream s;
  s << in.rdbuf();
  return parseXml(s.str());
}

const Element& piece(const std::vector<Element>& es) {
  for (const auto& e : es)
    if (e.name == "Piece") return e;
  FAIL("no Piece");
  return es.front();
}

/// The DataArray named `name` under the element `parent` (the Points array has no name).
const Element& array(const std::vector<Element>& es, const std::string& parent, const std::string& name) {
  for (const auto& e : es)
    if (e.name == "DataArray" && e.parent == parent &&
        (name.empty() || e.attributes.count("Name") && e.attributes.at("Name") == name))
      return e;
  FAIL("no DataArray " << name << " under " << parent);
  return es.front();
}

int components(const Element& e) {
  return e.attributes.count("NumberOfComponents") ? std::stoi(e.attributes.at("NumberOfComponents")) : 1;
}

Packing mixedPacking(int spheres, int pinacoids, bool withContacts) {
  Packing p;
  p.box.lengthX = 5.0;
  p.box.width = 3.0;
  Rng rng(5, StreamId::Test);
  for (int i = 0; i < spheres + pinacoids; ++i) {
    Grain g;
    g.shape = i < spheres ? ShapeKind::Sphere : ShapeKind::Pinacoid;
    g.size = 0.5 + 0.5 * rng.uniform();
    g.position = Vec3(rng.uniform(0.0, 5.0), rng.uniform(0.0, 3.0), rng.uniform(0.5, 3.0));
    g.orientation = rng.uniformQuaternion();
    p.grains.push_back(g);
  }
  if (withContacts) {
    std::vector<Contact> cs;
    Contact c;
    c.a = 0;
    c.b = 1;
    c.normal = Vec3::UnitX();
    c.points.push_back({p.grains[0].position, 0.25, Vec3::Zero(), 0.0});
    cs.push_back(c);
    c.b = static_cast<int>(WallId::Floor);
    c.type = ContactType::Double;
    c.normal = -Vec3::UnitZ();
    c.points = {{Vec3(1, 1, 0), 0.5, Vec3::Zero(), 0.0}, {Vec3(1.2, 1, 0), 0.75, Vec3::Zero(), 0.0}};
    cs.push_back(c);
    // A pair across the periodic boundary: the line must go to the nearest image.
    c = Contact{};
    c.a = spheres;  // a pinacoid
    c.b = 2;
    p.grains[spheres].position.x() = 0.1;
    p.grains[2].position.x() = 4.9;
    c.normal = -Vec3::UnitX();
    c.points.push_back({Vec3(0.0, 1, 1), 1.0, Vec3::Zero(), 0.0});
    c.type = ContactType::Triple;
    cs.push_back(c);
    p.contacts = cs;
  }
  return p;
}

}  // namespace

TEST_CASE("the grains file holds one vertex per sphere and eight world-space faces per pinacoid") {
  const fs::path dir = confpack::testing::scratchPath("vtk_grains");
  const int spheres = 7, pinacoids = 4;
  const Packing p = mixedPacking(spheres, pinacoids, false);
  std::vector<Vec3> velocities(p.grains.size(), Vec3(0.0, 0.0, -0.5));
  VtkSeries series(dir, "frame");
  const VtkFrameCounts counts = series.addFrame(0.0, p, velocities);
  CHECK(counts.verts == spheres);
  CHECK(counts.polys == 8 * pinacoids);
  CHECK(counts.grainPoints == spheres + 8 * pinacoids);
  CHECK(counts.lines == 0);

  const auto es = parseFile(dir / "frame_grains_000000.vtp");
  CHECK(es.front().name == "VTKFile");
  CHECK(es.front().attributes.at("type") == "PolyData");
  CHECK(es.front().attributes.at("version") == "1.0");
  CHECK(es.front().attributes.at("byte_order") == "LittleEndian");
  const Element& pc = piece(es);
  const int nPoints = std::stoi(pc.attributes.at("NumberOfPoints"));
  CHECK(nPoints == spheres + 8 * pinacoids);
  CHECK(std::stoi(pc.attributes.at("NumberOfVerts")) == spheres);
  CHECK(std::stoi(pc.attributes.at("NumberOfPolys")) == 8 * pinacoids);
  const Element& points = array(es, "Points", "");
  CHECK(components(points) == 3);
  CHECK(points.numbers.size() == 3u * nPoints);
  CHECK(array(es, "PointData", "diameter").numbers.size() == static_cast<std::size_t>(nPoints));
  CHECK(array(es, "PointData", "velocity").numbers.size() == 3u * nPoints);
  CHECK(array(es, "CellData", "id").numbers.size() == static_cast<std::size_t>(spheres + 8 * pinacoids));
  // Sphere vertices are the centres, with the diameter; offsets end at the connectivity size.
  CHECK(points.numbers[0] == p.grains[0].position.x());
  CHECK(array(es, "PointData", "diameter").numbers[0] == p.grains[0].size);
  const Element& polyOffsets = array(es, "Polys", "offsets");
  const Element& polyConn = array(es, "Polys", "connectivity");
  REQUIRE(polyOffsets.numbers.size() == static_cast<std::size_t>(8 * pinacoids));
  CHECK(polyOffsets.numbers.back() == polyConn.numbers.size());
  // 4 triangles + 4 trapezoids per pinacoid: 28 corner references each.
  CHECK(polyConn.numbers.size() == static_cast<std::size_t>(28 * pinacoids));
  for (double id : polyConn.numbers) CHECK((id >= spheres && id < nPoints));
  // The first pinacoid's points are its world vertices: all at its bounding radius or closer,
  // and their mean is its centre (the pinacoid is centrally symmetric).
  const Grain& g = p.grains[spheres];
  Vec3 mean = Vec3::Zero();
  for (int v = 0; v < 8; ++v) {
    const Vec3 x(points.numbers[3 * (spheres + v)], points.numbers[3 * (spheres + v) + 1],
                 points.numbers[3 * (spheres + v) + 2]);
    CHECK((x - g.position).norm() <= g.boundingRadius() + 1e-12);
    mean += x / 8.0;
  }
  CHECK((mean - g.position).norm() < 1e-12);
  fs::remove_all(dir);
}

TEST_CASE("contacts are lines with their force and type, the pvd lists every frame") {
  const fs::path dir = confpack::testing::scratchPath("vtk_contacts");
  const Packing p = mixedPacking(5, 2, true);
  VtkSeries series(dir, "run");
  series.addFrame(0.0, p);
  Packing noContacts = p;
  noContacts.contacts.reset();
  series.addFrame(0.5, noContacts);
  const VtkFrameCounts c = series.addFrame(1.25, p);
  series.finish();
  CHECK(c.lines == 3);

  const auto es = parseFile(dir / "run_contacts_000002.vtp");
  const Element& pc = piece(es);
  CHECK(std::stoi(pc.attributes.at("NumberOfLines")) == 3);
  CHECK(std::stoi(pc.attributes.at("NumberOfPoints")) == 6);
  const auto& force = array(es, "CellData", "normal_force").numbers;
  REQUIRE(force.size() == 3);
  CHECK(force[0] == 0.25);
  CHECK(force[1] == 1.25);  // sum over the two points of the double contact
  const auto& type = array(es, "CellData", "type").numbers;
  CHECK(type == std::vector<double>{0, 1, 2});
  CHECK(array(es, "Lines", "offsets").numbers == std::vector<double>{2, 4, 6});
  // The periodic pair: from x = 0.1 to the image of x = 4.9 at -0.1, not across the box.
  const auto& pts = array(es, "Points", "").numbers;
  CHECK(pts[12] == Approx(0.1));
  CHECK(pts[15] == Approx(-0.1));

  // Collections: three grain frames, two contact frames (frame 1 had no contact list).
  const auto grainsPvd = parseFile(series.grainsCollection());
  std::vector<std::string> files;
  std::vector<double> times;
  for (const auto& e : grainsPvd)
    if (e.name == "DataSet") {
      files.push_back(e.attributes.at("file"));
      times.push_back(std::stod(e.attributes.at("timestep")));
      CHECK(e.parent == "Collection");
    }
  CHECK(times == std::vector<double>{0.0, 0.5, 1.25});
  for (const auto& f : files) CHECK(fs::exists(dir / f));
  int contactSets = 0;
  for (const auto& e : parseFile(series.contactsCollection())) contactSets += e.name == "DataSet";
  CHECK(contactSets == 2);
  fs::remove_all(dir);
}

TEST_CASE("a frame with a wrong velocity count is refused") {
  const fs::path dir = confpack::testing::scratchPath("vtk_bad");
  const Packing p = mixedPacking(3, 0, false);
  VtkSeries series(dir, "f");
  std::vector<Vec3> v(2, Vec3::Zero());
  CHECK_THROWS_AS(series.addFrame(0.0, p, v), std::invalid_argument);
  fs::remove_all(dir);
}
