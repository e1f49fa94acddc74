#include "core/vtk_writer.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "core/packing_io.hpp"

namespace confpack::core {

namespace {

using Buffer = fmt::memory_buffer;

void header(Buffer& b) {
  fmt::format_to(std::back_inserter(b),
                 "<?xml version=\"1.0\"?>\n"
                 "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                 "<PolyData>\n");
}

void footer(Buffer& b) {
  fmt::format_to(std::back_inserter(b), "</Piece>\n</PolyData>\n</VTKFile>\n");
}

template <class T>
void dataArray(Buffer& b, std::string_view type, std::string_view name, int components, const std::vector<T>& values) {
  fmt::format_to(std::back_inserter(b), "<DataArray type=\"{}\"", type);
  if (!name.empty()) fmt::format_to(std::back_inserter(b), " Name=\"{}\"", name);
  if (components != 1) fmt::format_to(std::back_inserter(b), " NumberOfComponents=\"{}\"", components);
  fmt::format_to(std::back_inserter(b), " format=\"ascii\">\n");
  // Six values a line keeps the files readable; "{}" is the shortest round-trip form of a double.
  for (std::size_t i = 0; i < values.size(); ++i)
    fmt::format_to(std::back_inserter(b), "{}{}", values[i], (i + 1) % 6 == 0 || i + 1 == values.size() ? "\n" : " ");
  fmt::format_to(std::back_inserter(b), "</DataArray>\n");
}

void pushVec(std::vector<double>& v, const Vec3& x) {
  v.push_back(x.x());
  v.push_back(x.y());
  v.push_back(x.z());
}

/// One cell block (Verts, Lines or Polys): connectivity and the running end offsets.
struct Cells {
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
  void add(std::span<const std::int64_t> ids) {
    connectivity.insert(connectivity.end(), ids.begin(), ids.end());
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  int count() const { return static_cast<int>(offsets.size()); }
  void write(Buffer& b, std::string_view tag) const {
    if (offsets.empty()) return;
    fmt::format_to(std::back_inserter(b), "<{}>\n", tag);
    dataArray(b, "Int64", "connectivity", 1, connectivity);
    dataArray(b, "Int64", "offsets", 1, offsets);
    fmt::format_to(std::back_inserter(b), "</{}>\n", tag);
  }
};

void writePvd(const std::filesystem::path& path, const auto& entries) {
  Buffer b;
  fmt::format_to(std::back_inserter(b),
                 "<?xml version=\"1.0\"?>\n"
                 "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n");
  for (const auto& e : entries)
    fmt::format_to(std::back_inserter(b), "<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", e.time,
                   e.file);
  fmt::format_to(std::back_inserter(b), "</Collection>\n</VTKFile>\n");
  writeFileAtomically(path, std::string_view(b.data(), b.size()));
}

}  // namespace

VtkFrameCounts writeGrainsVtp(const Packing& packing, const std::filesystem::path& path,
                              std::span<const Vec3> velocities) {
  const auto& grains = packing.grains;
  if (!velocities.empty() && velocities.size() != grains.size())
    throw std::invalid_argument(fmt::format("vtk: velocities must be empty or one per grain ({} grains, got {})",
                                            grains.size(), velocities.size()));
  std::vector<double> points, diameter, velocity;
  std::vector<std::int32_t> pointId, cellIdVerts, cellIdPolys;
  std::vector<double> cellSizeVerts, cellSizePolys;
  Cells verts, polys;
  auto addPoint = [&](const Vec3& x, std::size_t grain) {
    pushVec(points, x);
    diameter.push_back(grains[grain].size);
    pointId.push_back(static_cast<std::int32_t>(grain));
    if (!velocities.empty()) pushVec(velocity, velocities[grain]);
    return static_cast<std::int64_t>(pointId.size() - 1);
  };
  for (std::size_t i = 0; i < grains.size(); ++i) {
    const Grain& g = grains[i];
    if (g.shape == ShapeKind::Sphere) {
      const std::int64_t id = addPoint(g.position, i);
      verts.add(std::span(&id, 1));
      cellIdVerts.push_back(static_cast<std::int32_t>(i));
      cellSizeVerts.push_back(g.size);
    } else {
      const ConvexPolyhedron poly = g.polyhedron();
      const Mat3 r = g.orientation.toRotationMatrix();
      const std::int64_t first = static_cast<std::int64_t>(pointId.size());
      for (const Vec3& v : poly.vertices()) addPoint(g.position + r * v, i);
      for (const auto& face : poly.faces()) {
        std::vector<std::int64_t> ids;
        for (int v : face) ids.push_back(first + v);
        polys.add(ids);
        cellIdPolys.push_back(static_cast<std::int32_t>(i));
        cellSizePolys.push_back(g.size);
      }
    }
  }
  // Cell data runs over Verts first, then Polys (the order VTK numbers PolyData cells in).
  std::vector<std::int32_t> cellId = cellIdVerts;
  cellId.insert(cellId.end(), cellIdPolys.begin(), cellIdPolys.end());
  std::vector<double> cellSize = cellSizeVerts;
  cellSize.insert(cellSize.end(), cellSizePolys.begin(), cellSizePolys.end());

  VtkFrameCounts counts;
  counts.grainPoints = static_cast<int>(pointId.size());
  counts.verts = verts.count();
  counts.polys = polys.count();

  Buffer b;
  header(b);
  fmt::format_to(std::back_inserter(b),
                 "<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
                 "NumberOfPolys=\"{}\">\n",
                 counts.grainPoints, counts.verts, counts.polys);
  fmt::format_to(std::back_inserter(b), "<PointData Scalars=\"diameter\">\n");
  dataArray(b, "Float64", "diameter", 1, diameter);
  dataArray(b, "Int32", "id", 1, pointId);
  if (!velocities.empty()) dataArray(b, "Float64", "velocity", 3, velocity);
  fmt::format_to(std::back_inserter(b), "</PointData>\n<CellData Scalars=\"id\">\n");
  dataArray(b, "Int32", "id", 1, cellId);
  dataArray(b, "Float64", "diameter", 1, cellSize);
  fmt::format_to(std::back_inserter(b), "</CellData>\n<Points>\n");
  dataArray(b, "Float64", "", 3, points);
  fmt::format_to(std::back_inserter(b), "</Points>\n");
  verts.write(b, "Verts");
  polys.write(b, "Polys");
  footer(b);
  writeFileAtomically(path, std::string_view(b.data(), b.size()));
  return counts;
}

int writeContactsVtp(const Packing& packing, const std::filesystem::path& path) {
  std::vector<double> points, normalForce, normal;
  std::vector<std::int32_t> type, wall;
  Cells lines;
  if (packing.contacts) {
    for (const Contact& c : *packing.contacts) {
      if (c.a < 0 || c.a >= static_cast<int>(packing.grains.size()) || c.b >= static_cast<int>(packing.grains.size()))
        throw std::invalid_argument(fmt::format("vtk: contact ({}, {}) refers to a missing grain", c.a, c.b));
      const Vec3 xa = packing.grains[c.a].position;
      Vec3 end;
      if (isWall(c.b)) {
        // Mean contact point, taken as the periodic image nearest to a (points live near a's
        // unwrapped position, see core/contact.hpp).
        Vec3 mean = Vec3::Zero();
        for (const auto& p : c.points) mean += p.position;
        end = c.points.empty() ? xa : Vec3(xa + packing.box.minimumImage(mean / c.points.size() - xa));
      } else {
        // Centre to centre through the nearest image, so a pair across the period is a short line.
        end = xa + packing.box.minimumImage(packing.grains[c.b].position - xa);
      }
      const auto first = static_cast<std::int64_t>(points.size() / 3);
      pushVec(points, xa);
      pushVec(points, end);
      const std::int64_t ids[2] = {first, first + 1};
      lines.add(ids);
      normalForce.push_back(c.normalForce());
      type.push_back(static_cast<std::int32_t>(c.type));
      wall.push_back(isWall(c.b) ? 1 : 0);
      pushVec(normal, c.normal);
    }
  }
  Buffer b;
  header(b);
  fmt::format_to(std::back_inserter(b),
                 "<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" "
                 "NumberOfPolys=\"0\">\n",
                 points.size() / 3, lines.count());
  fmt::format_to(std::back_inserter(b), "<CellData Scalars=\"normal_force\">\n");
  dataArray(b, "Float64", "normal_force", 1, normalForce);
  dataArray(b, "Int32", "type", 1, type);
  dataArray(b, "Int32", "wall", 1, wall);
  dataArray(b, "Float64", "normal", 3, normal);
  fmt::format_to(std::back_inserter(b), "</CellData>\n<Points>\n");
  dataArray(b, "Float64", "", 3, points);
  fmt::format_to(std::back_inserter(b), "</Points>\n");
  lines.write(b, "Lines");
  footer(b);
  writeFileAtomically(path, std::string_view(b.data(), b.size()));
  return lines.count();
}

VtkSeries::VtkSeries(std::filesystem::path directory, std::string basename)
    : directory_(std::move(directory)), basename_(std::move(basename)) {
  std::filesystem::create_directories(directory_);
}

VtkFrameCounts VtkSeries::addFrame(double time, const Packing& packing, std::span<const Vec3> velocities) {
  const int k = frameCount();
  const std::string grainsFile = fmt::format("{}_grains_{:06d}.vtp", basename_, k);
  VtkFrameCounts counts = writeGrainsVtp(packing, directory_ / grainsFile, velocities);
  grainFrames_.push_back({time, grainsFile});
  if (packing.contacts) {
    const std::string contactsFile = fmt::format("{}_contacts_{:06d}.vtp", basename_, k);
    counts.lines = writeContactsVtp(packing, directory_ / contactsFile);
    contactFrames_.push_back({time, contactsFile});
  }
  finish();
  return counts;
}

void VtkSeries::finish() {
  writePvd(grainsCollection(), grainFrames_);
  if (!contactFrames_.empty()) writePvd(contactsCollection(), contactFrames_);
}

}  // namespace confpack::core
