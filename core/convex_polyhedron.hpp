#pragma once
// A convex polyhedron in its body frame: vertices, faces (vertex loops counter-clockwise seen
// from outside), outward face planes, edges. Mass properties come from the divergence theorem
// (signed tetrahedra from the origin), so they hold for any convex shape, not only pinacoids.
#include <array>
#include <vector>

#include "core/types.hpp"

namespace confpack::core {

struct MassProperties {
  double volume = 0.0;               ///< [d_L^3]
  Vec3 centroid = Vec3::Zero();      ///< body frame [d_L]
  Mat3 secondMoment = Mat3::Zero();  ///< int (x-c)(x-c)^T dV about the centroid [d_L^5]
  /// Inertia tensor about the centroid for density rho: rho (tr(S) I - S).
  Mat3 inertia(double density = 1.0) const {
    return density * (secondMoment.trace() * Mat3::Identity() - secondMoment);
  }
};

class ConvexPolyhedron {
 public:
  ConvexPolyhedron() = default;
  /// Builds from vertices and faces (each face a CCW loop seen from outside). Computes face
  /// planes and the unique edge list; throws std::invalid_argument if a face is degenerate or
  /// the face planes do not contain all vertices on their inner side (not convex).
  ConvexPolyhedron(std::vector<Vec3> vertices, std::vector<std::vector<int>> faces);

  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<std::vector<int>>& faces() const { return faces_; }
  const std::vector<Vec3>& faceNormals() const { return normals_; }    ///< outward unit normals
  const std::vector<double>& faceOffsets() const { return offsets_; }  ///< n.x = offset on face
  const std::vector<std::array<int, 2>>& edges() const { return edges_; }

  /// Index of the vertex farthest along dir (the support point).
  int supportIndex(const Vec3& dir) const;
  Vec3 support(const Vec3& dir) const { return vertices_[supportIndex(dir)]; }
  /// Largest vertex distance from the origin of the body frame.
  double boundingRadius() const { return boundingRadius_; }
  /// Mass properties by the divergence theorem (exact for a polyhedron).
  MassProperties massProperties() const;
  /// True if p (body frame) is inside or on the surface, within tol.
  bool contains(const Vec3& p, double tol = 0.0) const;
  /// A copy scaled by s about the body origin.
  ConvexPolyhedron scaled(double s) const;

 private:
  std::vector<Vec3> vertices_;
  std::vector<std::vector<int>> faces_;
  std::vector<Vec3> normals_;
  std::vector<double> offsets_;
  std::vector<std::array<int, 2>> edges_;
  double boundingRadius_ = 0.0;
};

}  // namespace confpack::core
