// confpack.Box, confpack.Contacts, confpack.Packing and read_packing (docs/packing-format.md).
//
// A Packing owns its core::Packing and never changes it: positions and sizes are read-only numpy
// views into the grains (zero copy, kept alive by the Packing); orientations (stored x, y, z, w by
// Eigen, given w, x, y, z as in the file) and the contacts (a variable number of points each) are
// copied into arrays when asked for. A packing made from arrays is validated by the packing file's
// own rules (core::validatePacking), so that what Python builds always writes and reads back.
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "core/packing_io.hpp"
#include "python/bindings.hpp"

namespace confpack::python {

namespace {

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Ints = py::array_t<long, py::array::c_style | py::array::forcecast>;

/// Shape of `a` as "(3, 4)", for messages.
std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += fmt::format("{}{}", k ? ", " : "", a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// Refuses an argument array whose shape is not (rows, columns), or (rows,) when columns is 0.
void requireShape(const py::array& a, const char* name, py::ssize_t rows, py::ssize_t columns) {
  const bool ok =
      columns == 0 ? a.ndim() == 1 && a.shape(0) == rows : a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == columns;
  if (!ok)
    throw std::invalid_argument(
        columns == 0 ? fmt::format("{}: expected shape ({},) (got {})", name, rows, shapeText(a))
                     : fmt::format("{}: expected shape ({}, {}) (got {})", name, rows, columns, shapeText(a)));
}

/// A read-only array over memory that `owner` keeps alive.
template <class T>
py::array readOnlyView(std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides, const T* data,
                       py::handle owner) {
  py::array a(py::dtype::of<T>(), std::move(shape), std::move(strides), data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// An (n, K) array whose row i fill(grain i, row) writes.
template <py::ssize_t K, class F>
py::array grainRows(const std::vector<core::Grain>& grains, F fill) {
  py::array_t<double> a({static_cast<py::ssize_t>(grains.size()), K});
  double* row = a.mutable_data();
  for (const core::Grain& g : grains) {
    fill(g, row);
    row += K;
  }
  return a;
}

/// Strings as a numpy array of str.
py::array stringArray(const std::vector<std::string_view>& names) {
  py::list list;
  for (auto n : names) list.append(py::str(n.data(), n.size()));
  return py::module_::import("numpy").attr("array")(list, "dtype"_a = "U");
}

/// The strings of a sequence (a numpy array of str, a list, or one string for every element).
std::vector<std::string> strings(const py::object& values, py::ssize_t count, const char* name) {
  if (py::isinstance<py::str>(values))
    return std::vector<std::string>(static_cast<std::size_t>(count), values.cast<std::string>());
  std::vector<std::string> out;
  for (const py::handle v : values) out.push_back(py::str(v).cast<std::string>());
  if (static_cast<py::ssize_t>(out.size()) != count)
    throw std::invalid_argument(fmt::format("{}: expected {} values (got {})", name, count, out.size()));
  return out;
}

/// The contacts of a packing as arrays: per contact a, b, type, normal and the totals; per point
/// (contact k owns points point_offsets[k] to point_offsets[k + 1]) position, normal force, gap and
/// friction force.
struct PyContacts {
  std::vector<core::Contact> contacts;

  /// Grain (or wall) ids of one end of every contact.
  py::array ids(int core::Contact::*end) const {
    std::vector<long> v;
    for (const auto& c : contacts) v.push_back(c.*end);
    return toArray(v);
  }
  /// value(contact) of every contact: a double or a Vec3 each.
  template <class F>
  py::array perContact(F value) const {
    std::vector<decltype(value(core::Contact{}))> v;
    for (const auto& c : contacts) v.push_back(value(c));
    return column(v);
  }
  /// value(point) of every point, contact after contact.
  template <class F>
  py::array perPoint(F value) const {
    std::vector<decltype(value(core::ContactPoint{}))> v;
    for (const auto& c : contacts)
      for (const auto& p : c.points) v.push_back(value(p));
    return column(v);
  }

 private:
  static py::array column(const std::vector<double>& v) { return toArray(v); }
  static py::array column(const std::vector<core::Vec3>& v) {
    py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
    auto o = a.mutable_unchecked<2>();
    for (std::size_t i = 0; i < v.size(); ++i)
      for (py::ssize_t k = 0; k < 3; ++k) o(static_cast<py::ssize_t>(i), k) = v[i][k];
    return a;
  }
};

PyContacts makeContacts(const Ints& a, const Ints& b, const Doubles& normals, const Doubles& points,
                        const std::optional<Ints>& pointOffsets, const py::object& types,
                        const std::optional<Doubles>& pointForces, const std::optional<Doubles>& pointGaps,
                        const std::optional<Doubles>& pointTangentForces) {
  const py::ssize_t m = a.ndim() == 1 ? a.shape(0) : -1;
  requireShape(a, "a", m, 0);
  requireShape(b, "b", m, 0);
  requireShape(normals, "normals", m, 3);
  const py::ssize_t n = points.ndim() == 2 ? points.shape(0) : -1;
  requireShape(points, "points", n, 3);
  std::vector<long> offsets(static_cast<std::size_t>(m) + 1);
  if (pointOffsets) {
    requireShape(*pointOffsets, "point_offsets", m + 1, 0);
    for (py::ssize_t k = 0; k <= m; ++k) offsets[k] = pointOffsets->at(k);
    for (py::ssize_t k = 0; k < m; ++k)
      if (offsets[k + 1] <= offsets[k])
        throw std::invalid_argument(fmt::format("point_offsets: contact {} has no points", k));
    if (offsets[0] != 0 || offsets[m] != n)
      throw std::invalid_argument(fmt::format("point_offsets: must run from 0 to the {} points", n));
  } else {
    if (n != m)
      throw std::invalid_argument(
          fmt::format("points: one point per contact without point_offsets (got {} points, {} contacts)", n, m));
    for (py::ssize_t k = 0; k <= m; ++k) offsets[k] = k;
  }
  if (pointForces) requireShape(*pointForces, "point_forces", n, 0);
  if (pointGaps) requireShape(*pointGaps, "point_gaps", n, 0);
  if (pointTangentForces) requireShape(*pointTangentForces, "point_tangent_forces", n, 3);
  const std::vector<std::string> typeNames =
      types.is_none() ? std::vector<std::string>(static_cast<std::size_t>(m), "simple") : strings(types, m, "types");
  PyContacts out;
  out.contacts.resize(static_cast<std::size_t>(m));
  for (py::ssize_t k = 0; k < m; ++k) {
    core::Contact& c = out.contacts[k];
    c.a = static_cast<int>(a.at(k));
    c.b = static_cast<int>(b.at(k));
    c.type = core::contactTypeFromString(typeNames[k]);
    c.normal = core::Vec3(normals.at(k, 0), normals.at(k, 1), normals.at(k, 2));
    for (long p = offsets[k]; p < offsets[k + 1]; ++p) {
      core::ContactPoint cp;
      cp.position = core::Vec3(points.at(p, 0), points.at(p, 1), points.at(p, 2));
      if (pointForces) cp.normalForce = pointForces->at(p);
      if (pointGaps) cp.gap = pointGaps->at(p);
      if (pointTangentForces)
        cp.tangentForce =
            core::Vec3(pointTangentForces->at(p, 0), pointTangentForces->at(p, 1), pointTangentForces->at(p, 2));
      c.points.push_back(cp);
    }
  }
  return out;
}

PyPacking makePacking(const core::BoxDef& box, const Doubles& positions, const Doubles& sizes,
                      const std::optional<Doubles>& orientations, const py::object& shapes,
                      const std::optional<Doubles>& pinacoidParams, const std::optional<PyContacts>& contacts,
                      double wallFriction) {
  const py::ssize_t n = positions.ndim() == 2 ? positions.shape(0) : -1;
  requireShape(positions, "positions", n, 3);
  requireShape(sizes, "sizes", n, 0);
  if (orientations) requireShape(*orientations, "orientations", n, 4);
  if (pinacoidParams) requireShape(*pinacoidParams, "pinacoid_params", n, 3);
  const std::vector<std::string> shapeNames =
      shapes.is_none() ? std::vector<std::string>(static_cast<std::size_t>(n), "sphere") : strings(shapes, n, "shapes");
  PyPacking out;
  out.packing.box = box;
  out.packing.walls.friction = wallFriction;
  out.packing.grains.resize(static_cast<std::size_t>(n));
  for (py::ssize_t i = 0; i < n; ++i) {
    core::Grain& g = out.packing.grains[i];
    g.shape = core::shapeFromString(shapeNames[i]);
    g.size = sizes.at(i);
    g.position = core::Vec3(positions.at(i, 0), positions.at(i, 1), positions.at(i, 2));
    if (orientations) {
      // Taken as given: validatePacking refuses one that is not unit, as the writer does.
      g.orientation =
          core::Quat(orientations->at(i, 0), orientations->at(i, 1), orientations->at(i, 2), orientations->at(i, 3));
    }
    if (pinacoidParams && g.shape == core::ShapeKind::Pinacoid)
      g.params = {pinacoidParams->at(i, 0), pinacoidParams->at(i, 1), pinacoidParams->at(i, 2)};
  }
  if (contacts) out.packing.contacts = contacts->contacts;
  core::validatePacking(out.packing, "packing");
  return out;
}

}  // namespace

void bindPacking(py::module_& m) {
  py::class_<core::BoxDef>(m, "Box", "The simulation box (docs/model.md, \"Box\"); lengths in d_L.")
      .def(py::init([](double lengthX, double width, bool periodicY, double height) {
             core::BoxDef b{lengthX, width, periodicY, height};
             b.validate();
             return b;
           }),
           "length_x"_a = core::BoxDef{}.lengthX, "width"_a = core::BoxDef{}.width, "periodic_y"_a = false,
           "height"_a = core::BoxDef{}.height)
      .def_readonly("length_x", &core::BoxDef::lengthX)
      .def_readonly("width", &core::BoxDef::width)
      .def_readonly("periodic_y", &core::BoxDef::periodicY)
      .def_readonly("height", &core::BoxDef::height)
      .def("__repr__", [](const core::BoxDef& b) {
        return fmt::format("Box(length_x={}, width={}, periodic_y={}, height={})", b.lengthX, b.width,
                           b.periodicY ? "True" : "False", b.height);
      });

  py::class_<PyContacts>(m, "Contacts",
                         "Contacts with forces: per contact a, b (a grain, or a wall: -1 floor, -2 y = 0, -3 y = W), "
                         "type, normal; per point (point_offsets[k]:point_offsets[k+1] for contact k) position, "
                         "normal force, gap and friction force.")
      .def(py::init(&makeContacts), "a"_a, "b"_a, "normals"_a, "points"_a, "point_offsets"_a = py::none(),
           "types"_a = py::none(), "point_forces"_a = py::none(), "point_gaps"_a = py::none(),
           "point_tangent_forces"_a = py::none())
      .def("__len__", [](const PyContacts& c) { return c.contacts.size(); })
      .def_property_readonly("a", [](const PyContacts& c) { return c.ids(&core::Contact::a); })
      .def_property_readonly("b", [](const PyContacts& c) { return c.ids(&core::Contact::b); })
      .def_property_readonly("types",
                             [](const PyContacts& c) {
                               std::vector<std::string_view> v;
                               for (const auto& x : c.contacts) v.push_back(core::toString(x.type));
                               return stringArray(v);
                             })
      .def_property_readonly(
          "normals", [](const PyContacts& c) { return c.perContact([](const core::Contact& x) { return x.normal; }); })
      .def_property_readonly(
          "normal_forces",
          [](const PyContacts& c) { return c.perContact([](const core::Contact& x) { return x.normalForce(); }); })
      .def_property_readonly("tangent_forces",
                             [](const PyContacts& c) {
                               return c.perContact([](const core::Contact& x) {
                                 core::Vec3 t = core::Vec3::Zero();
                                 for (const auto& p : x.points) t += p.tangentForce;
                                 return t;
                               });
                             })
      .def_property_readonly("point_offsets",
                             [](const PyContacts& c) {
                               std::vector<long> v{0};
                               for (const auto& x : c.contacts)
                                 v.push_back(v.back() + static_cast<long>(x.points.size()));
                               return toArray(v);
                             })
      .def_property_readonly(
          "points",
          [](const PyContacts& c) { return c.perPoint([](const core::ContactPoint& p) { return p.position; }); })
      .def_property_readonly(
          "point_forces",
          [](const PyContacts& c) { return c.perPoint([](const core::ContactPoint& p) { return p.normalForce; }); })
      .def_property_readonly(
          "point_gaps",
          [](const PyContacts& c) { return c.perPoint([](const core::ContactPoint& p) { return p.gap; }); })
      .def_property_readonly("point_tangent_forces", [](const PyContacts& c) {
        return c.perPoint([](const core::ContactPoint& p) { return p.tangentForce; });
      });

  py::class_<PyPacking>(m, "Packing",
                        "A packing (docs/packing-format.md): the box, the grains as arrays and, optionally, "
                        "the contacts with forces. Immutable; positions and sizes are read-only views.")
      .def(py::init(&makePacking), "box"_a, "positions"_a, "sizes"_a, "orientations"_a = py::none(),
           "shapes"_a = py::none(), "pinacoid_params"_a = py::none(), "contacts"_a = py::none(),
           "wall_friction"_a = 0.0)
      .def("__len__", [](const PyPacking& p) { return p.packing.grains.size(); })
      .def_property_readonly("box", [](const PyPacking& p) { return p.packing.box; })
      .def_property_readonly(
          "wall_friction", [](const PyPacking& p) { return p.packing.walls.friction; },
          "Coulomb friction mu_w of the side walls the packing was made between")
      .def_property_readonly("source",
                             [](const PyPacking& p) -> py::object {
                               return p.source.empty() ? py::none() : py::object(py::str(p.source));
                             })
      .def_property_readonly("positions",
                             [](py::handle self) {
                               const auto& grains = self.cast<const PyPacking&>().packing.grains;
                               const auto n = static_cast<py::ssize_t>(grains.size());
                               return readOnlyView<double>(
                                   {n, 3}, {static_cast<py::ssize_t>(sizeof(core::Grain)), sizeof(double)},
                                   n ? grains[0].position.data() : nullptr, self);
                             })
      .def_property_readonly("sizes",
                             [](py::handle self) {
                               const auto& grains = self.cast<const PyPacking&>().packing.grains;
                               const auto n = static_cast<py::ssize_t>(grains.size());
                               return readOnlyView<double>({n}, {static_cast<py::ssize_t>(sizeof(core::Grain))},
                                                           n ? &grains[0].size : nullptr, self);
                             })
      .def_property_readonly("orientations",
                             [](const PyPacking& p) {
                               return grainRows<4>(p.packing.grains, [](const core::Grain& g, double* row) {
                                 const core::Quat& q = g.orientation;
                                 row[0] = q.w();
                                 row[1] = q.x();
                                 row[2] = q.y();
                                 row[3] = q.z();
                               });
                             })
      .def_property_readonly("shapes",
                             [](const PyPacking& p) {
                               std::vector<std::string_view> v;
                               for (const auto& g : p.packing.grains) v.push_back(core::toString(g.shape));
                               return stringArray(v);
                             })
      .def_property_readonly("pinacoid_params",
                             [](const PyPacking& p) {
                               // G / L, E / L, alpha_deg per grain; NaN for spheres, which have none.
                               return grainRows<3>(p.packing.grains, [](const core::Grain& g, double* row) {
                                 const bool pinacoid = g.shape == core::ShapeKind::Pinacoid;
                                 const double nan = std::numeric_limits<double>::quiet_NaN();
                                 row[0] = pinacoid ? g.params.widthRatio : nan;
                                 row[1] = pinacoid ? g.params.heightRatio : nan;
                                 row[2] = pinacoid ? g.params.alphaDeg : nan;
                               });
                             })
      .def_property_readonly("contacts",
                             [](const PyPacking& p) -> std::optional<PyContacts> {
                               if (!p.packing.contacts) return std::nullopt;
                               return PyContacts{*p.packing.contacts};
                             })
      .def(
          "write", [](const PyPacking& p, const std::filesystem::path& path) { core::writePacking(p.packing, path); },
          "path"_a, "Writes the packing file atomically (docs/packing-format.md); reading it back gives the same bits.")
      .def("__repr__", [](const PyPacking& p) {
        return fmt::format(
            "<confpack.Packing: {} grains, {}{}>", p.packing.grains.size(),
            p.packing.contacts ? fmt::format("{} contacts", p.packing.contacts->size()) : "no contact list",
            p.source.empty() ? "" : ", from " + p.source);
      });

  m.def(
      "read_packing",
      [](const std::filesystem::path& path) {
        return PyPacking{core::readPacking(path), path.string()};
      },
      "path"_a,
      "Reads and validates a packing file (docs/packing-format.md); a bad file raises ValueError naming the "
      "file, the element and the field.");
}

}  // namespace confpack::python
