#include "collision/separating_axis.hpp"

namespace confpack::collision {

// Gauss-map test (Gregorius, "The Separating Axis Test between Convex Polyhedra", GDC 2013):
// edges of A (adjacent face normals a, b) and of B (c, d) build a face of the Minkowski
// difference A - B iff the arcs a-b and (-c)-(-d) cross on the unit sphere. Only those edge
// pairs can carry the minimum-penetration axis, and for them the supports along the axis are
// the edges themselves, so sep costs one dot product. With the arc normals b x a and d x c
// precomputed per edge, the test is 4 dot products:
//   c.(b x a) * d.(b x a) < 0,  a.(d x c) * b.(d x c) < 0,  c.(b x a) * b.(d x c) > 0.

// Returns the best axis; stops early (with sep > stopAbove) once an axis proves separation
// beyond stopAbove.
SatResult separatingAxis(const WorldPolyhedron& A, const WorldPolyhedron& B, double stopAbove) {
  SatResult best;
  const double tieTol = kRelativeLengthTol * (A.radius + B.radius);
  for (std::size_t f = 0; f < A.n.size(); ++f) {
    const double s = B.minAlong(A.n[f]) - A.off[f];
    if (s > best.sep) best = {s, A.n[f]};
    if (s > stopAbove) return best;
  }
  for (std::size_t f = 0; f < B.n.size(); ++f) {
    const double s = A.minAlong(B.n[f]) - B.off[f];
    // Face of B: axis from a towards b is -n_B. Ties keep A's face (deterministic).
    if (s > best.sep + tieTol) best = {s, -B.n[f]};
    if (s > stopAbove) return best;
  }
  const auto& eA = A.shape->edges();
  const auto& eB = B.shape->edges();
  for (std::size_t i = 0; i < eA.size(); ++i) {
    const Vec3& pa = A.v[eA[i][0]];
    const Vec3 da = A.v[eA[i][1]] - pa;
    const Vec3& na0 = A.n[A.edgeFaces[i][0]];
    const Vec3& na1 = A.n[A.edgeFaces[i][1]];
    const Vec3& bxa = A.edgeArc[i];
    for (std::size_t j = 0; j < eB.size(); ++j) {
      // isMinkowskiFace(na0, na1, -nb0, -nb1) with the arc normals precomputed:
      // (-nb1) x (-nb0) = nb1 x nb0 = B.edgeArc[j].
      const Vec3& nb0 = B.n[B.edgeFaces[j][0]];
      const Vec3& nb1 = B.n[B.edgeFaces[j][1]];
      const Vec3& dxc = B.edgeArc[j];
      const double cba = -nb0.dot(bxa), dba = -nb1.dot(bxa), adc = na0.dot(dxc), bdc = na1.dot(dxc);
      if (!(cba * dba < 0.0 && adc * bdc < 0.0 && cba * bdc > 0.0)) continue;
      const Vec3& pb = B.v[eB[j][0]];
      const Vec3 db = B.v[eB[j][1]] - pb;
      Vec3 u = da.cross(db);
      const double len = u.norm();
      if (len <= kParallelEdgeSin * da.norm() * db.norm()) continue;
      u /= len;
      if (u.dot(pa - A.centre) < 0.0) u = -u;  // outward from A at its edge
      const double s = u.dot(pb - pa);
      // Edge axes must beat the face axes clearly: an edge pair lying in a face gives the face
      // normal again, and the face reading is the one that classifies the contact correctly.
      if (s > best.sep + tieTol) best = {s, u};
      if (s > stopAbove) return best;
    }
  }
  return best;
}

}  // namespace confpack::collision
