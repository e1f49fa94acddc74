#pragma once
// Separating-axis test between two convex polyhedra (step 1 of collidePolyhedra).
//
// For a unit axis u from A towards B, the support separation
//     sep(u) = min_{x in B} u.x - max_{x in A} u.x   [d_L]
// is a lower bound of the distance of A and B. Over the face normals of both bodies and the cross
// products of their edge pairs, the largest sep is exactly minus the penetration depth (the
// minimum translation distance) when A and B overlap; when they are disjoint it is only a lower
// bound (vertex-vertex, vertex-edge and non-crossing edge-edge closest pairs lie on no such
// axis; polyhedron_distance then computes the exact distance). Face axes win ties against edge
// axes, since an edge pair lying in a face gives that face's normal again and the face reading is
// the one that classifies the contact. Edge pairs whose cross product is shorter than
// kParallelEdgeSin (relative) give no axis: the face axes cover parallel edges.
#include "collision/world_polyhedron.hpp"

namespace confpack::collision {

struct SatResult {
  double sep = -kInf;         ///< largest separation over the axes [d_L]
  Vec3 axis = Vec3::UnitZ();  ///< unit, from a towards b
};

/// The axis of largest support separation of A and B; stops early (with sep > stopAbove) once an
/// axis proves separation beyond stopAbove [d_L].
SatResult separatingAxis(const WorldPolyhedron& A, const WorldPolyhedron& B, double stopAbove);

}  // namespace confpack::collision
